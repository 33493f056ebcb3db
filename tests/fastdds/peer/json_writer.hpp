// SPDX-License-Identifier: BSD-3-Clause
// A JSON object written member by member: what the peer prints when it ends.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace raymap::fastdds_peer {

/// @brief One JSON object, members in the order added. Non-finite numbers are written as null.
class JsonObject {
 public:
  JsonObject& number(std::string_view key, double value);
  JsonObject& integer(std::string_view key, std::int64_t value);
  JsonObject& text(std::string_view key, std::string_view value);
  JsonObject& texts(std::string_view key, const std::vector<std::string>& values);
  JsonObject& integers(std::string_view key, const std::vector<std::int64_t>& values);
  JsonObject& object(std::string_view key, const JsonObject& value);
  /// @brief The object on one line: {"key": value, ...}.
  std::string str() const;

 private:
  void key(std::string_view name);
  std::string body_;
};

/// @brief `value` as a JSON string literal, quotes included.
std::string jsonString(std::string_view value);

}  // namespace raymap::fastdds_peer
