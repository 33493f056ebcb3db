// SPDX-License-Identifier: BSD-3-Clause
// ByteReader: one buffer over a plain file, or over zlib's inflate for gzip files (every member,
// and nothing but members, to the end of the file).
#include "src/io/byte_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <optional>
#include <system_error>
#include <utility>

#include <zlib.h>

namespace raymap::io {
namespace {

constexpr std::size_t kMinBufferBytes = 64;
/// Compressed bytes read per call; the decoded buffer's size bounds what one refill decodes.
constexpr std::size_t kMaxInputBytes = std::size_t{1} << 20;
// RFC 1952: every gzip member starts with these two bytes.
constexpr unsigned char kGzipMagic0 = 0x1f;
constexpr unsigned char kGzipMagic1 = 0x8b;
/// inflateInit2's window bits: 15 (the largest window) + 16 (gzip wrapper only, no zlib or raw).
constexpr int kGzipWindowBits = 15 + 16;

std::string systemReason(int error_number) { return std::generic_category().message(error_number); }

}  // namespace

/// zlib's stream lives on the heap: zlib keeps a pointer back to it, so it must not move when the
/// ByteReader does.
struct ByteReader::Inflater {
  z_stream stream{};
  std::unique_ptr<Bytef[]> input;
  std::size_t input_capacity = 0;
  bool input_eof = false;     // the file has no more compressed bytes
  bool member_ended = false;  // inflate finished a member; what follows decides what is next
  bool initialised = false;

  ~Inflater() {
    if (initialised) {
      ::inflateEnd(&stream);
    }
  }
};

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
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    return fail(ErrorCode::kIo, path + ": cannot open: " + systemReason(errno));
  }
  std::unique_ptr<std::byte[]> buffer(new (std::nothrow) std::byte[buffer_bytes]);
  if (buffer == nullptr) {
    static_cast<void>(std::fclose(file));
    return fail(ErrorCode::kCapacity, path + ": cannot allocate a read buffer of " +
                                          std::to_string(buffer_bytes) + " bytes");
  }
  ByteReader reader(path, file, std::move(buffer), buffer_bytes,
                    size_error ? 0 : static_cast<std::uint64_t>(size));
  // The first two bytes tell gzip from plain data. They are read as plain data; a gzip file's
  // go to the inflater instead.
  std::byte* const start = reader.buffer_.get();
  std::size_t got = 0;
  while (got < 2) {
    const std::size_t n = std::fread(start + got, 1, 2 - got, file);
    if (n == 0) {
      if (std::ferror(file) != 0) {
        return fail(ErrorCode::kIo, path + ": read error: " + systemReason(errno));
      }
      break;
    }
    got += n;
  }
  reader.raw_read_ = got;
  const bool gzip = got == 2 && std::to_integer<unsigned char>(start[0]) == kGzipMagic0 &&
                    std::to_integer<unsigned char>(start[1]) == kGzipMagic1;
  if (!gzip) {
    reader.end_ = got;
    reader.eof_ = got < 2;
    return reader;
  }
  auto inflater = std::make_unique<Inflater>();
  inflater->input_capacity = std::min(buffer_bytes, kMaxInputBytes);
  inflater->input.reset(new (std::nothrow) Bytef[inflater->input_capacity]);
  if (inflater->input == nullptr) {
    return fail(ErrorCode::kCapacity, path + ": cannot allocate a read buffer of " +
                                          std::to_string(inflater->input_capacity) + " bytes");
  }
  if (::inflateInit2(&inflater->stream, kGzipWindowBits) != Z_OK) {
    return fail(ErrorCode::kCapacity, path + ": cannot start the gzip decoder (out of memory)");
  }
  inflater->initialised = true;
  std::memcpy(inflater->input.get(), start, got);
  inflater->stream.next_in = inflater->input.get();
  inflater->stream.avail_in = static_cast<uInt>(got);
  reader.inflater_ = std::move(inflater);
  return reader;
}

ByteReader::ByteReader(std::string path, std::FILE* file, std::unique_ptr<std::byte[]> buffer,
                       std::size_t capacity, std::uint64_t file_bytes) noexcept
    : path_(std::move(path)),
      file_(file),
      buffer_(std::move(buffer)),
      capacity_(capacity),
      file_bytes_(file_bytes) {}

ByteReader::ByteReader(ByteReader&& other) noexcept
    : path_(std::move(other.path_)),
      file_(std::exchange(other.file_, nullptr)),
      inflater_(std::move(other.inflater_)),
      buffer_(std::move(other.buffer_)),
      capacity_(std::exchange(other.capacity_, 0)),
      begin_(std::exchange(other.begin_, 0)),
      end_(std::exchange(other.end_, 0)),
      eof_(std::exchange(other.eof_, true)),
      file_bytes_(other.file_bytes_),
      raw_read_(other.raw_read_),
      position_(other.position_),
      line_number_(other.line_number_) {}

