// SPDX-License-Identifier: BSD-3-Clause
// RecordLogReader: header checks on open, then one record per step with its checksum verified.
#include "src/record/record_log_reader.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <utility>

#include <stdio.h>  // fseeko, fileno
#include <sys/stat.h>
#include <sys/types.h>

#include "src/core/byte_order.hpp"
#include "src/core/crc32.hpp"
#include "src/record/detail/record_codec.hpp"

namespace raymap::record {
namespace {

constexpr std::size_t kStdioBufferBytes = std::size_t{256} << 10;
/// The smallest header any version can have (magic, version, size, CRC) and a sanity bound on
/// the header size a newer version may declare, bytes.
constexpr std::uint32_t kMinHeaderBytes = 20;
constexpr std::uint32_t kMaxHeaderBytes = 4096;
/// A version beyond the current one by more than this is called what it more likely is: a
/// damaged or foreign file (with a matching checksum), not a future raymap's log.
constexpr std::uint32_t kPlausibleVersionsAhead = 16;

std::string systemReason(int error_number) { return std::generic_category().message(error_number); }

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { static_cast<void>(std::fclose(file)); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

std::string kindName(std::uint32_t kind) {
  switch (static_cast<RecordKind>(kind)) {
    case RecordKind::kTopic:
      return "TOPIC";
    case RecordKind::kMessage:
      return "MESSAGE";
    case RecordKind::kEnd:
      return "END";
  }
  return "kind " + std::to_string(kind);
}

}  // namespace

namespace {

/// Reads the file header (as many bytes as it declares) and checks the magic and its size.
Result<std::vector<std::byte>> readFileHeader(std::FILE* file, const std::string& path) {
  std::vector<std::byte> header(kFileHeaderBytes);
  std::size_t got = std::fread(header.data(), 1, header.size(), file);
  if (std::ferror(file) != 0) {
    return fail(ErrorCode::kIo, path + ": read error in the file header: " + systemReason(errno));
  }
  if (got == 0) {
    return fail(ErrorCode::kFormat, path + " is empty (0 bytes): not a raymap record log");
  }
  const std::size_t magic_bytes = std::min(got, kRecordLogMagic.size());
  if (std::memcmp(header.data(), kRecordLogMagic.data(), magic_bytes) != 0) {
    return fail(ErrorCode::kFormat, path +
                                        ": not a raymap record log: it does not start with the "
                                        "magic \"RMLOG\\r\\n\\x1a\"");
  }
  const auto truncated_header = [&](std::size_t needed) {
    return fail(ErrorCode::kTruncated, path + ": truncated in the file header (" +
                                           std::to_string(got) + " of " + std::to_string(needed) +
                                           " bytes)");
  };
  if (got < 16) {
    return truncated_header(kFileHeaderBytes);
  }
  const std::uint32_t header_bytes = loadLe<std::uint32_t>(header.data() + 12);
  if (header_bytes < kMinHeaderBytes || header_bytes > kMaxHeaderBytes) {
    return fail(ErrorCode::kCorrupt, path + ": impossible file header size " +
                                         std::to_string(header_bytes) + " (damaged file)");
  }
  if (header_bytes > got) {
    header.resize(header_bytes);
    got += std::fread(header.data() + got, 1, header_bytes - got, file);
    if (got < header_bytes) {
      return truncated_header(header_bytes);
    }
  }
  header.resize(header_bytes);
  return header;
}

/// Every version starts with magic, u32 version, u32 header size and ends its header with the
/// CRC-32 of the bytes before it (docs/record-format.md), so the checksum is checked first and a
/// damaged version field is reported as damage, not as a newer format. Then the version, and
/// the rest of a version-1 header.
Expected<void, Error> checkFileHeader(std::span<const std::byte> header, const std::string& path) {
  const std::uint32_t version = loadLe<std::uint32_t>(header.data() + 8);
  const auto header_bytes = static_cast<std::uint32_t>(header.size());
  const std::uint32_t stored_crc = loadLe<std::uint32_t>(header.data() + header_bytes - 4);
  const bool crc_ok = crc32(0, header.first(header_bytes - 4)) == stored_crc;
  const std::string versions_read =
      "versions 1 to " + std::to_string(kRecordLogVersion);  // every version so far is read
  if (!crc_ok) {
    // A damaged version field is damage, whatever number it now reads.
    if (version > kRecordLogVersion || version == 0) {
      return fail(ErrorCode::kCorrupt, path +
                                           ": damaged file header: its checksum does not match, "
                                           "and its version field reads " +
                                           std::to_string(version) +
                                           " (this raymap reads record-log " + versions_read + ")");
    }
    return fail(ErrorCode::kCorrupt, path + ": file header checksum mismatch (damaged file)");
  }
  if (version > kRecordLogVersion + kPlausibleVersionsAhead) {
    return fail(ErrorCode::kUnsupported,
                path + ": unsupported record-log version " + std::to_string(version) +
                    " (this raymap reads " + versions_read +
                    "); a version this far ahead is more likely a damaged or foreign file than "
                    "a newer raymap's");
  }
  if (version > kRecordLogVersion) {
    return fail(ErrorCode::kUnsupported, path + ": record-log version " + std::to_string(version) +
                                             " was written by a newer raymap; this one reads " +
                                             versions_read);
  }
  if (version == 0) {
    return fail(ErrorCode::kCorrupt, path + ": invalid record log format version 0");
  }
  if (header_bytes != kFileHeaderBytes) {
    return fail(ErrorCode::kCorrupt, path + ": version-1 file header declares " +
                                         std::to_string(header_bytes) + " bytes instead of " +
                                         std::to_string(kFileHeaderBytes));
  }
  if (const std::uint32_t flags = loadLe<std::uint32_t>(header.data() + 24); flags != 0) {
    return fail(ErrorCode::kUnsupported, path + ": file header flags " + std::to_string(flags) +
                                             " are unknown to this raymap");
  }
  return {};
}

}  // namespace

Result<std::unique_ptr<RecordLogReader>> RecordLogReader::open(const std::string& path) {
  std::error_code status_error;
  if (std::filesystem::is_directory(path, status_error)) {
    return fail(ErrorCode::kIo, path + ": cannot open: it is a directory");
  }
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (file == nullptr) {
    return fail(ErrorCode::kIo, path + ": cannot open: " + systemReason(errno));
  }
  // setvbuf must come before the first read. Header-sized reads then cost no system call each.
  std::unique_ptr<char[]> stdio_buffer(new char[kStdioBufferBytes]);
  if (std::setvbuf(file.get(), stdio_buffer.get(), _IOFBF, kStdioBufferBytes) != 0) {
    return fail(ErrorCode::kIo, path + ": cannot set up the read buffer");
  }
  auto header = readFileHeader(file.get(), path);
  if (!header) {
    return Unexpected(std::move(header).error());
  }
  if (auto ok = checkFileHeader(*header, path); !ok) {
    return Unexpected(ok.error());
  }
  const std::int64_t created = loadLe<std::int64_t>(header->data() + 16);
  std::unique_ptr<RecordLogReader> reader(
      new RecordLogReader(path, file.release(), std::move(stdio_buffer), header->size(), created));
  reader->refreshFileSize();
  return reader;
}

RecordLogReader::RecordLogReader(std::string path, std::FILE* file,
                                 std::unique_ptr<char[]> stdio_buffer, std::uint64_t header_bytes,
                                 std::int64_t created_unix_ns) noexcept
    : path_(std::move(path)),
      file_(file),
      stdio_buffer_(std::move(stdio_buffer)),
      header_bytes_(header_bytes),
      created_unix_ns_(created_unix_ns),
      offset_(header_bytes) {}

RecordLogReader::~RecordLogReader() {
  if (file_ != nullptr) {
    static_cast<void>(std::fclose(file_));
  }
}

const LogTopic* RecordLogReader::topic(std::uint32_t id) const noexcept {
  return id < topics_.size() ? &topics_[id] : nullptr;
}

double RecordLogReader::progress() const noexcept {
  if (finished_) {
    return 1.0;
  }
  if (file_bytes_ == 0) {
    return 0.0;
  }
  return std::clamp(static_cast<double>(offset_) / static_cast<double>(file_bytes_), 0.0, 1.0);
}

void RecordLogReader::refreshFileSize() noexcept {
  struct stat info {};
  if (::fstat(::fileno(file_), &info) == 0) {
    file_bytes_ = static_cast<std::uint64_t>(info.st_size);
  }
}

Result<void> RecordLogReader::rewind() {
  if (::fseeko(file_, static_cast<off_t>(header_bytes_), SEEK_SET) != 0) {
    return fail(ErrorCode::kIo, path_ + ": cannot rewind: " + systemReason(errno));
  }
  offset_ = header_bytes_;
  record_index_ = 0;
  messages_read_ = 0;
  declared_in_pass_ = 0;
  complete_ = false;
  finished_ = false;
  truncation_.reset();
  failure_.reset();
  refreshFileSize();
  return {};
}

Error RecordLogReader::recordError(ErrorCode code, std::uint64_t offset,
                                   const std::string& reason) {
  failure_ = Error{code, path_ + ": record " + std::to_string(record_index_) + " at byte offset " +
                             std::to_string(offset) + ": " + reason};
  return *failure_;
}

void RecordLogReader::truncateAt(std::uint64_t offset, std::string what) {
  truncation_ = LogTruncation{offset, messages_read_,
                              "record " + std::to_string(record_index_) + " at byte offset " +
                                  std::to_string(offset) + " is cut off: " + std::move(what)};
  finished_ = true;
}

Result<RecordLogReader::Fill> RecordLogReader::readExactly(std::byte* out, std::size_t size,
                                                           std::size_t& got) {
  got = 0;
  while (got < size) {
    const std::size_t n = std::fread(out + got, 1, size - got, file_);
    got += n;
    if (n == 0) {
      if (std::ferror(file_) != 0) {
        return Unexpected(
            recordError(ErrorCode::kIo, offset_, "read error: " + systemReason(errno)));
      }
      break;
    }
  }
  if (got == size) {
    return Fill::kAll;
  }
  return got == 0 ? Fill::kNone : Fill::kSome;
}

Result<bool> RecordLogReader::restIsZero() {
  std::array<std::byte, 4096> chunk{};
  for (;;) {
    const std::size_t n = std::fread(chunk.data(), 1, chunk.size(), file_);
    if (std::any_of(chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n),
                    [](std::byte b) { return b != std::byte{0}; })) {
      return false;
    }
    if (n < chunk.size()) {
      if (std::ferror(file_) != 0) {
        return Unexpected(
            recordError(ErrorCode::kIo, offset_, "read error: " + systemReason(errno)));
      }
      return true;
    }
  }
}

Result<bool> RecordLogReader::zeroHeader(std::uint64_t at) {
  // No record is all zeros (its CRC would not be 0). A zero-filled tail is what a file system
  // leaves when the size reached the disk and the data did not (power loss).
  auto zeros = restIsZero();
  if (!zeros) {
    return Unexpected(std::move(zeros).error());
  }
  if (*zeros) {
    refreshFileSize();
    truncateAt(at, "the file ends in " + std::to_string(file_bytes_ - at) +
                       " zero bytes (data lost before it reached the disk)");
    return false;
  }
  return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                "checksum mismatch (a zero record header before non-zero data: "
                                "damaged file)"));
}

