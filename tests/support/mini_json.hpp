// SPDX-License-Identifier: BSD-3-Clause
// A small strict JSON parser for tests that check the machine-readable output of the tools.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raymap::test {

/// @brief A parsed JSON value. Objects keep the last value of a repeated key.
/// Thread-safety: a value type; const access from any thread.
struct JsonValue {
  enum class Kind { kNull, kBool, kNumber, kString, kArray, kObject };
  Kind kind = Kind::kNull;
  bool boolean = false;
  double number = 0.0;
  std::string text;
  std::vector<JsonValue> items;
  std::map<std::string, JsonValue> members;

  bool isNull() const { return kind == Kind::kNull; }
  /// @brief The member `key` of an object, or nullptr (also when this is not an object).
  const JsonValue* find(const std::string& key) const;
};

/// @brief Parses exactly one JSON value (RFC 8259; surrounding whitespace allowed).
/// @return the value, or nullopt with `*error` saying where and why
std::optional<JsonValue> parseJson(std::string_view text, std::string* error = nullptr);

}  // namespace raymap::test
