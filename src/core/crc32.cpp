// SPDX-License-Identifier: BSD-3-Clause
// CRC-32 through zlib (see crc32.hpp).
#include "src/core/crc32.hpp"

#include <zlib.h>

namespace raymap {

std::uint32_t crc32(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  // NOTE: zlib reads a null buffer as "return the initial value" and answers 0 whatever `crc` is,
  // and an empty span may well have a null data(): an empty piece must leave `crc` alone.
  if (bytes.empty()) {
    return crc;
  }
  // crc32_z takes a size_t length (crc32's is a 32-bit uInt): no split at 4 GiB needed.
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

}  // namespace raymap