Result<bool> RecordLogReader::readRecord(std::uint64_t at, std::uint32_t& kind,
                                         std::span<const std::byte>& payload) {
  std::array<std::byte, kRecordHeaderBytes> head{};
  std::size_t got = 0;
  auto filled = readExactly(head.data(), head.size(), got);
  if (!filled) {
    return Unexpected(std::move(filled).error());
  }
  if (*filled == Fill::kNone) {
    finished_ = true;  // a clean end between records: a recording without END, not a cut
    return false;
  }
  if (*filled == Fill::kSome) {
    truncateAt(at, "its header has " + std::to_string(got) + " of " +
                       std::to_string(kRecordHeaderBytes) + " bytes");
    return false;
  }
  kind = loadLe<std::uint32_t>(head.data());
  const std::uint32_t length = loadLe<std::uint32_t>(head.data() + 4);
  const std::uint32_t stored_crc = loadLe<std::uint32_t>(head.data() + 8);
  if (kind == 0 && length == 0 && stored_crc == 0) {
    return zeroHeader(at);
  }
  if (length > kMaxPayloadBytes) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "impossible payload length " + std::to_string(length) +
                                      " (the limit is " + std::to_string(kMaxPayloadBytes) +
                                      " bytes; damaged record header)"));
  }
  // A length beyond the end of the file is a cut-off record: say so without allocating for it
  // (the file may still be growing when it is a .partial being written).
  const std::uint64_t payload_at = at + kRecordHeaderBytes;
  if (payload_at + length > file_bytes_) {
    refreshFileSize();
  }
  if (payload_at + length > file_bytes_) {
    const std::uint64_t present = file_bytes_ > payload_at ? file_bytes_ - payload_at : 0;
    truncateAt(at, "its payload has " + std::to_string(present) + " of " + std::to_string(length) +
                       " bytes");
    return false;
  }
  if (payload_.size() < length) {
    payload_.resize(length);
  }
  filled = readExactly(payload_.data(), length, got);
  if (!filled) {
    return Unexpected(std::move(filled).error());
  }
  if (*filled != Fill::kAll) {  // the file shrank after fstat
    truncateAt(
        at, "its payload has " + std::to_string(got) + " of " + std::to_string(length) + " bytes");
    return false;
  }
  payload = std::span<const std::byte>(payload_.data(), length);
  if (crc32(detail::recordCrcSeed(kind, length), payload) != stored_crc) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "checksum mismatch in a " + kindName(kind) + " record of " +
                                      std::to_string(length) + " payload bytes (damaged file)"));
  }
  offset_ = payload_at + length;
  return true;
}

