// SPDX-License-Identifier: BSD-3-Clause
// Recursive-descent JSON parser (strict: no trailing commas, no NaN, no comments).
#include "tests/support/mini_json.hpp"

#include <cstdlib>

namespace raymap::test {
namespace {

class Parser {
 public:
  explicit Parser(std::string_view text) : text_(text) {}

  std::optional<JsonValue> document(std::string* error) {
    JsonValue value;
    skipSpace();
    if (!parseValue(value, 0)) {
      report(error);
      return std::nullopt;
    }
    skipSpace();
    if (at_ != text_.size()) {
      why_ = "text after the value";
      report(error);
      return std::nullopt;
    }
    return value;
  }

 private:
  static constexpr int kMaxDepth = 64;

  void report(std::string* error) const {
    if (error != nullptr) {
      *error = why_ + " at offset " + std::to_string(at_);
    }
  }
  bool failWith(const char* why) {
    if (why_.empty()) {
      why_ = why;
    }
    return false;
  }
  void skipSpace() {
    while (at_ < text_.size() &&
           (text_[at_] == ' ' || text_[at_] == '\t' || text_[at_] == '\n' || text_[at_] == '\r')) {
      ++at_;
    }
  }
  bool literal(std::string_view word) {
    if (text_.substr(at_, word.size()) != word) {
      return failWith("bad literal");
    }
    at_ += word.size();
    return true;
  }

  bool parseValue(JsonValue& out, int depth) {
    if (depth > kMaxDepth) {
      return failWith("nested too deeply");
    }
    if (at_ >= text_.size()) {
      return failWith("unexpected end");
    }
    switch (text_[at_]) {
      case 'n':
        out.kind = JsonValue::Kind::kNull;
        return literal("null");
      case 't':
        out.kind = JsonValue::Kind::kBool;
        out.boolean = true;
        return literal("true");
      case 'f':
        out.kind = JsonValue::Kind::kBool;
        out.boolean = false;
        return literal("false");
      case '"':
        out.kind = JsonValue::Kind::kString;
        return parseString(out.text);
      case '[':
        out.kind = JsonValue::Kind::kArray;
        return parseArray(out, depth);
      case '{':
        out.kind = JsonValue::Kind::kObject;
        return parseObject(out, depth);
      default:
        out.kind = JsonValue::Kind::kNumber;
        return parseNumber(out.number);
    }
  }

  bool parseNumber(double& out) {
    const std::size_t start = at_;
    const auto digits = [this] {
      const std::size_t from = at_;
      while (at_ < text_.size() && text_[at_] >= '0' && text_[at_] <= '9') {
        ++at_;
      }
      return at_ > from;
    };
    if (at_ < text_.size() && text_[at_] == '-') {
      ++at_;
    }
    if (at_ < text_.size() && text_[at_] == '0') {
      ++at_;
    } else if (!digits()) {
      return failWith("bad number");
    }
    if (at_ < text_.size() && text_[at_] == '.') {
      ++at_;
      if (!digits()) {
        return failWith("bad fraction");
      }
    }
    if (at_ < text_.size() && (text_[at_] == 'e' || text_[at_] == 'E')) {
      ++at_;
      if (at_ < text_.size() && (text_[at_] == '+' || text_[at_] == '-')) {
        ++at_;
      }
      if (!digits()) {
        return failWith("bad exponent");
      }
    }
    const std::string number(text_.substr(start, at_ - start));
    out = std::strtod(number.c_str(), nullptr);
    return true;
  }

  static void appendUtf8(std::string& out, unsigned code) {
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (code >> 18));
      out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
  }

  bool hex4(unsigned& out) {
    if (at_ + 4 > text_.size()) {
      return failWith("short \\u escape");
    }
    out = 0;
    for (int i = 0; i < 4; ++i) {
      const char c = text_[at_++];
      out <<= 4;
      if (c >= '0' && c <= '9') {
        out |= static_cast<unsigned>(c - '0');
      } else if (c >= 'a' && c <= 'f') {
        out |= static_cast<unsigned>(c - 'a' + 10);
      } else if (c >= 'A' && c <= 'F') {
        out |= static_cast<unsigned>(c - 'A' + 10);
      } else {
        return failWith("bad \\u escape");
      }
    }
    return true;
  }

  bool parseString(std::string& out) {
    ++at_;  // opening quote
    while (at_ < text_.size()) {
      const char c = text_[at_++];
      if (c == '"') {
        return true;
      }
      if (static_cast<unsigned char>(c) < 0x20) {
        return failWith("control character in a string");
      }
      if (c != '\\') {
        out += c;
        continue;
      }
      if (at_ >= text_.size()) {
        break;
      }
      const char e = text_[at_++];
      switch (e) {
        case '"':
        case '\\':
        case '/':
          out += e;
          break;
        case 'b':
          out += '\b';
          break;
        case 'f':
          out += '\f';
          break;
        case 'n':
          out += '\n';
          break;
        case 'r':
          out += '\r';
          break;
        case 't':
          out += '\t';
          break;
        case 'u': {
          unsigned code = 0;
          if (!hex4(code)) {
            return false;
          }
          if (code >= 0xD800 && code < 0xDC00 && text_.substr(at_, 2) == "\\u") {
            at_ += 2;
            unsigned low = 0;
            if (!hex4(low)) {
              return false;
            }
            code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
          }
          appendUtf8(out, code);
          break;
        }
        default:
          return failWith("bad escape");
      }
    }
    return failWith("unterminated string");
  }

  bool parseArray(JsonValue& out, int depth) {
    ++at_;
    skipSpace();
    if (at_ < text_.size() && text_[at_] == ']') {
      ++at_;
      return true;
    }
    for (;;) {
      skipSpace();
      JsonValue item;
      if (!parseValue(item, depth + 1)) {
        return false;
      }
      out.items.push_back(std::move(item));
      skipSpace();
      if (at_ < text_.size() && text_[at_] == ',') {
        ++at_;
        continue;
      }
      if (at_ < text_.size() && text_[at_] == ']') {
        ++at_;
        return true;
      }
      return failWith("expected , or ]");
    }
  }

  bool parseObject(JsonValue& out, int depth) {
    ++at_;
    skipSpace();
    if (at_ < text_.size() && text_[at_] == '}') {
      ++at_;
      return true;
    }
    for (;;) {
      skipSpace();
      if (at_ >= text_.size() || text_[at_] != '"') {
        return failWith("expected a key");
      }
      std::string key;
      if (!parseString(key)) {
        return false;
      }
      skipSpace();
      if (at_ >= text_.size() || text_[at_] != ':') {
        return failWith("expected :");
      }
      ++at_;
      skipSpace();
      JsonValue value;
      if (!parseValue(value, depth + 1)) {
        return false;
      }
      out.members[key] = std::move(value);
      skipSpace();
      if (at_ < text_.size() && text_[at_] == ',') {
        ++at_;
        continue;
      }
      if (at_ < text_.size() && text_[at_] == '}') {
        ++at_;
        return true;
      }
      return failWith("expected , or }");
    }
  }

  std::string_view text_;
  std::size_t at_ = 0;
  std::string why_;
};

}  // namespace

const JsonValue* JsonValue::find(const std::string& key) const {
  if (kind != Kind::kObject) {
    return nullptr;
  }
  const auto it = members.find(key);
  return it == members.end() ? nullptr : &it->second;
}

std::optional<JsonValue> parseJson(std::string_view text, std::string* error) {
  return Parser(text).document(error);
}

}  // namespace raymap::test
