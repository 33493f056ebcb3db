// SPDX-License-Identifier: BSD-3-Clause
// JSON object writer.
#include "tools/raymap/json_writer.hpp"

#include <cmath>
#include <cstdio>

namespace raymap::cli {

std::string jsonQuote(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", static_cast<unsigned>(c));
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  out += '"';
  return out;
}

void JsonObject::key(std::string_view k) {
  if (style_ == JsonStyle::kCompact) {
    body_ += empty_ ? "" : ",";
  } else {
    body_ += empty_ ? "\n  " : ",\n  ";
  }
  empty_ = false;
  body_ += jsonQuote(k);
  body_ += style_ == JsonStyle::kCompact ? ":" : ": ";
}

JsonObject& JsonObject::add(std::string_view k, std::string_view value) {
  key(k);
  body_ += jsonQuote(value);
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, double value) {
  key(k);
  if (!std::isfinite(value)) {
    body_ += "null";  // JSON has no NaN or infinity
    return *this;
  }
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  body_ += buffer;
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, std::uint64_t value) {
  key(k);
  body_ += std::to_string(value);
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, std::int64_t value) {
  key(k);
  body_ += std::to_string(value);
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, bool value) {
  key(k);
  body_ += value ? "true" : "false";
  return *this;
}

JsonObject& JsonObject::raw(std::string_view k, std::string_view json) {
  key(k);
  if (style_ == JsonStyle::kCompact) {
    body_ += json;
    return *this;
  }
  // Indent nested lines one level further.
  for (const char c : json) {
    body_ += c;
    if (c == '\n') {
      body_ += "  ";
    }
  }
  return *this;
}

std::string JsonObject::str() const {
  if (style_ == JsonStyle::kCompact) {
    return "{" + body_ + "}";
  }
  return "{" + body_ + (empty_ ? "}" : "\n}");
}

std::string jsonList(const std::vector<std::string>& items) {
  std::string list = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    list += (i == 0 ? "" : ", ") + jsonQuote(items[i]);
  }
  return list + "]";
}

}  // namespace raymap::cli
