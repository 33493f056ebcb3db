// SPDX-License-Identifier: BSD-3-Clause
// Byte-level encoding of the record log shared by its writer and reader: the file header and the
// TOPIC, MESSAGE and END payloads (little-endian integers: src/core/byte_order.hpp; CRC-32:
// src/core/crc32.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "raymap/expected.hpp"

#include "src/record/record_log.hpp"

namespace raymap::record::detail {

// Every function here is a pure function of its arguments: safe to call from any thread.

/// @brief The version-1 file header for a log created at `created_unix_ns` (wall clock, ns).
std::array<std::byte, kFileHeaderBytes> encodeFileHeader(std::int64_t created_unix_ns) noexcept;

/// @brief CRC-32 of a record's kind and length fields. The stored checksum is the CRC-32 of kind,
/// length and payload together: continue this seed over the payload with raymap::crc32().
std::uint32_t recordCrcSeed(std::uint32_t kind, std::uint32_t payload_length) noexcept;
/// @brief Fills the 12-byte record header at `out` with `crc` from recordCrcSeed and crc32().
void encodeRecordHeader(std::byte* out, RecordKind kind, std::uint32_t payload_length,
                        std::uint32_t crc) noexcept;

/// @brief Size of the TOPIC payload for these strings, bytes. @pre each is at most 65535 bytes.
std::size_t topicPayloadBytes(const LogTopic& topic) noexcept;
/// @brief Writes the TOPIC payload at `out` (topicPayloadBytes(topic) bytes).
void encodeTopicPayload(std::byte* out, const LogTopic& topic) noexcept;
/// @brief Decodes a TOPIC payload; the error is the reason it is malformed. Bytes after the known
/// fields are ignored (the extension rule of docs/record-format.md).
Expected<LogTopic, std::string> decodeTopicPayload(std::span<const std::byte> payload);

/// @brief Writes the 28 bytes of a MESSAGE payload that precede the CDR bytes.
void encodeMessagePrefix(std::byte* out, std::uint32_t topic_id, std::int64_t receive_unix_ns,
                         std::int64_t receive_monotonic_ns,
                         std::int64_t source_timestamp_ns) noexcept;

/// The content of an END record. Thread-safety: a value type.
struct EndRecord {
  std::uint64_t message_count = 0;  ///< MESSAGE records the writer wrote
  std::int64_t end_unix_ns = 0;     ///< wall clock at close(), ns
};
/// Size of the version-1 END payload, bytes.
inline constexpr std::size_t kEndPayloadBytes = 16;
void encodeEndPayload(std::byte* out, const EndRecord& end) noexcept;
/// @brief Decodes an END payload; bytes after the known fields are ignored.
Expected<EndRecord, std::string> decodeEndPayload(std::span<const std::byte> payload);

}  // namespace raymap::record::detail
