// SPDX-License-Identifier: BSD-3-Clause
// RecordLogWriter: writev(2) per record into `<path>.partial`; END, fsync and rename on close.
#include "src/record/record_log_writer.hpp"

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <system_error>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include "src/core/crc32.hpp"
#include "src/record/detail/record_codec.hpp"

namespace raymap::record {
namespace {

std::string systemReason(int error_number) { return std::generic_category().message(error_number); }

std::int64_t wallClockNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

constexpr std::size_t kMaxStringBytes = std::numeric_limits<std::uint16_t>::max();

/// Flushes the directory entry of a rename to disk. Best effort: some file systems refuse fsync
/// on a directory (EINVAL), and the data itself is already safe by then.
void syncDirectoryOf(const std::string& path) {
  // (Initialised once, not assigned: GCC 12 at -O3 flags `dir = "."` with a false -Wrestrict.)
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  const std::string dir = parent.empty() ? std::string(".") : parent.string();
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    static_cast<void>(::fsync(fd));
    static_cast<void>(::close(fd));
  }
}

}  // namespace

Result<std::unique_ptr<RecordLogWriter>> RecordLogWriter::create(const std::string& path) {
  if (path.empty()) {
    return fail(ErrorCode::kInvalidArgument, "record log path is empty");
  }
  std::string partial = path + ".partial";
  // O_EXCL: an existing .partial is an interrupted recording, possibly the only copy of it.
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int error_number = errno;
    if (error_number == EEXIST) {
      return fail(ErrorCode::kIo, "cannot record to '" + path + "': '" + partial +
                                      "' exists (an interrupted recording?); move it away first");
    }
    return fail(ErrorCode::kIo, "cannot record to '" + path + "': cannot create '" + partial +
                                    "': " + systemReason(error_number));
  }
  std::unique_ptr<RecordLogWriter> writer(new RecordLogWriter(path, std::move(partial), fd));
  const auto header = detail::encodeFileHeader(wallClockNs());
  const std::array<std::span<const std::byte>, 1> parts{std::span<const std::byte>(header)};
  if (auto written = writer->writeAll(parts, "the file header"); !written) {
    // Nothing worth keeping was written: do not leave a .partial that blocks the next attempt.
    static_cast<void>(::unlink(writer->partial_path_.c_str()));
    return Unexpected(std::move(written).error());
  }
  return writer;
}

RecordLogWriter::RecordLogWriter(std::string path, std::string partial_path, int fd) noexcept
    : path_(std::move(path)), partial_path_(std::move(partial_path)), fd_(fd) {}

RecordLogWriter::~RecordLogWriter() {
  if (fd_ >= 0) {
    static_cast<void>(::close(fd_));  // the records are in the page cache already
  }
}

const char* RecordLogWriter::unusableReason() const noexcept {
  if (closed_) {
    return "the log is already closed";
  }
  if (broken_) {
    return "an earlier write failed and the file could not be cut back to its last record";
  }
  return nullptr;
}

Result<void> RecordLogWriter::writeAll(std::span<const std::span<const std::byte>> parts,
                                       const char* what) {
  std::array<iovec, kMaxPayloadParts + 1> iov{};
  RAYMAP_EXPECTS(parts.size() <= iov.size());
  std::size_t remaining = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): writev only reads; iovec is not const.
    iov[i].iov_base = const_cast<std::byte*>(parts[i].data());
    iov[i].iov_len = parts[i].size();
    remaining += parts[i].size();
  }
  const std::size_t total = remaining;
  std::size_t first = 0;
  while (remaining > 0) {
    const ssize_t n = ::writev(fd_, iov.data() + first, static_cast<int>(parts.size() - first));
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      // writev returning 0 for a non-empty request makes no progress: treat it like ENOSPC.
      const std::string reason = systemReason(n < 0 ? errno : ENOSPC);
      std::string message = "cannot write " + std::string(what) + " to '" + partial_path_ +
                            "' at byte offset " + std::to_string(bytes_) + ": " + reason;
      // Cut back to the last complete record, so the file stays readable to the end (a partial
      // record in the middle would read as corruption once later records follow it).
      if (::ftruncate(fd_, static_cast<off_t>(bytes_)) == 0 &&
          ::lseek(fd_, static_cast<off_t>(bytes_), SEEK_SET) == static_cast<off_t>(bytes_)) {
        message += " (the file is cut back to its last complete record)";
      } else {
        broken_ = true;
        message += " (and cutting the file back failed: " + systemReason(errno) + ")";
      }
      return fail(ErrorCode::kIo, std::move(message));
    }
    auto done = static_cast<std::size_t>(n);
    remaining -= done;
    while (first < parts.size() && done >= iov[first].iov_len) {
      done -= iov[first].iov_len;
      ++first;
    }
    if (first < parts.size()) {
      iov[first].iov_base = static_cast<std::byte*>(iov[first].iov_base) + done;
      iov[first].iov_len -= done;
    }
  }
  bytes_ += total;
  return {};
}

