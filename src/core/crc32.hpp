// SPDX-License-Identifier: BSD-3-Clause
// The CRC-32 that raymap's map files, spill files, record logs and MCAP bags carry: zlib's.
#pragma once

#include <cstdint>
#include <span>

namespace raymap {

/// @brief Continues the CRC-32 `crc` over `bytes`. It is the IEEE 802.3 CRC-32 of zlib, gzip, PNG
/// and MCAP (reflected polynomial 0xEDB88320, register preset to and result XORed with all ones),
/// computed by zlib: start with 0; crc32(crc32(0, a), b) == crc32(0, a followed by b), so a stream
/// is checksummed piece by piece. Any size (beyond 4 GiB too); an empty `bytes` returns `crc`.
/// Pure; safe from any thread; allocates: no.
[[nodiscard]] std::uint32_t crc32(std::uint32_t crc, std::span<const std::byte> bytes) noexcept;

}  // namespace raymap
