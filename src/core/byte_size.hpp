// SPDX-License-Identifier: BSD-3-Clause
// Sizes written as text ("4GiB", "512MiB", "1.5G", plain bytes) and device cache sizes ("auto",
// a size, or "2000regions"): one reading for the command line's flags and raymapd's YAML.
#pragma once

#include <cstdint>
#include <string>

#include "raymap/error.hpp"

namespace raymap {

/// @brief Parses a size: a number (decimals allowed) and an optional binary unit B, K/k/KiB,
/// M/MiB, G/GiB, T/TiB. @return bytes; the error says what is wrong with `text` (the caller
/// adds the option's name). Pure function: any thread, allocates only for the error.
Result<std::uint64_t> parseByteSize(const std::string& text);

/// A device region cache as asked for: both zero for "auto".
struct CacheSize {
  std::uint64_t bytes = 0;
  std::uint32_t regions = 0;  ///< "2000regions": a count of regions (wins over bytes)
};

/// @brief Parses "auto", a size (parseByteSize) or a region count "<N>regions" (N >= 1).
Result<CacheSize> parseCacheSize(const std::string& text);

}  // namespace raymap
