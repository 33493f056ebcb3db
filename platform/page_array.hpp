// SPDX-License-Identifier: BSD-3-Clause
// A growable array of plain elements in page-backed memory advised to use huge pages.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <type_traits>
#include <utility>

#include "platform/memory.hpp"

namespace raymap::platform {

/// @brief Scratch lists of plain elements that are written before they are read (the parallel
/// integrator's per-batch records): no element is ever initialised, and the block is advised to
/// use huge pages. A list first filled by a batch then costs one page fault per 2 MiB instead of
/// one per 4 KiB (on a paravirtualised VM a 4 KiB fault cost about 20 us: a fresh 88,000-ray scan
/// spent more time faulting its records in than integrating; docs/benchmarks.md), and the
/// pages a batch never reaches are never resident.
///
/// Move-only owner. Not thread-safe; the elements are plain memory (threads may write disjoint
/// elements). reserve() allocates and is not real-time safe; element access is.
template <class T>
class PageArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                "PageArray holds plain elements: copied with memcpy, never constructed");

 public:
  /// @brief Room for at least `n` elements; when it grows, the first `keep` elements are copied
  /// to the new block (the rest is lost). Returns false, and leaves the array as it was, when
  /// the OS refuses the memory.
  bool reserve(std::size_t n, std::size_t keep = 0) noexcept {
    if (n <= capacity_) {
      return true;
    }
    auto block = PageBlock::create(n * sizeof(T));
    if (!block) {
      return false;
    }
    block->adviseHugePages(0, block->size());
    if (const std::size_t kept = std::min(keep, capacity_); kept > 0) {
      std::memcpy(block->data(), block_.data(), kept * sizeof(T));
    }
    block_ = std::move(block).value();
    capacity_ = block_.size() / sizeof(T);
    return true;
  }
  std::size_t capacity() const noexcept { return capacity_; }
  T* data() noexcept { return reinterpret_cast<T*>(block_.data()); }
  const T* data() const noexcept { return reinterpret_cast<const T*>(block_.data()); }
  T& operator[](std::size_t i) noexcept { return data()[i]; }
  const T& operator[](std::size_t i) const noexcept { return data()[i]; }

 private:
  PageBlock block_;
  std::size_t capacity_ = 0;
};

}  // namespace raymap::platform
