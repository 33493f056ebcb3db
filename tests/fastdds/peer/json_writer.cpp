// SPDX-License-Identifier: BSD-3-Clause
// JsonObject: members appended to one string; strings escaped as RFC 8259 requires.
#include "tests/fastdds/peer/json_writer.hpp"

#include <cmath>
#include <cstdio>

namespace raymap::fastdds_peer {

std::string jsonString(std::string_view value) {
  std::string out = "\"";
  for (const char c : value) {
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
          char escaped[8];
          std::snprintf(escaped, sizeof(escaped), "\\u%04x", static_cast<unsigned>(c));
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

void JsonObject::key(std::string_view name) {
  if (!body_.empty()) {
    body_ += ", ";
  }
  body_ += jsonString(name) + ": ";
}

JsonObject& JsonObject::number(std::string_view name, double value) {
  key(name);
  if (!std::isfinite(value)) {
    body_ += "null";
    return *this;
  }
  char formatted[32];
  std::snprintf(formatted, sizeof(formatted), "%.6g", value);
  body_ += formatted;
  return *this;
}

JsonObject& JsonObject::integer(std::string_view name, std::int64_t value) {
  key(name);
  body_ += std::to_string(value);
  return *this;
}

JsonObject& JsonObject::text(std::string_view name, std::string_view value) {
  key(name);
  body_ += jsonString(value);
  return *this;
}

JsonObject& JsonObject::texts(std::string_view name, const std::vector<std::string>& values) {
  key(name);
  body_ += "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    body_ += (i == 0 ? "" : ", ") + jsonString(values[i]);
  }
  body_ += "]";
  return *this;
}

JsonObject& JsonObject::integers(std::string_view name, const std::vector<std::int64_t>& values) {
  key(name);
  body_ += "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    body_ += (i == 0 ? "" : ", ") + std::to_string(values[i]);
  }
  body_ += "]";
  return *this;
}

JsonObject& JsonObject::object(std::string_view name, const JsonObject& value) {
  key(name);
  body_ += value.str();
  return *this;
}

std::string JsonObject::str() const { return "{" + body_ + "}"; }

}  // namespace raymap::fastdds_peer
