// SPDX-License-Identifier: BSD-3-Clause
// Reading a record log front to back (replay), with checksums on every record and a clean stop at
// the cut-off end of an interrupted recording.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/record/record_log.hpp"

namespace raymap::record {

/// @brief Reads the messages of a log (finished or `.partial`) in file order.
///
/// Design: a FILE* with a 256 KiB stdio buffer reads record headers and small payloads; each
/// payload lands in one reusable buffer that grows to the largest record seen (messages can be
/// several MB) and never shrinks. Each record's CRC-32 is checked before it is used. Records are
/// counted from 0 after the file header; errors say "record N at byte offset X".
///
/// Outcomes of next(): a message; std::nullopt at the end (after END, at the end of a file
/// without END, or at a record cut off by the end of the file, which truncation() describes); or
/// an error (kCorrupt, kIo) naming the file, the record index, its byte offset and the reason.
/// After an error, next() returns the same error until rewind().
///
/// Thread-safety: none; use one reader from one thread. Not copyable or movable (owned through
/// the unique_ptr open() returns).
class RecordLogReader {
 public:
  /// @brief What one pass over a log found; see summarize().
  /// Thread-safety: a value type.
  struct Summary {
    std::vector<LogTopic> topics;
    std::vector<std::uint64_t> messages_per_topic;  ///< indexed by topic id, same size as topics
    /// receive_unix_ns of the first and the last message in file order (= arrival order at the
    /// recorder), ns; both 0 when the log holds no message.
    std::int64_t first_receive_unix_ns = 0;
    std::int64_t last_receive_unix_ns = 0;
    bool complete = false;  ///< an END record closes the log
    std::optional<LogTruncation> truncation;
  };

  /// @brief Opens `path` and checks its file header.
  /// @return the reader, positioned at the first record; or kIo (cannot open, naming the path),
  /// kFormat "not a raymap record log" (wrong magic: a PLY file, text, an empty file),
  /// kUnsupported (a format version written by a newer raymap, unknown header flags),
  /// kTruncated (the file ends inside its header) or kCorrupt (header checksum, header size).
  static Result<std::unique_ptr<RecordLogReader>> open(const std::string& path);

  RecordLogReader(const RecordLogReader&) = delete;
  RecordLogReader& operator=(const RecordLogReader&) = delete;
  RecordLogReader(RecordLogReader&&) = delete;
  RecordLogReader& operator=(RecordLogReader&&) = delete;
  ~RecordLogReader();

  /// @brief Reads up to and including the next MESSAGE record. TOPIC records on the way extend
  /// topics(); unknown record kinds with a good checksum are skipped (forward compatibility).
  /// @return the message (its `cdr` valid until the next call of next() or rewind()), nullopt at
  /// the end, or an error: checksum mismatch, payload length above kMaxPayloadBytes, a message
  /// on a topic id no earlier TOPIC record declared, a malformed TOPIC or END payload, an END
  /// whose message count disagrees or that is followed by more bytes, a read error.
  Result<std::optional<LogMessage>> next();

  /// @brief Topics declared so far (index = id); after rewind() they stay known.
  const std::vector<LogTopic>& topics() const noexcept { return topics_; }
  /// @brief The topic with this id, or nullptr when none has been read yet.
  const LogTopic* topic(std::uint32_t id) const noexcept;
  /// @brief True once the END record has been read: the recording was closed cleanly.
  bool complete() const noexcept { return complete_; }
  /// @brief Set when the log ends in a record cut off by the end of the file.
  const std::optional<LogTruncation>& truncation() const noexcept { return truncation_; }
  /// @brief Messages returned by next() since open() or the last rewind().
  std::uint64_t messagesRead() const noexcept { return messages_read_; }
  /// @brief Fraction of the file's bytes consumed, 0 to 1 (1 at the end, whatever ended it).
  double progress() const noexcept;
  /// @brief Wall clock when the log was created, from the file header, ns since the epoch.
  std::int64_t createdUnixNs() const noexcept { return created_unix_ns_; }
  const std::string& path() const noexcept { return path_; }

  /// @brief Goes back to the first record (replay --loop) and clears complete(), truncation(),
  /// messagesRead() and any error; topics() stay known. A `.partial` file still being written is
  /// read to its new end on the next pass.
  /// @return kIo when the file cannot be repositioned.
  Result<void> rewind();

  /// @brief Reads the whole log once, checking every checksum, without keeping payloads (one
  /// payload buffer): topics, messages per topic, first and last receive time, END, truncation.
  /// @return the summary, or the first error open() or next() reports.
  static Result<Summary> summarize(const std::string& path);

 private:
  RecordLogReader(std::string path, std::FILE* file, std::unique_ptr<char[]> stdio_buffer,
                  std::uint64_t header_bytes, std::int64_t created_unix_ns) noexcept;

  /// What reading exactly `size` bytes at the current position found.
  enum class Fill : std::uint8_t { kAll, kNone, kSome };
  /// Reads `size` bytes into `out`; `got` is how many arrived (fewer only at the end of the file).
  Result<Fill> readExactly(std::byte* out, std::size_t size, std::size_t& got);
  /// "<path>: record N at byte offset X: <reason>" as an error, remembered for later next().
  Error recordError(ErrorCode code, std::uint64_t offset, const std::string& reason);
  /// Ends the pass at a record cut off at `offset`.
  void truncateAt(std::uint64_t offset, std::string what);
  /// Refreshes file_bytes_ (a `.partial` may still grow). Keeps the old size when fstat fails.
  void refreshFileSize() noexcept;
  /// True when every byte from the current position to the end of the file is zero.
  Result<bool> restIsZero();
  // The steps of next().
  /// Reads the record at `at` and checks its checksum: true with its kind and payload (valid
  /// until the next read); false when the pass ended there (the end, or a record cut off).
  Result<bool> readRecord(std::uint64_t at, std::uint32_t& kind,
                          std::span<const std::byte>& payload);
  /// An all-zero record header: a zero-filled tail (false: the pass ends) or damage.
  Result<bool> zeroHeader(std::uint64_t at);
  Expected<void, Error> readTopic(std::uint64_t at, std::span<const std::byte> payload);
  Result<LogMessage> readMessage(std::uint64_t at, std::span<const std::byte> payload);
  Expected<void, Error> readEnd(std::uint64_t at, std::span<const std::byte> payload);

  std::string path_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<char[]> stdio_buffer_;  // must outlive file_
  std::uint64_t header_bytes_ = 0;        // where the first record starts
  std::int64_t created_unix_ns_ = 0;
  std::uint64_t file_bytes_ = 0;
  std::uint64_t offset_ = 0;        // byte offset of the next record
  std::uint64_t record_index_ = 0;  // index of the next record in this pass
  std::uint64_t messages_read_ = 0;
  std::uint32_t declared_in_pass_ = 0;  // TOPIC ids 0 .. declared_in_pass_-1 seen in this pass
  std::vector<LogTopic> topics_;
  std::vector<std::byte> payload_;  // reused; grows to the largest payload, never shrinks
  bool complete_ = false;
  bool finished_ = false;  // this pass ended (END, end of file, truncation)
  std::optional<LogTruncation> truncation_;
  std::optional<Error> failure_;
};

}  // namespace raymap::record
