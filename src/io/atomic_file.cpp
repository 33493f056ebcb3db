// SPDX-License-Identifier: BSD-3-Clause
// AtomicFileWriter: temporary file, fsync, rename.
#include "src/io/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <stdio.h>  // fseeko, fdopen
#include <sys/types.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/io/temp_files.hpp"

namespace raymap::io {

Result<AtomicFileWriter> AtomicFileWriter::open(const std::string& path) {
  if (path.empty()) {
    return fail(ErrorCode::kInvalidArgument, "output path is empty");
  }
  const bool in_place = isOwnTemporaryPath(path);
  std::string temp = in_place ? path : temporaryPathFor(path);
  if (!in_place) {
    // A file of this name is a leftover of an earlier process with this pid (only this process
    // makes the name now); it goes, so that O_EXCL below can insist on a new file.
    ::unlink(temp.c_str());
  }
  // O_NOFOLLOW: the name is predictable, so a symbolic link planted under it must not redirect
  // the write. O_EXCL for a name of our own making; a staged name was created by its owner.
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | O_NOFOLLOW | (in_place ? O_TRUNC : O_EXCL);
  const int fd = ::open(temp.c_str(), flags, 0666);
  if (fd < 0) {
    return fail(ErrorCode::kIo, "cannot write '" + path + "': " + platform::errnoText(errno));
  }
  std::FILE* file = ::fdopen(fd, "wb");
  if (file == nullptr) {
    const std::string reason = platform::errnoText(errno);
    ::close(fd);
    ::unlink(temp.c_str());
    return fail(ErrorCode::kIo, "cannot write '" + path + "': " + reason);
  }
  // Messages name the output the user asked for, not its temporary name.
  std::string destination = in_place ? path.substr(0, path.rfind(kTemporaryInfix)) : path;
  return AtomicFileWriter(std::move(destination), std::move(temp), file, in_place);
}

AtomicFileWriter::AtomicFileWriter(std::string path, std::string temp_path, std::FILE* file,
                                   bool in_place) noexcept
    : path_(std::move(path)), temp_path_(std::move(temp_path)), file_(file), in_place_(in_place) {}

AtomicFileWriter::AtomicFileWriter(AtomicFileWriter&& other) noexcept
    : path_(std::move(other.path_)),
      temp_path_(std::move(other.temp_path_)),
      file_(std::exchange(other.file_, nullptr)),
      written_(other.written_),
      in_place_(other.in_place_) {}

AtomicFileWriter& AtomicFileWriter::operator=(AtomicFileWriter&& other) noexcept {
  if (this != &other) {
    abandon();
    path_ = std::move(other.path_);
    temp_path_ = std::move(other.temp_path_);
    file_ = std::exchange(other.file_, nullptr);
    written_ = other.written_;
    in_place_ = other.in_place_;
  }
  return *this;
}

AtomicFileWriter::~AtomicFileWriter() { abandon(); }

void AtomicFileWriter::abandon() noexcept {
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
    std::remove(temp_path_.c_str());
  }
}

Expected<void, Error> AtomicFileWriter::write(std::span<const std::byte> bytes) {
  if (file_ == nullptr) {
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': file already closed");
  }
  if (bytes.empty()) {
    return {};
  }
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    const std::string reason = platform::errnoText(errno);
    abandon();
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': " + reason);
  }
  written_ += bytes.size();
  return {};
}

Expected<void, Error> AtomicFileWriter::write(const std::string& text) {
  return write(std::as_bytes(std::span<const char>(text.data(), text.size())));
}

Expected<void, Error> AtomicFileWriter::patch(std::size_t offset,
                                              std::span<const std::byte> bytes) {
  if (file_ == nullptr) {
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': file already closed");
  }
  if (offset > written_ || bytes.size() > written_ - offset) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot patch '" + path_ + "': bytes " + std::to_string(offset) + " to " +
                    std::to_string(offset + bytes.size()) + " are beyond the " +
                    std::to_string(written_) + " bytes written");
  }
  if (bytes.empty()) {
    return {};
  }
  // fseeko rather than fseek: off_t is 64-bit on 64-bit Linux (and on 32-bit targets built with
  // _FILE_OFFSET_BITS=64), where fseek's long would stop at 2 GiB.
  const bool ok = ::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) == 0 &&
                  std::fwrite(bytes.data(), 1, bytes.size(), file_) == bytes.size() &&
                  ::fseeko(file_, 0, SEEK_END) == 0;
  if (!ok) {
    const std::string reason = platform::errnoText(errno);
    abandon();
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': " + reason);
  }
  return {};
}

Expected<void, Error> AtomicFileWriter::patch(std::size_t offset, const std::string& text) {
  return patch(offset, std::as_bytes(std::span<const char>(text.data(), text.size())));
}

Expected<void, Error> AtomicFileWriter::commit() {
  if (file_ == nullptr) {
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': file already closed");
  }
  const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const std::string reason = platform::errnoText(errno);
  if (!flushed) {
    abandon();
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': " + reason);
  }
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!closed) {
    const std::string why = platform::errnoText(errno);
    std::remove(temp_path_.c_str());
    return fail(ErrorCode::kIo, "cannot write '" + path_ + "': " + why);
  }
  if (in_place_) {
    return {};  // the owner of the temporary name renames it with the other outputs
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const std::string why = platform::errnoText(errno);
    std::remove(temp_path_.c_str());
    return fail(ErrorCode::kIo, "cannot replace '" + path_ + "': " + why);
  }
  return {};
}

}  // namespace raymap::io
