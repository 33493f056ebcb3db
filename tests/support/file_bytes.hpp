// SPDX-License-Identifier: BSD-3-Clause
// Test-only file bytes: read and write whole files, bounds-checked little-endian fields and the
// CRC-32 of some of them, for forging files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace raymap::test {

/// @brief The bytes of a file.
using Bytes = std::vector<std::uint8_t>;

/// @brief Every byte of the file at `path` (empty when it cannot be read).
Bytes readFileBytes(const std::string& path);

/// @brief Replaces the file at `path` with `bytes` (unlinked first, then written anew).
void writeFileBytes(const std::string& path, const Bytes& bytes);

/// @brief The little-endian unsigned integer of `count` bytes at `at`; throws when out of range.
std::uint64_t getLe(const Bytes& bytes, std::size_t at, int count);

/// @brief Stores the low `count` bytes of `v` little-endian at `at`; throws when out of range.
void putLe(Bytes& bytes, std::size_t at, std::uint64_t v, int count);

/// @brief Appends the low `count` bytes of `v` little-endian.
void appendLe(Bytes& bytes, std::uint64_t v, int count);

/// @brief The CRC-32 (raymap::crc32, zlib's) of `size` bytes at `data`: so tests can forge files
/// whose checksums are right but whose content is wrong.
std::uint32_t crc32(const std::uint8_t* data, std::size_t size);

}  // namespace raymap::test
