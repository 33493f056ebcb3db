// SPDX-License-Identifier: BSD-3-Clause
// The library's messages name options by configuration key ("heightmap.size: 500",
// "backend.fallback: cpu"); the command line shows them as the flags its user typed ("--size 500",
// "--fallback cpu"). docs/architecture.md, "Messages name configuration keys".
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace raymap::cli {

/// @brief One row of the table: a configuration key, or a key with one value ("map.tiers: false"),
/// and the command line's words for it.
struct OptionFlag {
  std::string_view key;   ///< "heightmap.size", or "map.tiers: false"
  std::string_view flag;  ///< "--size", "--no-tiers"
  /// Words that "key: WORD" takes as the flag's value ("key: cpu" -> "--flag cpu"), separated by
  /// spaces; numbers ("key: 500", "key: -1,2,3", "key: nan") always are.
  std::string_view values;
};

/// @brief Every key the library's messages name that has a flag, with the flag.
std::span<const OptionFlag> optionFlags() noexcept;

/// @brief `text` with each configuration key of optionFlags() replaced by its flag: "key: VALUE"
/// (a number, or one of the row's values) becomes "--flag VALUE", "key: prose" "--flag: prose",
/// and a bare key the flag. A key is a whole word ("xheightmap.size" and "/heightmap.size/" are
/// left alone); keys that are not in the table stay as they are.
std::string withCliFlags(std::string_view text);

}  // namespace raymap::cli
