// SPDX-License-Identifier: BSD-3-Clause
// loadLe/storeLe, loadBe/storeBe and the byte-order-parameterised pair: known byte patterns of
// every width, round trips of edge values, unaligned access, and the same results at compile time.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "src/core/byte_order.hpp"

namespace raymap {
namespace {

template <std::size_t N>
constexpr std::array<std::byte, N> bytesOf(const std::uint8_t (&values)[N]) {
  std::array<std::byte, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    out[i] = std::byte{values[i]};
  }
  return out;
}

constexpr auto kCounting = bytesOf({0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08});

// The same answers in a constant expression (the byte-by-byte path) as at run time (memcpy).
static_assert(loadLe<std::uint32_t>(kCounting.data()) == 0x04030201u);
static_assert(loadBe<std::uint32_t>(kCounting.data()) == 0x01020304u);
static_assert(loadLe<std::uint64_t>(kCounting.data()) == 0x0807060504030201u);
static_assert(loadEndian<std::uint16_t>(kCounting.data(), std::endian::big) == 0x0102u);
static_assert([] {
  std::array<std::byte, 8> out{};
  storeBe(storeLe(out.data(), std::int16_t{-2}), 0x01020304u);
  return out == bytesOf({0xFE, 0xFF, 0x01, 0x02, 0x03, 0x04, 0x00, 0x00});
}());

TEST(ByteOrder, LittleEndianLoadsReadTheLeastSignificantByteFirst) {
  // Arrange
  const auto b = kCounting;

  // Act, Assert
  EXPECT_EQ(loadLe<std::uint8_t>(b.data()), 0x01u);
  EXPECT_EQ(loadLe<std::uint16_t>(b.data()), 0x0201u);
  EXPECT_EQ(loadLe<std::uint32_t>(b.data()), 0x04030201u);
  EXPECT_EQ(loadLe<std::uint64_t>(b.data()), 0x0807060504030201u);
  EXPECT_EQ(loadLe<std::uint32_t>(b.data() + 1), 0x05040302u);  // unaligned
}

TEST(ByteOrder, BigEndianLoadsReadTheMostSignificantByteFirst) {
  // Arrange
  const auto b = kCounting;

  // Act, Assert
  EXPECT_EQ(loadBe<std::uint16_t>(b.data()), 0x0102u);
  EXPECT_EQ(loadBe<std::uint32_t>(b.data() + 3), 0x04050607u);  // unaligned
  EXPECT_EQ(loadBe<std::uint64_t>(b.data()), 0x0102030405060708u);
  EXPECT_EQ(loadEndian<std::uint32_t>(b.data(), std::endian::big), 0x01020304u);
  EXPECT_EQ(loadEndian<std::uint32_t>(b.data(), std::endian::little), 0x04030201u);
}

TEST(ByteOrder, SignedValuesAreTwosComplementAndFloatsTheirIeeeBits) {
  // Arrange: -2 as int32, 1.0f (0x3F800000), -0.5 (0xBFE0000000000000), all little-endian.
  const auto minus_two = bytesOf({0xFE, 0xFF, 0xFF, 0xFF});
  const auto one_f32 = bytesOf({0x00, 0x00, 0x80, 0x3F});
  const auto minus_half_f64 = bytesOf({0, 0, 0, 0, 0, 0, 0xE0, 0xBF});

  // Act, Assert
  EXPECT_EQ(loadLe<std::int32_t>(minus_two.data()), -2);
  EXPECT_EQ(loadLe<std::int16_t>(minus_two.data()), -2);
  EXPECT_EQ(loadLe<std::int8_t>(minus_two.data()), -2);
  EXPECT_EQ(loadLe<std::int64_t>(bytesOf({0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}).data()),
            -1);
  EXPECT_EQ(loadLe<float>(one_f32.data()), 1.0f);
  EXPECT_EQ(loadBe<float>(bytesOf({0x3F, 0x80, 0x00, 0x00}).data()), 1.0f);
  EXPECT_EQ(loadLe<double>(minus_half_f64.data()), -0.5);
}

TEST(ByteOrder, StoresWriteTheDocumentedBytesAndSayWhereTheNextValueGoes) {
  // Arrange
  std::array<std::byte, 15> out{};

  // Act
  std::byte* next = storeLe(out.data(), std::uint32_t{0xA1B2C3D4u});
  next = storeBe(next, std::uint16_t{0x0102u});
  next = storeEndian(next, std::int8_t{-1}, std::endian::big);
  next = storeEndian(next, 1.0, std::endian::little);

  // Assert
  EXPECT_EQ(next, out.data() + out.size());
  EXPECT_EQ(out, bytesOf({0xD4, 0xC3, 0xB2, 0xA1, 0x01, 0x02, 0xFF, 0, 0, 0, 0, 0, 0, 0xF0, 0x3F}));
}

/// Stores `value` in both orders at an odd offset and loads it back both ways.
template <class T>
void expectRoundTrips(T value) {
  std::array<std::byte, sizeof(T) + 1> le{};
  std::array<std::byte, sizeof(T) + 1> be{};
  storeLe(le.data() + 1, value);
  storeBe(be.data() + 1, value);
  EXPECT_EQ(loadLe<T>(le.data() + 1), value);
  EXPECT_EQ(loadBe<T>(be.data() + 1), value);
  EXPECT_EQ(loadEndian<T>(le.data() + 1, std::endian::little), value);
  EXPECT_EQ(loadEndian<T>(be.data() + 1, std::endian::big), value);
  // The two orders are each other's reverse.
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    EXPECT_EQ(le[1 + i], be[sizeof(T) - i]) << "byte " << i;
  }
}