Expected<void, Error> RecordLogReader::readTopic(std::uint64_t at,
                                                 std::span<const std::byte> payload) {
  auto topic = detail::decodeTopicPayload(payload);
  if (!topic) {
    return Unexpected(
        recordError(ErrorCode::kCorrupt, at, "malformed TOPIC record: " + topic.error()));
  }
  if (topic->id != declared_in_pass_) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "TOPIC record declares id " + std::to_string(topic->id) +
                                      " where id " + std::to_string(declared_in_pass_) +
                                      " comes next (ids are given in order)"));
  }
  if (topic->id < topics_.size()) {
    // Read before a rewind(): the same file must declare the same topic again.
    if (*topic != topics_[topic->id]) {
      return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                    "TOPIC record for id " + std::to_string(topic->id) +
                                        " differs from the one read before rewind() (was the "
                                        "file replaced?)"));
    }
  } else {
    topics_.push_back(std::move(*topic));
  }
  ++declared_in_pass_;
  return {};
}

Result<LogMessage> RecordLogReader::readMessage(std::uint64_t at,
                                                std::span<const std::byte> payload) {
  if (payload.size() < kMessagePrefixBytes) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "MESSAGE payload of " + std::to_string(payload.size()) +
                                      " bytes is shorter than its " +
                                      std::to_string(kMessagePrefixBytes) + "-byte prefix"));
  }
  LogMessage message;
  message.topic_id = loadLe<std::uint32_t>(payload.data());
  if (message.topic_id >= declared_in_pass_) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "message on topic id " + std::to_string(message.topic_id) +
                                      ", which no earlier TOPIC record declares"));
  }
  message.receive_unix_ns = loadLe<std::int64_t>(payload.data() + 4);
  message.receive_monotonic_ns = loadLe<std::int64_t>(payload.data() + 12);
  message.source_timestamp_ns = loadLe<std::int64_t>(payload.data() + 20);
  message.cdr = payload.subspan(kMessagePrefixBytes);
  return message;
}

