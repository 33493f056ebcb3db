// SPDX-License-Identifier: BSD-3-Clause
// One worker's per-scan miss bits, keyed by region, for walks made before the regions exist.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "platform/page_array.hpp"
#include "src/map/region_key_set.hpp"
#include "src/map/region_slot_cache.hpp"

namespace raymap::detail {

/// @brief A worker's own miss planes (one bit per voxel of a region, as ScanBits' miss plane),
/// keyed by packed region coordinate (RegionStore::packCoord).
///
/// Why: per-scan occupancy misses commute (each voxel crossed in a scan takes at most one miss,
/// applied after the walks; src/map/scan_bits.hpp), so a worker can walk its rays to the
/// voxel in the parallel integrator's survey, before the batch's regions are created, and mark
/// its own planes; the regions' owners then or the workers' planes together. The spans never
/// have to be listed, counted and handed from worker to worker.
///
/// Memory: `plane_words` 64-bit words per region the worker's rays cross in a batch, page-backed
/// (platform::PageArray), grown by doubling; a plane is cleared when the batch first asks for it.
///
/// Thread-safety: one worker's object; not thread-safe. Between batches another thread may read
/// it (find()) once the worker is done. Real time: planeFor() allocates only when the batch
/// crosses more regions than any batch before it.
class MissPlanes {
 public:
  /// `max_regions`: at most this many planes per batch (the store's capacity);
  /// `plane_words`: words per plane (ScanBits::voxelWords()).
  MissPlanes(std::size_t max_regions, std::size_t plane_words);

  /// @brief The plane of region `key`, all clear the first time the batch asks for it; null when
  /// the batch already holds `max_regions` planes or the OS refuses memory to grow.
  std::uint64_t* planeFor(std::uint64_t key) noexcept {
    const std::size_t f = frontIndex(key);
    if (front_keys_[f] == key) {
      return plane(front_planes_[f]);
    }
    const std::uint32_t p = insert(key);
    if (p == kNoPlane) {
      return nullptr;
    }
    front_keys_[f] = key;
    front_planes_[f] = p;
    return plane(p);
  }

  /// @brief The plane of region `key` in this batch, or null when no ray of this worker crossed it.
  const std::uint64_t* find(std::uint64_t key) const noexcept;

  /// @brief Forgets every plane (their memory stays for the next batch).
  void clear() noexcept;

  /// @brief True when the batch holds `max_regions` planes (planeFor() returned null for want of
  /// room, not of memory).
  bool full() const noexcept { return keys_.full(); }

 private:
  static constexpr std::uint64_t kEmpty = RegionKeySet::kNoKey;
  static constexpr std::uint32_t kNoPlane = ~0u;
  static constexpr std::size_t kFrontEntries = 64;

  static std::size_t frontIndex(std::uint64_t key) noexcept {
    return static_cast<std::size_t>(regionKeyHash(key) >> 58);  // top 6 bits
  }
  std::uint64_t* plane(std::uint32_t p) noexcept {
    return words_.data() + (std::size_t{p} * plane_words_);
  }
  /// The plane of `key`, found or added (and cleared); kNoPlane when none can be added.
  std::uint32_t insert(std::uint64_t key) noexcept;

  std::size_t plane_words_;
  RegionKeySet keys_;
  std::vector<std::uint32_t> plane_;  // per bucket of keys_: its plane
  std::array<std::uint64_t, kFrontEntries> front_keys_{};
  std::array<std::uint32_t, kFrontEntries> front_planes_{};
  platform::PageArray<std::uint64_t> words_;
};

}  // namespace raymap::detail