Result<void> RecordLogWriter::appendRecord(RecordKind kind,
                                           std::span<const std::span<const std::byte>> payload,
                                           const char* what) {
  RAYMAP_EXPECTS(payload.size() <= kMaxPayloadParts);
  std::size_t length = 0;
  for (const auto& part : payload) {
    length += part.size();
  }
  RAYMAP_EXPECTS(length <= kMaxPayloadBytes);
  const auto length32 = static_cast<std::uint32_t>(length);
  std::uint32_t crc = detail::recordCrcSeed(static_cast<std::uint32_t>(kind), length32);
  for (const auto& part : payload) {
    crc = crc32(crc, part);
  }
  std::array<std::byte, kRecordHeaderBytes> header{};
  detail::encodeRecordHeader(header.data(), kind, length32, crc);
  std::array<std::span<const std::byte>, kMaxPayloadParts + 1> parts{};
  parts[0] = header;
  for (std::size_t i = 0; i < payload.size(); ++i) {
    parts[i + 1] = payload[i];
  }
  return writeAll(std::span(parts).first(payload.size() + 1), what);
}

Result<std::uint32_t> RecordLogWriter::addTopic(const std::string& name, const std::string& type,
                                                LogReliability reliability,
                                                LogDurability durability) {
  const auto invalid = [&](const std::string& why) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot add topic '" + name + "' to '" + partial_path_ + "': " + why);
  };
  if (const char* reason = unusableReason()) {
    return invalid(reason);
  }
  if (name.empty()) {
    return invalid("the topic name is empty");
  }
  if (name.size() > kMaxStringBytes || type.size() > kMaxStringBytes) {
    return invalid("topic and type names are limited to 65535 bytes");
  }
  if (static_cast<std::uint8_t>(reliability) >
          static_cast<std::uint8_t>(LogReliability::kReliable) ||
      static_cast<std::uint8_t>(durability) >
          static_cast<std::uint8_t>(LogDurability::kTransientLocal)) {
    return invalid("unknown reliability or durability value");
  }
  if (topic_count_ == std::numeric_limits<std::uint32_t>::max()) {
    return fail(ErrorCode::kCapacity,
                "cannot add topic '" + name + "' to '" + partial_path_ + "': no topic ids left");
  }
  const LogTopic topic{topic_count_, name, type, reliability, durability};
  std::vector<std::byte> payload(detail::topicPayloadBytes(topic));
  detail::encodeTopicPayload(payload.data(), topic);
  const std::array<std::span<const std::byte>, 1> parts{std::span<const std::byte>(payload)};
  if (auto written = appendRecord(RecordKind::kTopic, parts, "a TOPIC record"); !written) {
    return Unexpected(std::move(written).error());
  }
  return topic_count_++;
}

Result<void> RecordLogWriter::write(std::uint32_t topic_id, std::int64_t receive_unix_ns,
                                    std::int64_t receive_monotonic_ns,
                                    std::int64_t source_timestamp_ns,
                                    std::span<const std::byte> cdr) {
  if (const char* reason = unusableReason()) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write a message to '" + partial_path_ + "': " + reason);
  }
  if (topic_id >= topic_count_) {
    return fail(ErrorCode::kInvalidArgument, "cannot write a message to '" + partial_path_ +
                                                 "': topic id " + std::to_string(topic_id) +
                                                 " was never added (" +
                                                 std::to_string(topic_count_) + " topics)");
  }
  if (cdr.size() > kMaxCdrBytes) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write a message to '" + partial_path_ + "': " + std::to_string(cdr.size()) +
                    " CDR bytes exceed the record limit of " + std::to_string(kMaxCdrBytes));
  }
  std::array<std::byte, kMessagePrefixBytes> prefix{};
  detail::encodeMessagePrefix(prefix.data(), topic_id, receive_unix_ns, receive_monotonic_ns,
                              source_timestamp_ns);
  const std::array<std::span<const std::byte>, 2> parts{std::span<const std::byte>(prefix), cdr};
  if (auto written = appendRecord(RecordKind::kMessage, parts, "a MESSAGE record"); !written) {
    return written;
  }
  ++messages_;
  return {};
}

Result<void> RecordLogWriter::close() {
  if (const char* reason = unusableReason()) {
    return fail(ErrorCode::kInvalidArgument, "cannot close '" + partial_path_ + "': " + reason);
  }
  std::array<std::byte, detail::kEndPayloadBytes> end{};
  detail::encodeEndPayload(end.data(), detail::EndRecord{messages_, wallClockNs()});
  const std::array<std::span<const std::byte>, 1> parts{std::span<const std::byte>(end)};
  auto written = appendRecord(RecordKind::kEnd, parts, "the END record");
  // From here on the writer is closed whatever happens: a failed close leaves the .partial file
  // exactly as a crash would, which readers handle.
  closed_ = true;
  if (!written) {
    static_cast<void>(::close(std::exchange(fd_, -1)));
    return written;
  }
  if (::fsync(fd_) != 0) {
    const std::string reason = systemReason(errno);
    static_cast<void>(::close(std::exchange(fd_, -1)));
    return fail(ErrorCode::kIo, "cannot flush '" + partial_path_ + "' to disk: " + reason);
  }
  if (::close(std::exchange(fd_, -1)) != 0) {
    return fail(ErrorCode::kIo, "cannot close '" + partial_path_ + "': " + systemReason(errno));
  }
  if (std::rename(partial_path_.c_str(), path_.c_str()) != 0) {
    return fail(ErrorCode::kIo, "cannot rename '" + partial_path_ + "' to '" + path_ +
                                    "': " + systemReason(errno) + " (the complete log stays in '" +
                                    partial_path_ + "')");
  }
  syncDirectoryOf(path_);
  return {};
}

}  // namespace raymap::record
