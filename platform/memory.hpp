// SPDX-License-Identifier: BSD-3-Clause
// Large page-backed memory blocks for fixed pools (the region store, later device staging).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "raymap/error.hpp"

namespace raymap::platform {

/// @brief A block of zero-filled, page-aligned memory obtained from the OS in one piece.
/// Pages are only backed when first written (or when prefault() touches them), so a large pool
/// costs resident memory in proportion to what is used. Move-only owner.
/// Thread-safety: the object itself is not synchronised; the bytes are plain memory.
class PageBlock {
 public:
  PageBlock() = default;
  /// @brief Maps `bytes` (rounded up to whole pages). Fails with kCapacity when the OS refuses.
  static Result<PageBlock> create(std::size_t bytes);
  PageBlock(PageBlock&& other) noexcept;
  PageBlock& operator=(PageBlock&& other) noexcept;
  PageBlock(const PageBlock&) = delete;
  PageBlock& operator=(const PageBlock&) = delete;
  ~PageBlock();

  std::byte* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  /// @brief Asks for the bytes [offset, offset + bytes) to be backed by huge pages (2 MiB on
  /// x86-64 and arm64) where the OS offers them: fewer TLB misses for memory that is touched all
  /// over, at the price of making a whole huge page resident (and zeroed) on its first write.
  /// Advice only; a no-op where transparent huge pages are off.
  void adviseHugePages(std::size_t offset, std::size_t bytes) noexcept;
  /// @brief Writes every page once so later accesses never fault (for real-time users).
  void prefault() noexcept;
  /// @brief Gives the pages of [offset, offset + bytes) back to the OS: they read as zeros again
  /// and take no memory until written. Only whole pages: returns false (and does nothing) when
  /// the range does not start and end on page boundaries, or the OS refuses.
  bool discard(std::size_t offset, std::size_t bytes) noexcept;

 private:
  PageBlock(std::byte* data, std::size_t size) noexcept : data_(data), size_(size) {}
  void reset() noexcept;

  std::byte* data_ = nullptr;
  std::size_t size_ = 0;
};

/// @brief How much memory a process starting now can count on, and what sets that bound.
struct MemoryLimit {
  std::uint64_t bytes = 0;  ///< the smallest of the bounds below that applies
  std::string source;  ///< e.g. "MemAvailable in /proc/meminfo", "RLIMIT_AS", "cgroup memory.max"
};

/// @brief The smallest of: MemAvailable (/proc/meminfo), RLIMIT_AS (soft, when finite), and the
/// cgroup v2 memory.max of this process's cgroup less its memory.current (when finite). Start-up
/// only (reads files; allocates). Bounds it cannot read are left out; with none, bytes is
/// UINT64_MAX and source says so.
MemoryLimit availableMemory();

}  // namespace raymap::platform
