// SPDX-License-Identifier: BSD-3-Clause
// The machine-readable outputs of the command line: nlohmann::ordered_json documents and the two
// layouts they are printed in.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace raymap::cli {

/// A JSON document whose object keys keep the order they were set in: the order docs/cli.md
/// lists them in, which scripts and readers of the output rely on.
using Json = nlohmann::ordered_json;

/// How dumpJson() lays a document out.
enum class JsonStyle : std::uint8_t {
  kPretty,   ///< two-space indentation, one member or element per line (documents, summaries)
  kCompact,  ///< one line, no spaces (JSON Lines streams: one object per line)
};

/// @brief `json` as text in `style`, without a final newline. Non-finite numbers are written as
/// null (JSON has neither NaN nor infinity). Bytes that are not UTF-8 (paths, names read from files
/// or the wire) become U+FFFD instead of failing the command, as nlohmann's default would.
inline std::string dumpJson(const Json& json, JsonStyle style = JsonStyle::kPretty) {
  return json.dump(style == JsonStyle::kPretty ? 2 : -1, ' ', false,
                   Json::error_handler_t::replace);
}

}  // namespace raymap::cli
