// SPDX-License-Identifier: BSD-3-Clause
// PageBlock on Linux: anonymous private mappings.
#include "platform/memory.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <utility>

#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include "platform/errno_text.hpp"

namespace raymap::platform {

Result<PageBlock> PageBlock::create(std::size_t bytes) {
  if (bytes == 0) {
    return PageBlock();
  }
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t rounded = (bytes + page - 1) / page * page;
  void* p = mmap(nullptr, rounded, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) {
    return fail(ErrorCode::kCapacity,
                "cannot reserve " + std::to_string(rounded) + " bytes of memory: " +
                    // NOLINTNEXTLINE(concurrency-mt-unsafe): start-up only, before any thread
                    platform::errnoText(errno));
  }
  return PageBlock(static_cast<std::byte*>(p), rounded);
}

PageBlock::PageBlock(PageBlock&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}

PageBlock& PageBlock::operator=(PageBlock&& other) noexcept {
  if (this != &other) {
    reset();
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
  }
  return *this;
}

PageBlock::~PageBlock() { reset(); }

void PageBlock::reset() noexcept {
  if (data_ != nullptr) {
    munmap(data_, size_);
    data_ = nullptr;
    size_ = 0;
  }
}

void PageBlock::adviseHugePages(std::size_t offset, std::size_t bytes) noexcept {
#if defined(MADV_HUGEPAGE)
  // madvise wants a page-aligned start: round the range inwards to whole pages.
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t begin = (offset + page - 1) / page * page;
  const std::size_t end = std::min(offset + bytes, size_) / page * page;
  if (data_ != nullptr && begin < end) {
    (void)madvise(data_ + begin, end - begin, MADV_HUGEPAGE);
  }
#else
  (void)offset;
  (void)bytes;
#endif
}

bool PageBlock::discard(std::size_t offset, std::size_t bytes) noexcept {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  if (data_ == nullptr || offset % page != 0 || bytes % page != 0 || offset + bytes > size_) {
    return false;
  }
  // Private anonymous memory: after MADV_DONTNEED the next read finds the zero page.
  return madvise(data_ + offset, bytes, MADV_DONTNEED) == 0;
}

void PageBlock::prefault() noexcept {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  for (std::size_t offset = 0; offset < size_; offset += page) {
    // A volatile write so the compiler keeps it; the page already holds zero.
    *static_cast<volatile std::byte*>(data_ + offset) = std::byte{0};
  }
}

namespace {

/// The first word of a file as a whole number (memory.max, memory.current); false for "max"
/// (no limit) or when it cannot be read.
bool readNumber(const std::string& path, std::uint64_t* out) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word.empty() || word.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  *out = std::stoull(word);
  return true;
}

}  // namespace

MemoryLimit availableMemory() {
  MemoryLimit limit;
  limit.bytes = std::numeric_limits<std::uint64_t>::max();
  limit.source = "no limit could be read";
  const auto consider = [&](std::uint64_t bytes, std::string source) {
    if (bytes < limit.bytes) {
      limit.bytes = bytes;
      limit.source = std::move(source);
    }
  };
  {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    std::uint64_t kib = 0;
    std::string unit;
    while (meminfo >> key >> kib >> unit) {
      if (key == "MemAvailable:") {
        consider(kib * 1024, "MemAvailable in /proc/meminfo");
        break;
      }
    }
  }
  rlimit as{};
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    consider(static_cast<std::uint64_t>(as.rlim_cur), "RLIMIT_AS (ulimit -v)");
  }
  // cgroup v2: "0::/path" in /proc/self/cgroup; the limit is that folder's memory.max.
  std::ifstream cgroup("/proc/self/cgroup");
  std::string line;
  while (std::getline(cgroup, line)) {
    if (line.rfind("0::", 0) != 0) {
      continue;
    }
    const std::string dir = "/sys/fs/cgroup" + line.substr(3);
    std::uint64_t max = 0;
    std::uint64_t current = 0;
    if (readNumber(dir + "/memory.max", &max)) {
      (void)readNumber(dir + "/memory.current", &current);
      consider(max > current ? max - current : 0, "cgroup memory.max (" + dir + ")");
    }
  }
  return limit;
}

}  // namespace raymap::platform
