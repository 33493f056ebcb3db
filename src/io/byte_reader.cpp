// SPDX-License-Identifier: BSD-3-Clause
// ByteReader: one buffer over zlib's gzread (which reads gzip and plain files alike).
#include "src/io/byte_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <system_error>
#include <utility>

#include <zlib.h>

namespace raymap::io {
namespace {

constexpr std::size_t kMinBufferBytes = 64;

std::string systemReason(int error_number) { return std::generic_category().message(error_number); }

}  // namespace

Result<ByteReader> ByteReader::open(const std::string& path, std::size_t buffer_bytes) {
  buffer_bytes = std::max(buffer_bytes, kMinBufferBytes);
  std::error_code status_error;
  const auto status = std::filesystem::status(path, status_error);
  if (status_error) {
    return fail(ErrorCode::kIo, path + ": cannot open: " + status_error.message());
  }
  if (std::filesystem::is_directory(status)) {
    return fail(ErrorCode::kIo, path + ": cannot open: it is a directory");
  }
  std::error_code size_error;
  const std::uintmax_t size = std::filesystem::file_size(path, size_error);
  errno = 0;
  gzFile file = ::gzopen(path.c_str(), "rb");
  if (file == nullptr) {
    const int error_number = errno;
    return fail(ErrorCode::kIo, path + ": cannot open: " +
                                    (error_number != 0 ? systemReason(error_number)
                                                       : std::string("out of memory")));
  }
  // zlib's own input/output buffers: large reads amortise the per-call overhead of inflate.
  const unsigned zlib_buffer = static_cast<unsigned>(
      std::min<std::size_t>(buffer_bytes, std::numeric_limits<unsigned>::max() / 4));
  if (::gzbuffer(file, zlib_buffer) != 0) {
    ::gzclose(file);
    return fail(ErrorCode::kIo, path + ": cannot set the read buffer size");
  }
  std::unique_ptr<std::byte[]> buffer(new (std::nothrow) std::byte[buffer_bytes]);
  if (buffer == nullptr) {
    ::gzclose(file);
    return fail(ErrorCode::kCapacity, path + ": cannot allocate a read buffer of " +
                                          std::to_string(buffer_bytes) + " bytes");
  }
  ByteReader reader(path, file, std::move(buffer), buffer_bytes,
                    size_error ? 0 : static_cast<std::uint64_t>(size), false);
  // gzdirect() is only meaningful once zlib has looked at the first bytes.
  if (auto filled = reader.refill(); !filled) {
    return Unexpected(std::move(filled).error());
  }
  reader.compressed_ = ::gzdirect(file) == 0;
  return reader;
}

ByteReader::ByteReader(std::string path, gzFile_s* file, std::unique_ptr<std::byte[]> buffer,
                       std::size_t capacity, std::uint64_t file_bytes, bool compressed) noexcept
    : path_(std::move(path)),
      file_(file),
      buffer_(std::move(buffer)),
      capacity_(capacity),
      compressed_(compressed),
      file_bytes_(file_bytes) {}

ByteReader::ByteReader(ByteReader&& other) noexcept
    : path_(std::move(other.path_)),
      file_(std::exchange(other.file_, nullptr)),
      buffer_(std::move(other.buffer_)),
      capacity_(std::exchange(other.capacity_, 0)),
      begin_(std::exchange(other.begin_, 0)),
      end_(std::exchange(other.end_, 0)),
      eof_(std::exchange(other.eof_, true)),
      compressed_(other.compressed_),
      file_bytes_(other.file_bytes_),
      position_(other.position_),
      line_number_(other.line_number_) {}

ByteReader& ByteReader::operator=(ByteReader&& other) noexcept {
  if (this != &other) {
    close();
    path_ = std::move(other.path_);
    file_ = std::exchange(other.file_, nullptr);
    buffer_ = std::move(other.buffer_);
    capacity_ = std::exchange(other.capacity_, 0);
    begin_ = std::exchange(other.begin_, 0);
    end_ = std::exchange(other.end_, 0);
    eof_ = std::exchange(other.eof_, true);
    compressed_ = other.compressed_;
    file_bytes_ = other.file_bytes_;
    position_ = other.position_;
    line_number_ = other.line_number_;
  }
  return *this;
}

ByteReader::~ByteReader() { close(); }

void ByteReader::close() noexcept {
  if (file_ != nullptr) {
    ::gzclose(file_);
    file_ = nullptr;
  }
}

double ByteReader::progress() const noexcept {
  if (eof_ && begin_ == end_) {
    return 1.0;
  }
  if (file_ == nullptr || file_bytes_ == 0) {
    return 0.0;
  }
  const z_off_t offset = ::gzoffset(file_);
  if (offset < 0) {
    return 0.0;
  }
  const double fraction = static_cast<double>(offset) / static_cast<double>(file_bytes_);
  return std::clamp(fraction, 0.0, 1.0);
}

std::span<const std::byte> ByteReader::buffered() const noexcept {
  return {buffer_.get() + begin_, end_ - begin_};
}

void ByteReader::consume(std::size_t bytes) noexcept {
  RAYMAP_EXPECTS(bytes <= end_ - begin_);
  begin_ += bytes;
  position_ += bytes;
}

Expected<void, Error> ByteReader::refill() {
  if (eof_ || file_ == nullptr) {
    eof_ = true;
    return {};
  }
  if (begin_ > 0) {
    std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  const std::size_t room = capacity_ - end_;
  if (room == 0) {
    return {};
  }
  // gzread takes an unsigned count and returns an int: stay well inside both.
  const unsigned request = static_cast<unsigned>(std::min<std::size_t>(room, 1u << 30));
  const int got = ::gzread(file_, buffer_.get() + end_, request);
  if (got < 0) {
    int zlib_error = Z_OK;
    const char* message = ::gzerror(file_, &zlib_error);
    const std::string reason = zlib_error == Z_ERRNO
                                   ? systemReason(errno)
                                   : std::string(message != nullptr ? message : "");
    return fail(ErrorCode::kIo, path_ + ": read error: " + reason);
  }
  end_ += static_cast<std::size_t>(got);
  if (static_cast<unsigned>(got) < request) {
    eof_ = true;
    int zlib_error = Z_OK;
    ::gzerror(file_, &zlib_error);
    if (zlib_error == Z_BUF_ERROR) {
      // zlib's way of saying the gzip stream stopped mid-way (the .gz file was cut short).
      return fail(ErrorCode::kTruncated,
                  path_ + ": truncated: the gzip stream ends before its end marker");
    }
    if (zlib_error != Z_OK) {
      return fail(ErrorCode::kCorrupt,
                  path_ + ": corrupt gzip data: " + std::string(::gzerror(file_, &zlib_error)));
    }
  }
  return {};
}

Result<std::span<const std::byte>> ByteReader::ensure(std::size_t bytes) {
  if (end_ - begin_ >= bytes) {
    return buffered();
  }
  if (bytes > capacity_) {
    std::unique_ptr<std::byte[]> larger(new (std::nothrow) std::byte[bytes]);
    if (larger == nullptr) {
      return fail(ErrorCode::kCapacity,
                  path_ + ": cannot allocate a read buffer of " + std::to_string(bytes) + " bytes");
    }
    std::memcpy(larger.get(), buffer_.get() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
    buffer_ = std::move(larger);
    capacity_ = bytes;
  }
  while (end_ - begin_ < bytes && !eof_) {
    if (auto filled = refill(); !filled) {
      return Unexpected(std::move(filled).error());
    }
  }
  return buffered();
}

template <class Sink>
Result<std::uint64_t> ByteReader::drain(std::uint64_t bytes, Sink&& sink) {
  std::uint64_t done = 0;
  while (done < bytes) {
    if (begin_ == end_) {
      if (eof_) {
        break;
      }
      if (auto filled = refill(); !filled) {
        return Unexpected(std::move(filled).error());
      }
      continue;
    }
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(bytes - done, end_ - begin_));
    sink(buffer_.get() + begin_, done, n);
    consume(n);
    done += n;
  }
  return done;
}

Result<std::size_t> ByteReader::read(std::span<std::byte> out) {
  auto copied = drain(out.size(), [&](const std::byte* from, std::uint64_t at, std::size_t n) {
    std::memcpy(out.data() + at, from, n);
  });
  if (!copied) {
    return Unexpected(std::move(copied).error());
  }
  return static_cast<std::size_t>(*copied);
}

Expected<void, Error> ByteReader::readExact(std::span<std::byte> out, std::string_view what) {
  const std::uint64_t at = position_;
  auto got = read(out);
  if (!got) {
    return Unexpected(std::move(got).error());
  }
  if (*got != out.size()) {
    return fail(ErrorCode::kTruncated, path_ + ": truncated: " + std::string(what) + " needs " +
                                           std::to_string(out.size()) + " bytes at byte " +
                                           std::to_string(at) + ", the data ends after " +
                                           std::to_string(*got));
  }
  return {};
}

Result<std::uint64_t> ByteReader::skip(std::uint64_t bytes) {
  return drain(bytes, [](const std::byte*, std::uint64_t, std::size_t) {});
}

Result<bool> ByteReader::atEnd() {
  if (begin_ == end_ && !eof_) {
    if (auto filled = refill(); !filled) {
      return Unexpected(std::move(filled).error());
    }
  }
  return begin_ == end_ && eof_;
}

Result<bool> ByteReader::readLine(std::string_view& line) {
  std::size_t searched = 0;  // bytes after begin_ already known to hold no newline
  for (;;) {
    const char* start = reinterpret_cast<const char*>(buffer_.get() + begin_);
    const std::size_t available = end_ - begin_;
    const void* newline = std::memchr(start + searched, '\n', available - searched);
    if (newline != nullptr) {
      const std::size_t length =
          static_cast<std::size_t>(static_cast<const char*>(newline) - start);
      line = std::string_view(start, length);
      consume(length + 1);
      break;
    }
    if (eof_) {
      if (available == 0) {
        line = {};
        return false;
      }
      line = std::string_view(start, available);
      consume(available);
      break;
    }
    if (available == capacity_) {
      return fail(ErrorCode::kFormat, path_ + ": line " + std::to_string(line_number_ + 1) +
                                          " is longer than " + std::to_string(capacity_) +
                                          " bytes");
    }
    searched = available;
    if (auto filled = refill(); !filled) {
      return Unexpected(std::move(filled).error());
    }
  }
  if (!line.empty() && line.back() == '\r') {
    line.remove_suffix(1);
  }
  ++line_number_;
  return true;
}

}  // namespace raymap::io