template <class T>
void expectEdgesRoundTrip() {
  expectRoundTrips<T>(std::numeric_limits<T>::min());
  expectRoundTrips<T>(std::numeric_limits<T>::max());
  expectRoundTrips<T>(std::numeric_limits<T>::lowest());
  expectRoundTrips<T>(T{0});
  expectRoundTrips<T>(T{1});
}

TEST(ByteOrder, EveryTypeRoundTripsInBothOrders) {
  expectEdgesRoundTrip<std::uint8_t>();
  expectEdgesRoundTrip<std::int8_t>();
  expectEdgesRoundTrip<std::uint16_t>();
  expectEdgesRoundTrip<std::int16_t>();
  expectEdgesRoundTrip<std::uint32_t>();
  expectEdgesRoundTrip<std::int32_t>();
  expectEdgesRoundTrip<std::uint64_t>();
  expectEdgesRoundTrip<std::int64_t>();
  expectEdgesRoundTrip<float>();
  expectEdgesRoundTrip<double>();
  expectRoundTrips(-0.0f);
  expectRoundTrips(std::numeric_limits<double>::infinity());
  expectRoundTrips(std::numeric_limits<float>::denorm_min());
}

TEST(ByteOrder, NanPayloadsSurviveBitForBit) {
  // Arrange: a quiet NaN with a payload; compared as bits (NaN != NaN).
  const auto nan = bytesOf({0x01, 0x00, 0xC0, 0x7F});

  // Act
  const float value = loadLe<float>(nan.data());
  std::array<std::byte, 4> out{};
  storeLe(out.data(), value);

  // Assert
  EXPECT_EQ(out, nan);
}

TEST(ByteOrder, AppendLeGrowsAByteVector) {
  // Arrange
  std::vector<std::byte> out{std::byte{0xAA}};

  // Act
  appendLe(out, std::uint16_t{0x0102u});
  appendLe(out, -1.0f);

  // Assert
  const auto expected = bytesOf({0xAA, 0x02, 0x01, 0x00, 0x00, 0x80, 0xBF});
  EXPECT_EQ(out, std::vector<std::byte>(expected.begin(), expected.end()));
}

}  // namespace
}  // namespace raymap
