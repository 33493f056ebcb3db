// SPDX-License-Identifier: BSD-3-Clause
// Whole-file reads and writes, little-endian fields and the CRC-32 for forging test files.
#include "tests/support/file_bytes.hpp"

#include <filesystem>
#include <fstream>
#include <iterator>

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

std::uint64_t getLe(const Bytes& bytes, std::size_t at, int count) {
  std::uint64_t v = 0;
  for (int i = 0; i < count; ++i) {
    v |= std::uint64_t{bytes.at(at + static_cast<std::size_t>(i))} << (8 * i);
  }
  return v;
}

void putLe(Bytes& bytes, std::size_t at, std::uint64_t v, int count) {
  for (int i = 0; i < count; ++i) {
    bytes.at(at + static_cast<std::size_t>(i)) = static_cast<std::uint8_t>(v >> (8 * i));
  }
}

void appendLe(Bytes& bytes, std::uint64_t v, int count) {
  bytes.resize(bytes.size() + static_cast<std::size_t>(count));
  putLe(bytes, bytes.size() - static_cast<std::size_t>(count), v, count);
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 1u) != 0 ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
  }
  return ~crc;
}

}  // namespace raymap::test
