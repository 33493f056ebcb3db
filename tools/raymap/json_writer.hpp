// SPDX-License-Identifier: BSD-3-Clause
// A minimal JSON object writer for the machine-readable outputs of the command line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace raymap::cli {

/// How JsonObject::str() lays the object out.
enum class JsonStyle : std::uint8_t {
  kPretty,   ///< one key per line, two-space indentation (documents, `--json` summaries)
  kCompact,  ///< one line, no spaces (JSON Lines streams: one object per line)
};

/// @brief Builds one JSON object, key by key, in insertion order. Nested objects are added as
/// already-rendered JSON text with raw(). Not thread-safe.
class JsonObject {
 public:
  explicit JsonObject(JsonStyle style = JsonStyle::kPretty) : style_(style) {}

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
  /// @brief The object, in the style it was made with (compact: no newline anywhere, provided
  /// the raw() parts have none).
  std::string str() const;

 private:
  void key(std::string_view key);
  std::string body_;
  bool empty_ = true;
  JsonStyle style_ = JsonStyle::kPretty;
};

/// @brief Quotes and escapes a string for JSON.
std::string jsonQuote(std::string_view text);
/// @brief A JSON array of the strings, quoted: ["a", "b"].
std::string jsonList(const std::vector<std::string>& items);

}  // namespace raymap::cli
