// SPDX-License-Identifier: BSD-3-Clause
// PageBlock on Linux: anonymous private mappings.
#include "platform/memory.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include <sys/mman.h>
#include <unistd.h>

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
    return fail(ErrorCode::kCapacity, "cannot reserve " + std::to_string(rounded) +
                                          " bytes of memory: " + std::strerror(errno));
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

void PageBlock::prefault() noexcept {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  for (std::size_t offset = 0; offset < size_; offset += page) {
    // A volatile write so the compiler keeps it; the page already holds zero.
    *static_cast<volatile std::byte*>(data_ + offset) = std::byte{0};
  }
}

}  // namespace raymap::platform
