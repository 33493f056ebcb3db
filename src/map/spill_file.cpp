// SPDX-License-Identifier: BSD-3-Clause
// SpillFile: an unnamed append-only file of compressed regions (see spill_file.hpp).
#include "src/map/spill_file.hpp"

#include <array>
#include <cerrno>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/core/byte_order.hpp"
#include "src/core/crc32.hpp"

namespace raymap {
namespace {

constexpr std::uint32_t kRecordTag = 0x4C505352u;  // "RSPL" as a little-endian u32

}  // namespace

Result<SpillFile> SpillFile::create(const std::string& folder) {
  SpillFile file;
  file.description_ = "the spill file in " + folder;
  // An unnamed file: nothing to clean up after a crash. Some file systems lack O_TMPFILE (and
  // answer EOPNOTSUPP or EISDIR): then a named file, removed before it holds anything.
  int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
    std::string pattern = folder + "/.raymap-spill-XXXXXX";
    fd = ::mkostemp(pattern.data(), O_CLOEXEC);
    if (fd >= 0) {
      ::unlink(pattern.c_str());
    }
  }
  if (fd < 0) {
    const int error = errno;
    return fail(ErrorCode::kIo, "cannot create a spill file in " + folder + ": " +
                                    platform::errnoText(error) +
                                    " (map.spill_dir names a writable folder for regions that fit "
                                    "neither memory budget)");
  }
  file.fd_ = fd;
  return file;
}

SpillFile::SpillFile(SpillFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      end_(other.end_),
      garbage_bytes_(other.garbage_bytes_),
      description_(std::move(other.description_)) {}

SpillFile& SpillFile::operator=(SpillFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) {
      ::close(fd_);
    }
    fd_ = std::exchange(other.fd_, -1);
    end_ = other.end_;
    garbage_bytes_ = other.garbage_bytes_;
    description_ = std::move(other.description_);
  }
  return *this;
}

SpillFile::~SpillFile() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

Result<SpillRecord> SpillFile::append(std::uint64_t key, std::uint32_t raw_bytes,
                                      std::span<const std::byte> packed) {
  std::array<std::byte, kHeaderBytes> header{};
  const SpillRecord record{end_, static_cast<std::uint32_t>(packed.size())};
  storeLe(header.data(), kRecordTag);
  storeLe(header.data() + 4, key);
  storeLe(header.data() + 12, raw_bytes);
  storeLe(header.data() + 16, record.packed_bytes);
  storeLe(header.data() + 20, crc32(0, packed));
  storeLe(header.data() + 24, crc32(0, std::span(header).first(24)));
  std::uint64_t at = end_;
  for (std::span<const std::byte> part : {std::span<const std::byte>(header), packed}) {
    while (!part.empty()) {
      const ssize_t n = ::pwrite(fd_, part.data(), part.size(), static_cast<off_t>(at));
      if (n <= 0) {
        const int error = n < 0 ? errno : ENOSPC;
        if (n < 0 && error == EINTR) {
          continue;
        }
        // The end does not move: a later append overwrites the partial record.
        return fail(ErrorCode::kIo, description_ + ": writing " +
                                        std::to_string(kHeaderBytes + packed.size()) +
                                        " bytes at offset " + std::to_string(end_) +
                                        " failed: " + platform::errnoText(error));
      }
      part = part.subspan(static_cast<std::size_t>(n));
      at += static_cast<std::uint64_t>(n);
    }
  }
  end_ = at;
  return record;
}

Expected<void, Error> SpillFile::read(const SpillRecord& record, std::uint64_t key,
                                      std::uint32_t raw_bytes,
                                      std::vector<std::byte>& packed) const {
  const std::string where =
      description_ + ": the record at offset " + std::to_string(record.offset);
  std::array<std::byte, kHeaderBytes> header{};
  packed.resize(record.packed_bytes);
  std::uint64_t at = record.offset;
  for (std::span<std::byte> part : {std::span<std::byte>(header), std::span<std::byte>(packed)}) {
    while (!part.empty()) {
      const ssize_t n = ::pread(fd_, part.data(), part.size(), static_cast<off_t>(at));
      if (n < 0 && errno == EINTR) {
        continue;
      }
      if (n <= 0) {
        return fail(ErrorCode::kIo,
                    where + ": reading failed: " +
                        (n < 0 ? platform::errnoText(errno) : std::string("end of file")));
      }
      part = part.subspan(static_cast<std::size_t>(n));
      at += static_cast<std::uint64_t>(n);
    }
  }
  if (loadLe<std::uint32_t>(header.data()) != kRecordTag ||
      loadLe<std::uint32_t>(header.data() + 24) != crc32(0, std::span(header).first(24))) {
    return fail(ErrorCode::kCorrupt, where + ": damaged record header");
  }
  if (loadLe<std::uint64_t>(header.data() + 4) != key ||
      loadLe<std::uint32_t>(header.data() + 12) != raw_bytes ||
      loadLe<std::uint32_t>(header.data() + 16) != record.packed_bytes) {
    return fail(ErrorCode::kCorrupt, where + ": holds another region than the one expected");
  }
  if (loadLe<std::uint32_t>(header.data() + 20) != crc32(0, packed)) {
    return fail(ErrorCode::kCorrupt, where + ": payload checksum mismatch");
  }
  return {};
}

}  // namespace raymap