Expected<void, Error> RecordLogReader::readEnd(std::uint64_t at,
                                               std::span<const std::byte> payload) {
  auto end = detail::decodeEndPayload(payload);
  if (!end) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at, "malformed END record: " + end.error()));
  }
  if (end->message_count != messages_read_) {
    return Unexpected(recordError(ErrorCode::kCorrupt, at,
                                  "END record counts " + std::to_string(end->message_count) +
                                      " messages, but the log holds " +
                                      std::to_string(messages_read_)));
  }
  refreshFileSize();
  if (file_bytes_ > offset_) {
    return Unexpected(recordError(
        ErrorCode::kCorrupt, at,
        "the END record is followed by " + std::to_string(file_bytes_ - offset_) + " more bytes"));
  }
  return {};
}

Result<std::optional<LogMessage>> RecordLogReader::next() {
  if (failure_) {
    return Unexpected(*failure_);
  }
  if (finished_) {
    return std::optional<LogMessage>();
  }
  for (;;) {
    const std::uint64_t at = offset_;
    std::uint32_t kind = 0;
    std::span<const std::byte> payload;
    auto record = readRecord(at, kind, payload);
    if (!record) {
      return Unexpected(std::move(record).error());
    }
    if (!*record) {
      return std::optional<LogMessage>();  // the end, or a record cut off (truncation())
    }
    switch (static_cast<RecordKind>(kind)) {
      case RecordKind::kTopic:
        if (auto ok = readTopic(at, payload); !ok) {
          return Unexpected(ok.error());
        }
        break;
      case RecordKind::kMessage: {
        auto message = readMessage(at, payload);
        if (!message) {
          return Unexpected(std::move(message).error());
        }
        ++record_index_;
        ++messages_read_;
        return std::optional<LogMessage>(*message);
      }
      case RecordKind::kEnd:
        if (auto ok = readEnd(at, payload); !ok) {
          return Unexpected(ok.error());
        }
        ++record_index_;
        complete_ = true;
        finished_ = true;
        return std::optional<LogMessage>();
    }
    // A TOPIC record, or a kind this reader does not know (written by a newer raymap; its
    // checksum is good, so skipping it is safe): go on to the next record.
    ++record_index_;
  }
}

}  // namespace raymap::record
