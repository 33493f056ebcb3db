// SPDX-License-Identifier: BSD-3-Clause
// The raymap record log (`raymap record` / `raymap replay`): format constants and the value types
// its writer and reader exchange. The byte layout is in docs/record-format.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace raymap::record {

// ---- format version 1 (docs/record-format.md); every integer is little-endian ----

/// First 8 bytes of every log. "\r\n" and "\x1a" make a text-mode transfer or `type` fail the
/// check.
inline constexpr std::string_view kRecordLogMagic{"RMLOG\r\n\x1a", 8};
/// The format version this build writes, and the newest it reads.
inline constexpr std::uint32_t kRecordLogVersion = 1;
/// Size of the version-1 file header, bytes.
inline constexpr std::size_t kFileHeaderBytes = 32;
/// Size of a record header (u32 kind, u32 payload length, u32 CRC-32), bytes.
inline constexpr std::size_t kRecordHeaderBytes = 12;
/// Payload lengths above this are corruption, never data (bounds the reader's buffer), bytes.
inline constexpr std::uint32_t kMaxPayloadBytes = std::uint32_t{512} << 20;
/// Fixed part of a MESSAGE payload before the CDR bytes (topic id and three timestamps), bytes.
inline constexpr std::size_t kMessagePrefixBytes = 28;
/// Largest CDR payload one message can carry, bytes.
inline constexpr std::size_t kMaxCdrBytes = kMaxPayloadBytes - kMessagePrefixBytes;

/// Record kinds (values are part of the format and are never renumbered). Readers skip kinds
/// they do not know when the record's checksum is good.
enum class RecordKind : std::uint32_t {
  kTopic = 1,    ///< declares a topic id before the first message on it
  kMessage = 2,  ///< one received sample: timestamps and the raw CDR bytes
  kEnd = 3,      ///< written by a clean close only
};

/// DDS reliability the recorder subscribed with (replay publishes with the same).
enum class LogReliability : std::uint8_t { kBestEffort = 0, kReliable = 1 };
/// DDS durability the recorder subscribed with (transient-local topics are latched, like
/// /tf_static).
enum class LogDurability : std::uint8_t { kVolatile = 0, kTransientLocal = 1 };

/// @brief One recorded topic, as its TOPIC record declares it.
/// Thread-safety: a value type; no shared state.
struct LogTopic {
  std::uint32_t id = 0;  ///< 0, 1, 2, ... in order of first appearance in the file
  std::string name;      ///< DDS topic name, e.g. "rt/points"
  std::string type;      ///< DDS type name, e.g. "sensor_msgs::msg::dds_::PointCloud2_"
  LogReliability reliability = LogReliability::kBestEffort;
  LogDurability durability = LogDurability::kVolatile;

  bool operator==(const LogTopic&) const = default;
};

/// @brief One recorded message. `cdr` points into the reader's buffer: it is valid until the next
/// call to RecordLogReader::next() or rewind(), or the reader's destruction.
/// Thread-safety: a value type over borrowed bytes; read it on the reader's thread.
struct LogMessage {
  std::uint32_t topic_id = 0;
  std::int64_t receive_unix_ns = 0;       ///< wall clock at the recorder when it arrived, ns
  std::int64_t receive_monotonic_ns = 0;  ///< CLOCK_MONOTONIC at the recorder, ns (for pacing)
  std::int64_t source_timestamp_ns = 0;   ///< the writer's DDS source timestamp, ns since epoch
  /// The serialized sample as it came off the wire, including the 4-byte encapsulation header.
  std::span<const std::byte> cdr;
};

/// @brief Where and why a log stops early: the last record is cut off by the end of the file (a
/// recorder killed mid-write, a copy cut short, a zero-filled tail after a power loss).
/// Thread-safety: a value type.
struct LogTruncation {
  std::uint64_t offset = 0;  ///< start of the incomplete record: the usable length, bytes
  std::uint64_t complete_messages = 0;  ///< messages before it, all readable
  std::string what;                     ///< which record and how much of it is there
};

/// @brief True when the file exists and starts with kRecordLogMagic (lets replay tell logs from
/// PLY files). Reads 8 bytes; any failure (missing, unreadable, shorter) is false.
/// Thread-safety: safe to call from any thread.
bool looksLikeRecordLog(const std::string& path);

/// @brief True when `path` is to be read as a record log: it starts with kRecordLogMagic, or its
/// name ends in ".rmlog" (so that an empty or damaged log is reported as a log that is empty or
/// damaged, not as a file of another format).
/// Thread-safety: safe to call from any thread.
bool isRecordLogInput(const std::string& path);

}  // namespace raymap::record
