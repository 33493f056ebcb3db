// SPDX-License-Identifier: BSD-3-Clause
// Reading the JSON the tools print, in tests: nlohmann's parser, with text that is not JSON a test
// failure that shows the text.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace raymap::test {

/// A parsed document; object members keep the order they were written in, so a test can check
/// the documented order too.
using Json = nlohmann::ordered_json;

/// @brief Parses `text` as exactly one JSON value (RFC 8259; white space around it allowed).
/// Text that is not JSON adds a test failure naming the parser's complaint and the text, and
/// gives nullopt (a caller that needs the value asserts it and stops there).
std::optional<Json> parseJson(std::string_view text);

/// @brief The value at a path of object member names ({"last_map", "resolution"}), or nullptr
/// when a member is missing or a step is not an object.
const Json* findPath(const Json& json, const std::vector<std::string>& path);

/// @brief The first value of a member named `key` anywhere in `json`, in document order (depth
/// first: a nested object's members come before the members after it), or nullptr.
const Json* findFirst(const Json& json, std::string_view key);

}  // namespace raymap::test
