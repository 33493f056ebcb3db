// SPDX-License-Identifier: BSD-3-Clause
// The fixed sizes of the map file's parts (docs/map-format.md), for tests that edit map files
// byte by byte.
#pragma once

#include <cstddef>

namespace raymap::test {

constexpr std::size_t kMapPrefixBytes = 16;       ///< magic, version, header body size
constexpr std::size_t kMapBlockHeaderBytes = 32;  ///< before each region block's layers
constexpr std::size_t kMapFooterBytes = 24;       ///< index offset, count, checksum
constexpr std::size_t kMapIndexEntryBytes = 20;   ///< one region in the index

}  // namespace raymap::test
