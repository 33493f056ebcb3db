// SPDX-License-Identifier: BSD-3-Clause
// crc32(): the CRC-32 check value of the catalogue, known values of other inputs, and a stream
// checksummed piece by piece equal to the whole checksummed at once.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "src/core/crc32.hpp"

namespace raymap {
namespace {

std::span<const std::byte> bytesOf(std::string_view text) {
  return std::as_bytes(std::span(text.data(), text.size()));
}

TEST(Crc32, TheCheckValueOfTheDigitsOneToNine) {
  // The "check" of CRC-32/ISO-HDLC in the CRC catalogue (zlib's, PNG's).
  EXPECT_EQ(crc32(0, bytesOf("123456789")), 0xCBF43926u);
}

TEST(Crc32, KnownValues) {
  EXPECT_EQ(crc32(0, bytesOf("a")), 0xE8B7BE43u);
  EXPECT_EQ(crc32(0, bytesOf("The quick brown fox jumps over the lazy dog")), 0x414FA339u);
  EXPECT_EQ(crc32(0, bytesOf("IEND")), 0xAE426082u);  // the CRC every PNG ends with
}

TEST(Crc32, NothingLeavesTheCrcAsItIs) {
  // Arrange: an empty span with a null data(), which zlib alone would read as "restart".
  const std::span<const std::byte> empty;

  // Act, Assert
  EXPECT_EQ(crc32(0, empty), 0u);
  EXPECT_EQ(crc32(0xCBF43926u, empty), 0xCBF43926u);
}

TEST(Crc32, ContinuingPieceByPieceEqualsOneShot) {
  // Arrange: 100,000 bytes of a pattern, cut at every kind of boundary.
  std::vector<std::byte> data(100'000);
  for (std::size_t i = 0; i < data.size(); ++i) {
    data[i] = static_cast<std::byte>((i * 131 + i / 7) & 0xFFu);
  }
  const std::uint32_t whole = crc32(0, data);

  for (const std::size_t piece :
       {std::size_t{1}, std::size_t{3}, std::size_t{4096}, std::size_t{65'537}, data.size()}) {
    // Act
    std::uint32_t crc = 0;
    for (std::size_t at = 0; at < data.size(); at += piece) {
      crc = crc32(crc, std::span(data).subspan(at, std::min(piece, data.size() - at)));
    }

    // Assert
    EXPECT_EQ(crc, whole) << "pieces of " << piece << " bytes";
  }
}

}  // namespace
}  // namespace raymap
