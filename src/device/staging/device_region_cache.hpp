// SPDX-License-Identifier: BSD-3-Clause
// The host-side table of a device region cache: which region each device slot holds, which slots
// the batch being planned uses, and which slot to give up next. API-agnostic (OpenCL and CUDA).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "src/core/vec3.hpp"
#include "src/map/region_index.hpp"

namespace raymap::gpu {

/// @brief Slot bookkeeping of a device region cache: device memory is cut into `capacity` fixed
/// slots, one region each (per layer); this class decides which slot a region goes to.
///
/// Policy: a region the current batch needs is placed in its slot if resident (a hit), else in a
/// free slot, else in the least recently used slot whose region the current batch does not use
/// (an eviction: the caller downloads that region to the host store before reusing the slot).
/// When every slot holds a region of the current batch, place() fails and the caller submits the
/// batch so far and starts a new one. LRU order is an intrusive list over slots, so every
/// operation is O(1) expected.
///
/// Thread-safety: none (one integrating thread). Real-time: allocation-free after construction.
class DeviceRegionCache {
 public:
  static constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

  /// @brief A slot's region: host slot it mirrors, last batch that used it, dirty since sync.
  struct Entry {
    Vec3i region{};
    std::uint32_t host_slot = kNoSlot;
    std::uint64_t batch = 0;
    bool used = false;
    bool dirty = false;  ///< the device copy is newer than the host store
    /// Its sample layers (written only where a sample lands: sampleLayer() in staged_backend.hpp)
    /// are newer too: a batch put a sample in the region, or the region was created on the device.
    /// A dirty region without it is downloaded without those layers.
    bool samples_dirty = false;
  };

  /// @brief Where a region was placed and what the caller must move first.
  struct Placement {
    std::uint32_t slot = kNoSlot;
    bool resident = false;  ///< already on the device: nothing to upload
    bool evicted = false;   ///< the slot held `evicted_entry`, which must be downloaded if dirty
    Entry evicted_entry{};
  };

  explicit DeviceRegionCache(std::uint32_t capacity);

  std::uint32_t capacity() const noexcept { return static_cast<std::uint32_t>(entries_.size()); }
  std::uint32_t size() const noexcept { return size_; }

  /// @brief Starts a new batch: regions placed from now on are pinned until the next call.
  void beginBatch() noexcept { ++batch_; }
  /// @brief Places `region` (held in host store slot `host_slot`) for the current batch; nullopt
  /// when every slot is pinned by the current batch. `write`: the batch will change it, so it is
  /// marked dirty (a reader, such as the height map, leaves a resident region's flag as it was
  /// and places a region it brings in clean).
  std::optional<Placement> place(Vec3i region, std::uint32_t host_slot, bool write = true) noexcept;
  /// @brief Device slot of a resident region, or kNoSlot.
  std::uint32_t find(Vec3i region) const noexcept;
  const Entry& entry(std::uint32_t slot) const noexcept { return entries_[slot]; }
  void markClean(std::uint32_t slot) noexcept {
    entries_[slot].dirty = false;
    entries_[slot].samples_dirty = false;
  }
  /// @brief A batch writes every layer of resident region `slot`, its sample layers included.
  void markSamplesWritten(std::uint32_t slot) noexcept {
    entries_[slot].dirty = true;
    entries_[slot].samples_dirty = true;
  }
  /// @brief Forgets a region without downloading it (its host region was recycled).
  void drop(std::uint32_t slot) noexcept;

  /// @brief Calls fn(slot, entry) for every resident region.
  template <class Fn>
  void forEachResident(Fn&& fn) const {
    for (std::uint32_t slot = 0; slot < capacity(); ++slot) {
      if (entries_[slot].used) {
        fn(slot, entries_[slot]);
      }
    }
  }

  /// @brief Counts a hit the caller resolved itself (a region it already placed in this batch).
  void noteHit() noexcept { ++hits_; }
  /// @brief Counts `count` such hits at once (a device-planned batch's further spans in a region).
  void noteHits(std::uint64_t count) noexcept { hits_ += count; }
  std::uint64_t hits() const noexcept { return hits_; }
  std::uint64_t misses() const noexcept { return misses_; }
  std::uint64_t evictions() const noexcept { return evictions_; }

 private:
  void unlink(std::uint32_t slot) noexcept;
  void pushBack(std::uint32_t slot) noexcept;  // most recently used end

  std::vector<Entry> entries_;
  std::vector<std::uint32_t> prev_;
  std::vector<std::uint32_t> next_;
  std::vector<std::uint32_t> free_;  // stack of unused slots
  std::uint32_t head_ = kNoSlot;     // least recently used
  std::uint32_t tail_ = kNoSlot;
  std::uint32_t size_ = 0;
  std::uint64_t batch_ = 1;
  RegionIndex index_;  // packed region -> slot
  std::uint64_t hits_ = 0;
  std::uint64_t misses_ = 0;
  std::uint64_t evictions_ = 0;
};

}  // namespace raymap::gpu
