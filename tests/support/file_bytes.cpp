// SPDX-License-Identifier: BSD-3-Clause
// Whole-file reads and writes, little-endian fields and the CRC-32 for forging test files.
#include "tests/support/file_bytes.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>

#include "src/core/byte_order.hpp"
#include "src/core/crc32.hpp"

namespace raymap::test {

Bytes readFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void writeFileBytes(const std::string& path, const Bytes& bytes) {
  // Unlink first: truncating a file with data makes ext4 flush it on close (auto_da_alloc),
  // which would make the tests' every-offset loops take seconds.
  std::filesystem::remove(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// The low `count` bytes of a u64 stored little-endian are the field: one u64 codec serves every
// width, and bytes.at() checks the range.

std::uint64_t getLe(const Bytes& bytes, std::size_t at, int count) {
  std::array<std::byte, 8> field{};  // the bytes above `count` stay zero
  for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
    field.at(i) = std::byte{bytes.at(at + i)};
  }
  return loadLe<std::uint64_t>(field.data());
}

void putLe(Bytes& bytes, std::size_t at, std::uint64_t v, int count) {
  std::array<std::byte, 8> field{};
  storeLe(field.data(), v);
  for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
    bytes.at(at + i) = std::to_integer<std::uint8_t>(field.at(i));
  }
}

void appendLe(Bytes& bytes, std::uint64_t v, int count) {
  bytes.resize(bytes.size() + static_cast<std::size_t>(count));
  putLe(bytes, bytes.size() - static_cast<std::size_t>(count), v, count);
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  return raymap::crc32(0, std::as_bytes(std::span(data, size)));
}

}  // namespace raymap::test
