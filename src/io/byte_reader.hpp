// SPDX-License-Identifier: BSD-3-Clause
// Buffered, streamed reading of a plain or gzip-compressed file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

namespace raymap::io {

/// @brief Reads a file front to back through one bounded buffer, so files larger than memory
/// work. gzip files (they start with the gzip magic) are decompressed on the fly, every member of
/// a multi-member file in turn (`cat a.gz b.gz`, as gzip -d reads it); data after the last member
/// that is not another member is an error naming its offset (zlib's gzread ignored it). Other
/// files are read as they are. Offers three
/// ways in: lines (headers, ASCII data), exact byte counts, and direct access to the buffered
/// bytes (zero-copy decoding of binary records). Every error message starts with the path.
/// Move-only; not thread-safe.
class ByteReader {
 public:
  /// Default size of the decoded-data buffer (zlib keeps its own buffers of about 3x this).
  static constexpr std::size_t kDefaultBufferBytes = std::size_t{1} << 20;

  /// @brief Opens `path` for reading.
  /// @param[in] buffer_bytes size of the decoded-data buffer; also the longest line readLine()
  /// accepts. At least 64 bytes.
  /// @return the reader, or kIo naming the path and the operating system's reason.
  static Result<ByteReader> open(const std::string& path,
                                 std::size_t buffer_bytes = kDefaultBufferBytes);

  ByteReader(ByteReader&& other) noexcept;
  ByteReader& operator=(ByteReader&& other) noexcept;
  ByteReader(const ByteReader&) = delete;
  ByteReader& operator=(const ByteReader&) = delete;
  ~ByteReader();

  const std::string& path() const noexcept { return path_; }
  /// @brief True when the file is gzip-compressed (decoded on the fly).
  bool compressed() const noexcept { return inflater_ != nullptr; }
  /// @brief Size of the file on disk (compressed bytes for gzip), bytes; 0 when unknown.
  std::uint64_t fileBytes() const noexcept { return file_bytes_; }
  /// @brief Fraction of the file on disk consumed so far, 0 to 1 (compressed bytes for gzip;
  /// includes what sits decoded in the buffer, so it runs slightly ahead of the caller).
  double progress() const noexcept;
  /// @brief Decoded bytes handed to the caller so far (consumed, read or skipped).
  std::uint64_t position() const noexcept { return position_; }
  /// @brief Lines returned by readLine() so far: the 1-based number of the last line read.
  std::uint64_t lineNumber() const noexcept { return line_number_; }

  /// @brief The decoded bytes in the buffer that have not been consumed yet (may be empty).
  std::span<const std::byte> buffered() const noexcept;
  /// @brief Makes at least `bytes` contiguous decoded bytes available in the buffer, unless the
  /// data ends first; grows the buffer when `bytes` exceeds it.
  /// @return all buffered bytes: fewer than `bytes` only at the end of the data.
  Result<std::span<const std::byte>> ensure(std::size_t bytes);
  /// @brief Marks `bytes` buffered bytes as used. @pre bytes <= buffered().size()
  void consume(std::size_t bytes) noexcept;

  /// @brief Copies up to out.size() bytes; fewer only at the end of the data.
  Result<std::size_t> read(std::span<std::byte> out);
  /// @brief Copies exactly out.size() bytes or fails with kTruncated naming `what`.
  Expected<void, Error> readExact(std::span<std::byte> out, std::string_view what);
  /// @brief Skips up to `bytes` bytes; returns how many were skipped (fewer only at the end).
  Result<std::uint64_t> skip(std::uint64_t bytes);
  /// @brief True when no decoded byte is left.
  Result<bool> atEnd();

  /// @brief Reads the next line (without its "\n" or "\r\n") into `line`, a view into the buffer
  /// valid until the next call on this reader. The last line may lack its newline.
  /// @return false at the end of the data; kFormat when a line is longer than the buffer.
  Result<bool> readLine(std::string_view& line);

 private:
  struct Inflater;  // zlib's stream state and the compressed input (gzip files only)

  ByteReader(std::string path, std::FILE* file, std::unique_ptr<std::byte[]> buffer,
             std::size_t capacity, std::uint64_t file_bytes) noexcept;
  /// Moves the unconsumed bytes to the front and reads more behind them. Sets eof_ at the end.
  Expected<void, Error> refill();
  /// refill() for a gzip file: decodes into the buffer's free space.
  Expected<void, Error> inflateMore();
  /// Reads more compressed input behind what inflate has not used yet.
  Expected<void, Error> readInput();
  /// Consumes up to `bytes`, handing each buffered piece to sink(data, offset so far, size);
  /// returns how many were consumed (fewer at the end of the data). The loop of read and skip.
  template <class Sink>
  Result<std::uint64_t> drain(std::uint64_t bytes, Sink&& sink);
  void close() noexcept;

  std::string path_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<Inflater> inflater_;  // null for a plain file
  std::unique_ptr<std::byte[]> buffer_;
  std::size_t capacity_ = 0;
  std::size_t begin_ = 0;  // first unconsumed byte in buffer_
  std::size_t end_ = 0;    // one past the last decoded byte in buffer_
  bool eof_ = false;       // the file has no more bytes to decode
  std::uint64_t file_bytes_ = 0;
  std::uint64_t raw_read_ = 0;  // bytes read from the file so far
  std::uint64_t position_ = 0;
  std::uint64_t line_number_ = 0;
};

}  // namespace raymap::io
