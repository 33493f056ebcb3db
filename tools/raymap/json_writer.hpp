// SPDX-License-Identifier: BSD-3-Clause
// A minimal JSON object writer for the machine-readable outputs of the command line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace raymap::cli {

/// @brief Builds one JSON object, key by key, in insertion order. Nested objects are added as
/// already-rendered JSON text with raw(). Not thread-safe.
class JsonObject {
 public:
  JsonObject& add(std::string_view key, std::string_view value);
  JsonObject& add(std::string_view key, const char* value) {
    return add(key, std::string_view(value));
  }
  JsonObject& add(std::string_view key, double value);
  JsonObject& add(std::string_view key, std::uint64_t value);
  JsonObject& add(std::string_view key, std::int64_t value);
  JsonObject& add(std::string_view key, int value) { return add(key, std::int64_t{value}); }
  JsonObject& add(std::string_view key, unsigned value) { return add(key, std::uint64_t{value}); }
  JsonObject& add(std::string_view key, bool value);
  /// @brief Adds pre-rendered JSON (an object or array) under `key`.
  JsonObject& raw(std::string_view key, std::string_view json);
  /// @brief The object, pretty-printed with two-space indentation.
  std::string str() const;

 private:
  void key(std::string_view key);
  std::string body_;
  bool empty_ = true;
};

/// @brief Quotes and escapes a string for JSON.
std::string jsonQuote(std::string_view text);

}  // namespace raymap::cli
