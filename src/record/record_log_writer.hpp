// SPDX-License-Identifier: BSD-3-Clause
// Writing a record log: one write(2) per record, straight into `<path>.partial`, renamed on close.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "raymap/error.hpp"

#include "src/record/record_log.hpp"

namespace raymap::record {

/// @brief Appends TOPIC and MESSAGE records to a new log and finishes it with an END record.
///
/// Design: there is no user-space buffer. Each record is assembled (header and message prefix on
/// the stack, the CDR bytes in place) and handed to the kernel in one writev(2), so every call
/// that returned is in the page cache: a recorder killed with SIGKILL leaves a `.partial` file
/// whose records are all readable. Only a power loss can lose returned records (close() fsyncs;
/// nothing else does, to keep the receive path free of disk waits).
///
/// Crash behaviour: while recording, the file is `<path>.partial` and `<path>` does not exist (or
/// is an older file); close() writes END, fsyncs, renames `.partial` onto `<path>` and fsyncs the
/// directory. A writer destroyed without close() leaves the `.partial` file as it is.
///
/// Thread-safety: none; use one writer from one thread (the recorder's writer thread).
/// Not copyable or movable (owned through the unique_ptr create() returns).
class RecordLogWriter {
 public:
  /// @brief Creates `<path>.partial` and writes the file header (created now, wall clock).
  /// Refuses to overwrite an existing `.partial` file: it may be the only copy of an interrupted
  /// recording. An existing file at `path` is replaced by close().
  /// @return the writer, or kIo naming the path and the reason (missing or read-only directory,
  /// `.partial` exists), or kInvalidArgument for an empty path.
  static Result<std::unique_ptr<RecordLogWriter>> create(const std::string& path);

  RecordLogWriter(const RecordLogWriter&) = delete;
  RecordLogWriter& operator=(const RecordLogWriter&) = delete;
  RecordLogWriter(RecordLogWriter&&) = delete;
  RecordLogWriter& operator=(RecordLogWriter&&) = delete;
  /// @brief Without close(): closes the descriptor and leaves `.partial` as is (like a crash).
  ~RecordLogWriter();

  /// @brief Declares a topic (writes its TOPIC record). Ids are 0, 1, 2, ... in call order. A
  /// name may be declared more than once (e.g. with another type); each call gets a new id.
  /// @param[in] name DDS topic name, 1 to 65535 bytes. @param[in] type DDS type name, at most
  /// 65535 bytes.
  /// @return the topic id for write(), or kInvalidArgument (bad name, unknown enum value), kIo.
  Result<std::uint32_t> addTopic(const std::string& name, const std::string& type,
                                 LogReliability reliability, LogDurability durability);

  /// @brief Appends one MESSAGE record with one writev(2) (retried only for EINTR and short
  /// writes). Allocates nothing on success.
  /// @param[in] topic_id an id addTopic() returned.
  /// @param[in] receive_unix_ns wall clock at reception, ns. @param[in] receive_monotonic_ns
  /// CLOCK_MONOTONIC at reception, ns. @param[in] source_timestamp_ns the DDS source timestamp, ns.
  /// @param[in] cdr the serialized sample with its encapsulation header; at most kMaxCdrBytes.
  /// @return kInvalidArgument (unknown topic id, too large, closed) or kIo (disk full, ...). After
  /// kIo the file is cut back to its last complete record, so it stays readable; if even that
  /// fails, every later call fails too.
  Result<void> write(std::uint32_t topic_id, std::int64_t receive_unix_ns,
                     std::int64_t receive_monotonic_ns, std::int64_t source_timestamp_ns,
                     std::span<const std::byte> cdr);

  /// @brief Writes END (message count, wall clock now), fsyncs, renames `.partial` to the final
  /// path and fsyncs the directory. Later calls to any writing function fail.
  /// @return kIo naming the file; if only the rename failed, the complete log stays in `.partial`.
  Result<void> close();

  /// @brief MESSAGE records written so far.
  std::uint64_t messages() const noexcept { return messages_; }
  /// @brief Size of the file so far (header and every record), bytes.
  std::uint64_t bytes() const noexcept { return bytes_; }
  /// @brief The final path given to create().
  const std::string& path() const noexcept { return path_; }
  /// @brief `<path>.partial`, the file being written until close().
  const std::string& partialPath() const noexcept { return partial_path_; }

 private:
  /// Most payload pieces one record is written from (MESSAGE: prefix and CDR bytes).
  static constexpr std::size_t kMaxPayloadParts = 2;

  RecordLogWriter(std::string path, std::string partial_path, int fd) noexcept;
  /// Writes one record (header, then the payload pieces) with writeAll().
  Result<void> appendRecord(RecordKind kind, std::span<const std::span<const std::byte>> payload,
                            const char* what);
  /// Writes `parts` back to back with writev(2), continuing after EINTR and short writes. On
  /// failure cuts the file back to bytes_ (or marks the writer broken_ when it cannot).
  Result<void> writeAll(std::span<const std::span<const std::byte>> parts, const char* what);
  /// Why writing is refused (closed, broken), or nullptr when the writer can write.
  const char* unusableReason() const noexcept;

  std::string path_;
  std::string partial_path_;
  int fd_ = -1;
  bool closed_ = false;
  bool broken_ = false;  // a failed write could not be rolled back: the tail is unknown
  std::uint32_t topic_count_ = 0;
  std::uint64_t messages_ = 0;
  std::uint64_t bytes_ = 0;
};

}  // namespace raymap::record
