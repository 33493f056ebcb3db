// SPDX-License-Identifier: BSD-3-Clause
// A bounded reader of XCDR1 (classic CDR) bytes, as ROS 2 messages travel: no allocation, every
// read checked against the end of the buffer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace raymap::msgs {

/// @brief Reads an XCDR1 payload that starts with its 4-byte encapsulation header
/// (00 01 = CDR little endian, 00 00 = CDR big endian; the options bytes are ignored).
///
/// Rules (ROS 2 / rmw_cyclonedds): each primitive is aligned to its size (at most 8) relative to
/// the first byte after the encapsulation header; a string is a uint32 length that counts the
/// terminating NUL, the bytes and the NUL; a sequence is a uint32 element count and the elements.
///
/// Error handling is sticky: the first read that would pass the end of the buffer (or a string
/// without its NUL) puts the reader in the failed state, returns false and leaves its output
/// unchanged; every later read fails too. So a decoder may read a whole struct and check
/// `ok()` once.
///
/// Thread-safety: none (a cursor over caller-owned bytes, which must outlive it).
/// @rt allocates: no; blocks: no.
class CdrReader {
 public:
  /// @brief A reader in the failed state (bad or missing encapsulation header).
  CdrReader() noexcept = default;
  /// @brief Starts after the encapsulation header of `cdr`; ok() is false when the buffer is
  /// shorter than 4 bytes or the representation is not CDR_LE/CDR_BE.
  explicit CdrReader(std::span<const std::byte> cdr) noexcept;

  bool ok() const noexcept { return ok_; }
  /// @brief The failure was structural (a string without its NUL), not the end of the data.
  bool malformed() const noexcept { return malformed_; }
  /// @brief True for CDR_LE data (00 01), false for CDR_BE (00 00).
  bool littleEndian() const noexcept { return little_endian_; }
  /// @brief Bytes left after the cursor (0 once failed).
  std::size_t remaining() const noexcept { return ok_ ? payload_.size() - position_ : 0; }
  /// @brief Offset of the cursor from the start of the payload (after the header).
  std::size_t position() const noexcept { return position_; }

  /// @brief Moves the cursor to the next multiple of `alignment` (1, 2, 4 or 8).
  bool align(std::size_t alignment) noexcept;
  bool readU8(std::uint8_t& out) noexcept;
  /// @brief A CDR boolean: one byte, 0 or 1 (other values read as true, as Cyclone does).
  bool readBool(bool& out) noexcept;
  bool readU16(std::uint16_t& out) noexcept;
  bool readU32(std::uint32_t& out) noexcept;
  bool readI32(std::int32_t& out) noexcept;
  bool readU64(std::uint64_t& out) noexcept;
  bool readF32(float& out) noexcept;
  bool readF64(double& out) noexcept;
  /// @brief A string; `out` views the bytes inside the buffer, without the NUL. A zero length
  /// (which some writers send for "") reads as an empty string.
  bool readString(std::string_view& out) noexcept;
  /// @brief readString() copied into `out`, for decoders that keep what they read.
  /// @rt allocates: yes (the copy); not for the real-time path.
  bool readString(std::string& out);
  /// @brief A sequence length. Fails when `count * min_element_bytes` cannot fit in what is left,
  /// so an absurd count is rejected before any loop runs over it.
  bool readSequenceLength(std::uint32_t& count, std::size_t min_element_bytes) noexcept;
  /// @brief `count` raw bytes (no alignment, no byte swapping).
  bool readBytes(std::size_t count, std::span<const std::byte>& out) noexcept;
  /// @brief Skips `count` bytes (no alignment).
  bool skip(std::size_t count) noexcept;
  /// @brief Puts the reader in the failed state (for a decoder's own structural checks).
  void fail() noexcept { ok_ = false; }

 private:
  template <class T>
  bool readPrimitive(T& out) noexcept;

  std::span<const std::byte> payload_{};
  std::size_t position_ = 0;
  bool little_endian_ = true;
  bool ok_ = false;
  bool malformed_ = false;
};

}  // namespace raymap::msgs
