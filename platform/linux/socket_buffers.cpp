// SPDX-License-Identifier: BSD-3-Clause
// UdpDrops from /proc/self/fd (socket:[inode]) and /proc/net/udp{,6} (inode and drops columns).
#include "platform/socket_buffers.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

namespace raymap::platform {
namespace {

/// Parses the unsigned decimal at `p` (skipping blanks first); advances `p` past it.
std::uint64_t readDecimal(const char*& p, const char* end) noexcept {
  while (p < end && (*p == ' ' || *p == '\t')) {
    ++p;
  }
  std::uint64_t value = 0;
  while (p < end && *p >= '0' && *p <= '9') {
    value = value * 10 + static_cast<std::uint64_t>(*p - '0');
    ++p;
  }
  return value;
}

/// Skips `n` blank-separated fields.
void skipFields(const char*& p, const char* end, int n) noexcept {
  for (int i = 0; i < n; ++i) {
    while (p < end && (*p == ' ' || *p == '\t')) {
      ++p;
    }
    while (p < end && *p != ' ' && *p != '\t' && *p != '\n') {
      ++p;
    }
  }
}

/// One line of /proc/net/udp: "sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref
/// pointer drops". Adds its drops to `sum` when its inode is one of `inodes`.
void addLine(const char* p, const char* end, const std::vector<std::uint64_t>& inodes,
             std::uint64_t& sum) noexcept {
  skipFields(p, end, 9);
  const std::uint64_t inode = readDecimal(p, end);
  if (inode == 0 || !std::binary_search(inodes.begin(), inodes.end(), inode)) {
    return;
  }
  skipFields(p, end, 2);  // ref, pointer
  sum += readDecimal(p, end);
}

/// Sums the drops of `inodes` in one /proc/net file, reading it in chunks of `buffer`.
std::uint64_t dropsIn(const char* path, const std::vector<std::uint64_t>& inodes,
                      std::vector<char>& buffer) noexcept {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return 0;
  }
  std::uint64_t sum = 0;
  std::size_t held = 0;  // bytes of an unfinished line kept at the buffer's start
  bool header = true;
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data() + held, buffer.size() - held);
    if (n <= 0) {
      break;
    }
    const char* p = buffer.data();
    const char* end = buffer.data() + held + static_cast<std::size_t>(n);
    for (;;) {
      const char* newline =
          static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
      if (newline == nullptr) {
        break;
      }
      if (!header) {
        addLine(p, newline, inodes, sum);
      }
      header = false;
      p = newline + 1;
    }
    held = static_cast<std::size_t>(end - p);
    if (held == buffer.size()) {
      held = 0;  // a line longer than the buffer: not a /proc/net/udp line
    }
    std::memmove(buffer.data(), p, held);
  }
  ::close(fd);
  return sum;
}

}  // namespace

std::uint64_t socketReceiveBufferCap() noexcept {
  const int fd = ::open("/proc/sys/net/core/rmem_max", O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return 0;
  }
  char text[32] = {};
  const ssize_t n = ::read(fd, text, sizeof(text) - 1);
  ::close(fd);
  if (n <= 0) {
    return 0;
  }
  const char* p = text;
  return readDecimal(p, text + n);
}

UdpDrops UdpDrops::ofThisProcess() {
  UdpDrops drops;
  drops.buffer_.resize(16384);
  DIR* dir = ::opendir("/proc/self/fd");
  if (dir == nullptr) {
    return drops;
  }
  // Every socket of the process: /proc/net/udp then tells which are UDP (others never match).
  // NOLINTNEXTLINE(concurrency-mt-unsafe): a DIR stream of our own, read by this thread alone
  while (const dirent* entry = ::readdir(dir)) {
    char target[64] = {};
    const std::string link = std::string("/proc/self/fd/") + entry->d_name;
    const ssize_t n = ::readlink(link.c_str(), target, sizeof(target) - 1);
    if (n > 9 && std::strncmp(target, "socket:[", 8) == 0) {
      drops.inodes_.push_back(std::strtoull(target + 8, nullptr, 10));
    }
  }
  ::closedir(dir);
  std::sort(drops.inodes_.begin(), drops.inodes_.end());
  drops.inodes_.erase(std::unique(drops.inodes_.begin(), drops.inodes_.end()), drops.inodes_.end());
  return drops;
}

std::uint64_t UdpDrops::total() noexcept {
  if (inodes_.empty()) {
    return 0;
  }
  return dropsIn("/proc/net/udp", inodes_, buffer_) + dropsIn("/proc/net/udp6", inodes_, buffer_);
}

}  // namespace raymap::platform
