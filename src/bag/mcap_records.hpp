// SPDX-License-Identifier: BSD-3-Clause
// The MCAP container's record layout (https://mcap.dev/spec, major version 0), shared by the
// reader and the writer: the magic, the opcodes, and a bounds-checked little-endian cursor over
// one record's content and its writing counterpart. MCAP's CRC-32 is zlib's: src/core/crc32.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "src/core/byte_order.hpp"

namespace raymap::bag::mcap {

/// Begins and ends every MCAP file: 0x89 "MCAP" '0' (major version) "\r\n".
inline constexpr std::array<std::byte, 8> kMagic{std::byte{0x89}, std::byte{'M'}, std::byte{'C'},
                                                 std::byte{'A'},  std::byte{'P'}, std::byte{'0'},
                                                 std::byte{'\r'}, std::byte{'\n'}};

/// Every record: opcode (uint8) and content length (uint64), then the content.
inline constexpr std::size_t kRecordPrefixBytes = 9;

enum class Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// Footer content: summary_start, summary_offset_start (uint64), summary_crc (uint32).
inline constexpr std::size_t kFooterContentBytes = 20;
/// A file ends with the footer record and the magic.
inline constexpr std::size_t kFooterRecordBytes = kRecordPrefixBytes + kFooterContentBytes;

/// @brief Reads the fields of one record's content in order. A read past the end sets a sticky
/// failure flag and returns zero/empty, so a parser reads every field and checks ok() once.
/// Views returned point into the content (valid as long as it is). Not thread-safe.
class Cursor {
 public:
  explicit Cursor(std::span<const std::byte> content) noexcept : bytes_(content) {}

  bool ok() const noexcept { return ok_; }
  std::size_t left() const noexcept { return bytes_.size() - at_; }

  std::uint8_t u8() noexcept { return little<std::uint8_t>(); }
  std::uint16_t u16() noexcept { return little<std::uint16_t>(); }
  std::uint32_t u32() noexcept { return little<std::uint32_t>(); }
  std::uint64_t u64() noexcept { return little<std::uint64_t>(); }
  /// A uint32 length prefix and that many bytes of UTF-8.
  std::string_view string() noexcept {
    const std::span<const std::byte> b = take(u32());
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  /// A uint32 length prefix and that many bytes.
  std::span<const std::byte> bytes32() noexcept { return take(u32()); }
  /// A uint64 length prefix and that many bytes.
  std::span<const std::byte> bytes64() noexcept { return take(u64()); }
  /// Everything left (a message's data).
  std::span<const std::byte> rest() noexcept { return take(left()); }
  /// `n` bytes, or an empty span and the failure flag when fewer are left.
  std::span<const std::byte> take(std::uint64_t n) noexcept {
    if (!ok_ || n > left()) {
      ok_ = false;
      return {};
    }
    const std::span<const std::byte> b = bytes_.subspan(at_, static_cast<std::size_t>(n));
    at_ += static_cast<std::size_t>(n);
    return b;
  }

 private:
  /// The next T, or 0 (and the failure flag) when fewer than sizeof(T) bytes are left.
  template <ByteValue T>
  T little() noexcept {
    const std::span<const std::byte> b = take(sizeof(T));
    return b.empty() ? T{0} : loadLe<T>(b.data());
  }

  std::span<const std::byte> bytes_;
  std::size_t at_ = 0;
  bool ok_ = true;
};

/// @brief Appends record fields in little-endian order (the writer's counterpart of Cursor):
/// LeWriter's fields, plus MCAP's strings and records. Not thread-safe; allocates (offline and
/// recording paths only).
class Builder : public LeWriter {
 public:
  /// A uint32 length prefix and the bytes of `s`.
  void string(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    text(s);
  }
  /// Starts a record: opcode and a length to be filled in by endRecord(). @return its start.
  std::size_t beginRecord(Op op) {
    const std::size_t at = size();
    u8(static_cast<std::uint8_t>(op));
    u64(0);
    return at;
  }
  void endRecord(std::size_t at) { patch64(at + 1, size() - at - kRecordPrefixBytes); }
  /// Overwrites the uint64 at `at` (a length prefix written before its content).
  void patch64(std::size_t at, std::uint64_t v) { storeLe(bytes().data() + at, v); }
  void patch32(std::size_t at, std::uint32_t v) { storeLe(bytes().data() + at, v); }
};

}  // namespace raymap::bag::mcap
