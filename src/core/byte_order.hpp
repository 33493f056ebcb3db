// SPDX-License-Identifier: BSD-3-Clause
// Numbers as bytes in a stated byte order: the one codec that every file format, bag and log
// record and CDR message of raymap reads and writes its integers and floats with, and LeWriter,
// the byte vector that file headers and records are put together in.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

namespace raymap {

/// A value the byte-order functions encode: an integer other than bool, or an IEEE 754 float, of
/// 1, 2, 4 or 8 bytes. Signed integers are stored as two's complement, floats as their bits.
template <class T>
concept ByteValue = std::is_arithmetic_v<T> && !std::is_same_v<T, bool> &&
                    (sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8);

namespace detail {

/// The unsigned integer with the bits of a T (a ByteValue: 1, 2, 4 or 8 bytes).
template <class T>
using UnsignedOf = std::conditional_t<
    sizeof(T) == 1, std::uint8_t,
    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;

/// `bits` with its bytes in the reverse order.
template <class U>
constexpr U byteSwap(U bits) noexcept {
  if constexpr (sizeof(U) == 1) {
    return bits;
  } else if constexpr (sizeof(U) == 2) {
    return __builtin_bswap16(bits);
  } else if constexpr (sizeof(U) == 4) {
    return __builtin_bswap32(bits);
  } else {
    return __builtin_bswap64(bits);
  }
}

/// The shift, in bits, of byte `i` of a `bytes`-byte value stored in `order`.
constexpr unsigned shiftOf(std::size_t i, std::size_t bytes, std::endian order) noexcept {
  return static_cast<unsigned>(8 * (order == std::endian::little ? i : bytes - 1 - i));
}

}  // namespace detail

// Byte order is stated, never assumed: a host of either order reads and writes the same bytes.
// At run time a value is copied with memcpy (no alignment needed) and its bytes are swapped when
// `order` is not the host's: one load or store and at most one bswap. GCC 12 does not merge a
// byte-by-byte loop into one load at -O2 (Clang does), and the point-cloud and depth-image
// decoders call these per point. In a constant expression (memcpy is not constexpr) the bytes
// are assembled one by one instead. Nothing here allocates or throws, except appendLe (it grows
// its container); all are pure, safe from any thread.
static_assert(std::endian::native == std::endian::little || std::endian::native == std::endian::big,
              "a mixed-endian host: byteSwap() would not convert its order");

/// @brief The T stored in the sizeof(T) bytes at `in` in byte order `order` (std::endian::little
/// or std::endian::big). `in` needs no alignment.
template <ByteValue T>
[[nodiscard]] constexpr T loadEndian(const std::byte* in, std::endian order) noexcept {
  using U = detail::UnsignedOf<T>;
  U bits = 0;
  if (std::is_constant_evaluated()) {
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      bits = static_cast<U>(
          bits | static_cast<U>(std::to_integer<U>(in[i]) << detail::shiftOf(i, sizeof(T), order)));
    }
  } else {
    std::memcpy(&bits, in, sizeof(U));
    if (order != std::endian::native) {
      bits = detail::byteSwap(bits);
    }
  }
  return std::bit_cast<T>(bits);
}

/// @brief Stores `value` in the sizeof(T) bytes at `out` in byte order `order`.
/// @return `out` + sizeof(T): where the next value goes.
template <ByteValue T>
constexpr std::byte* storeEndian(std::byte* out, T value, std::endian order) noexcept {
  auto bits = std::bit_cast<detail::UnsignedOf<T>>(value);
  if (std::is_constant_evaluated()) {
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      out[i] = static_cast<std::byte>(
          static_cast<std::uint8_t>(bits >> detail::shiftOf(i, sizeof(T), order)));
    }
  } else {
    if (order != std::endian::native) {
      bits = detail::byteSwap(bits);
    }
    std::memcpy(out, &bits, sizeof(bits));
  }
  return out + sizeof(T);
}

/// @brief The T stored least significant byte first at `in` (the order of every raymap file).
template <ByteValue T>
[[nodiscard]] constexpr T loadLe(const std::byte* in) noexcept {
  return loadEndian<T>(in, std::endian::little);
}

/// @brief The T stored most significant byte first at `in` (network order: PNG, CDR_BE).
template <ByteValue T>
[[nodiscard]] constexpr T loadBe(const std::byte* in) noexcept {
  return loadEndian<T>(in, std::endian::big);
}

/// @brief Stores `value` least significant byte first at `out`. @return `out` + sizeof(T).
template <ByteValue T>
constexpr std::byte* storeLe(std::byte* out, T value) noexcept {
  return storeEndian(out, value, std::endian::little);
}

/// @brief Stores `value` most significant byte first at `out`. @return `out` + sizeof(T).
template <ByteValue T>
constexpr std::byte* storeBe(std::byte* out, T value) noexcept {
  return storeEndian(out, value, std::endian::big);
}

/// @brief Appends `value` least significant byte first to `out`, a growable container of
/// std::byte (std::vector<std::byte>). Allocates when `out` grows.
template <ByteValue T, class Bytes>
void appendLe(Bytes& out, T value) {
  std::byte bytes[sizeof(T)];
  storeLe(bytes, value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

/// @brief A byte vector that grows by little-endian fields: how map files' headers, blocks and
/// indexes and MCAP's records are put together. Each method is named after the field's type in
/// those formats. Allocates as it grows; not thread-safe (a value type).
class LeWriter {
 public:
  void u8(std::uint8_t v) { appendLe(bytes_, v); }
  void u16(std::uint16_t v) { appendLe(bytes_, v); }
  void u32(std::uint32_t v) { appendLe(bytes_, v); }
  void u64(std::uint64_t v) { appendLe(bytes_, v); }
  void i32(std::int32_t v) { appendLe(bytes_, v); }
  void f32(float v) { appendLe(bytes_, v); }
  void f64(double v) { appendLe(bytes_, v); }
  /// Bytes as they are (no length, no terminator).
  void raw(std::span<const std::byte> bytes) {
    bytes_.insert(bytes_.end(), bytes.begin(), bytes.end());
  }
  /// The characters of `text` as bytes (no length, no terminator).
  void text(std::string_view chars) { raw(std::as_bytes(std::span(chars.data(), chars.size()))); }

  std::vector<std::byte>& bytes() noexcept { return bytes_; }
  std::size_t size() const noexcept { return bytes_.size(); }
  void clear() noexcept { bytes_.clear(); }

 private:
  std::vector<std::byte> bytes_;
};

}  // namespace raymap