ByteReader& ByteReader::operator=(ByteReader&& other) noexcept {
  if (this != &other) {
    close();
    path_ = std::move(other.path_);
    file_ = std::exchange(other.file_, nullptr);
    inflater_ = std::move(other.inflater_);
    buffer_ = std::move(other.buffer_);
    capacity_ = std::exchange(other.capacity_, 0);
    begin_ = std::exchange(other.begin_, 0);
    end_ = std::exchange(other.end_, 0);
    eof_ = std::exchange(other.eof_, true);
    file_bytes_ = other.file_bytes_;
    raw_read_ = other.raw_read_;
    position_ = other.position_;
    line_number_ = other.line_number_;
  }
  return *this;
}

ByteReader::~ByteReader() { close(); }

void ByteReader::close() noexcept {
  if (file_ != nullptr) {
    static_cast<void>(std::fclose(file_));
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
  // The compressed bytes inflate has used (for a plain file, every byte read).
  const std::uint64_t unused = inflater_ ? inflater_->stream.avail_in : 0;
  const double fraction =
      static_cast<double>(raw_read_ - unused) / static_cast<double>(file_bytes_);
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
  if (end_ == capacity_) {
    return {};
  }
  if (inflater_) {
    return inflateMore();
  }
  const std::size_t room = capacity_ - end_;
  const std::size_t got = std::fread(buffer_.get() + end_, 1, room, file_);
  end_ += got;
  raw_read_ += got;
  if (got < room) {
    eof_ = true;
    if (std::ferror(file_) != 0) {
      return fail(ErrorCode::kIo, path_ + ": read error: " + systemReason(errno));
    }
  }
  return {};
}

Expected<void, Error> ByteReader::readInput() {
  Inflater& z = *inflater_;
  const std::size_t kept = z.stream.avail_in;
  if (kept > 0 && z.stream.next_in != z.input.get()) {
    std::memmove(z.input.get(), z.stream.next_in, kept);
  }
  const std::size_t got = std::fread(z.input.get() + kept, 1, z.input_capacity - kept, file_);
  raw_read_ += got;
  z.stream.next_in = z.input.get();
  z.stream.avail_in = static_cast<uInt>(kept + got);
  if (got < z.input_capacity - kept) {
    z.input_eof = true;
    if (std::ferror(file_) != 0) {
      return fail(ErrorCode::kIo, path_ + ": read error: " + systemReason(errno));
    }
  }
  return {};
}

Expected<void, Error> ByteReader::inflateMore() {
  Inflater& z = *inflater_;
  // inflate takes a uInt count: stay well inside it.
  const std::size_t room = std::min<std::size_t>(capacity_ - end_, std::size_t{1} << 30);
  z.stream.next_out = reinterpret_cast<Bytef*>(buffer_.get() + end_);
  z.stream.avail_out = static_cast<uInt>(room);
  std::optional<Error> error;
  while (z.stream.avail_out > 0 && !error) {
    if (z.member_ended) {
      // RFC 1952 allows members back to back; anything else after a member is not gzip data.
      while (z.stream.avail_in < 2 && !z.input_eof && !error) {
        if (auto read = readInput(); !read) {
          error = read.error();
        }
      }
      if (error) {
        break;
      }
      if (z.stream.avail_in == 0) {
        eof_ = true;
        break;
      }
      if (z.stream.avail_in >= 2 && z.stream.next_in[0] == kGzipMagic0 &&
          z.stream.next_in[1] == kGzipMagic1) {
        ::inflateReset(&z.stream);
        z.member_ended = false;
        continue;
      }
      const std::uint64_t offset = raw_read_ - z.stream.avail_in;
      const std::uint64_t trailing =
          file_bytes_ > offset ? file_bytes_ - offset : std::uint64_t{z.stream.avail_in};
      eof_ = true;
      // kCorrupt, not kFormat: the PLY header parser reads a kFormat error on its first line
      // as "not a PLY file", and this file is a gzip file damaged at its end.
      error = Error{ErrorCode::kCorrupt,
                    path_ + ": " + std::to_string(trailing) +
                        " bytes of unexpected data after the gzip stream, at byte " +
                        std::to_string(offset) + " (not another gzip member)"};
      break;
    }
    if (z.stream.avail_in == 0 && !z.input_eof) {
      if (auto read = readInput(); !read) {
        error = read.error();
        break;
      }
    }
    const int status = ::inflate(&z.stream, Z_NO_FLUSH);
    if (status == Z_STREAM_END) {
      z.member_ended = true;
    } else if (status == Z_BUF_ERROR && z.stream.avail_in == 0 && z.input_eof) {
      // No progress possible and no input left: the file stops inside a member.
      eof_ = true;
      error = Error{ErrorCode::kTruncated,
                    path_ + ": truncated: the gzip stream ends before its end marker"};
    } else if (status != Z_OK && status != Z_BUF_ERROR) {
      eof_ = true;
      error = Error{
          ErrorCode::kCorrupt,
          path_ + ": corrupt gzip data at byte " + std::to_string(raw_read_ - z.stream.avail_in) +
              ": " +
              (z.stream.msg != nullptr ? z.stream.msg : "zlib error " + std::to_string(status))};
    }
  }
  end_ += room - z.stream.avail_out;
  if (error) {
    return Unexpected(std::move(*error));
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
