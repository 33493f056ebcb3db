// SPDX-License-Identifier: BSD-3-Clause
// Fixed pool of region memory plus an open-addressing index from region coordinate to pool slot.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "raymap/error.hpp"

#include "platform/memory.hpp"
#include "src/core/vec3.hpp"
#include "src/map/layer_schema.hpp"
#include "src/map/region_index.hpp"

namespace raymap {

/// Why a region could not be stored (real-time path: a code, no message).
enum class StoreError : std::uint8_t {
  kFull,           ///< every slot holds a region
  kOutOfRange,     ///< the region coordinate is beyond RegionStore::kMaxRegionCoord
  kOutsideWindow,  ///< a rolling map was asked for a region outside its window
  kTierFailed,     ///< a global map's cold tiers failed (VoxelMap::tierFailure() says why)
};

const char* toString(StoreError error) noexcept;

/// @brief All region memory of a map: one page-backed pool cut into `capacity` slots, each slot
/// holding one contiguous array per layer, and a linear-probing hash index from region coordinate
/// to slot.
///
/// Design: memory is layer-major: layer L of slot S starts at
/// `pool + layer_offset[L] + S * layer_region_bytes[L]`, so one layer of all regions is one array
/// (what a device cache uploads). Everything is sized in create(); nothing is allocated afterwards.
/// A newly created region has every voxel at its layer's clear value (e.g. "unobserved").
/// The index is a RegionIndex (linear probing, backward-shift deletion, at most half full).
///
/// Thread-safety: find(), coordOf() and the layer accessors may run concurrently with each other.
/// findOrCreate(), release() and clear() need exclusive access (no concurrent readers).
/// Real-time: every member except create() is allocation-free and noexcept; find/findOrCreate are
/// O(1) expected.
class RegionStore {
 public:
  static constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;
  /// Largest |region coordinate| on any axis (coordinates are packed into 21 bits each).
  static constexpr std::int32_t kMaxRegionCoord = (1 << 20) - 1;
  /// packCoord(): 21 bits per axis, biased to be non-negative.
  static constexpr std::int32_t kCoordBias = 1 << 20;
  static constexpr std::uint64_t kCoordMask = (std::uint64_t{1} << 21) - 1;

  struct Config {
    LayerSchema schema;
    std::int32_t region_voxels = 32;
    std::uint32_t capacity = 0;  ///< regions
    bool prefault = false;       ///< touch all pages now (real-time users)
  };

  RegionStore() = default;
  static Result<RegionStore> create(const Config& config);
  RegionStore(RegionStore&&) noexcept = default;
  RegionStore& operator=(RegionStore&&) noexcept = default;
  RegionStore(const RegionStore&) = delete;
  RegionStore& operator=(const RegionStore&) = delete;

  std::uint32_t capacity() const noexcept { return capacity_; }
  std::uint32_t size() const noexcept { return size_; }
  const LayerSchema& schema() const noexcept { return schema_; }
  std::int32_t regionVoxels() const noexcept { return region_voxels_; }
  std::uint32_t voxelsPerRegion() const noexcept { return voxels_per_region_; }
  /// @brief Bytes of the pool (what the configuration asked for, rounded to pages).
  std::size_t poolBytes() const noexcept { return pool_.size(); }

  /// @brief Slot of a region, or kNoSlot. @rt wait-free; allocates: no.
  std::uint32_t find(Vec3i region) const noexcept;
  /// @brief find() by packed coordinate (packCoord()).
  std::uint32_t findPacked(std::uint64_t key) const noexcept;
  /// @brief Slot of a region, creating it (all voxels clear) if absent. @rt allocates: no.
  Expected<std::uint32_t, StoreError> findOrCreate(Vec3i region) noexcept;
  /// @brief Like findOrCreate(), but a region it creates (*created = true) is NOT cleared: the
  /// caller calls clearRegion() before the region is used. Lets a multi-threaded caller insert
  /// serially and clear in parallel. @rt allocates: no.
  Expected<std::uint32_t, StoreError> findOrCreateUncleared(Vec3i region, bool* created) noexcept;
  /// @brief Sets every voxel of every layer of a region to its clear value. Different slots may be
  /// cleared concurrently.
  void clearRegion(std::uint32_t slot) noexcept;
  /// @brief Removes the region in `slot`; the slot becomes free for reuse. @rt allocates: no.
  void release(std::uint32_t slot) noexcept;
  /// @brief Removes every region.
  void clear() noexcept;

  /// @brief Records that a slot's memory was written by someone other than clearRegion() (a
  /// region restored from the cold tiers), so it is no longer the OS's zero pages.
  void noteWritten(std::uint32_t slot) noexcept {
    fresh_[slot] = 0;
    sparse_zero_[slot] = 0;
  }
  /// @brief For a slot about to be released: gives the pages of its sparse zero-clearing layers
  /// (LayerSpec::dense false: voxel means, NDT Gaussians...) back to the OS, so that the region
  /// that takes the slot next makes resident only the pages it writes, as a fresh slot does
  /// (clearRegion() then skips them; restoring writes only their non-zero words). Not for memory
  /// a device uses in place. Real-time: no (a system call per layer).
  void discardSparseLayers(std::uint32_t slot) noexcept;
  /// @brief True between discardSparseLayers() and the slot's next use: its sparse zero-clearing
  /// layers read as zeros and none of their pages is resident.
  bool sparseLayersZero(std::uint32_t slot) const noexcept { return sparse_zero_[slot] != 0; }

  bool inUse(std::uint32_t slot) const noexcept { return used_[slot] != 0; }
  /// @brief For a slot findOrCreateUncleared() has just created: true when no region held it
  /// before, so its memory is still the OS's zero pages and its zero-valued layers
  /// (LayerSpec::clearsToZero) need no clearing, on the host or on a device sharing the pool.
  bool onZeroPages(std::uint32_t slot) const noexcept { return fresh_[slot] != 0; }
  Vec3i coordOf(std::uint32_t slot) const noexcept { return coords_[slot]; }

  /// @brief Start of layer `layer` (schema index) of the region in `slot`.
  std::byte* layerBytes(std::uint32_t slot, int layer) const noexcept {
    const auto l = static_cast<std::size_t>(layer);
    return pool_.data() + layer_offset_[l] + std::size_t{slot} * layer_region_bytes_[l];
  }
  template <class T>
  T* layerData(std::uint32_t slot, int layer) const noexcept {
    return reinterpret_cast<T*>(
        layerBytes(slot, layer));  // the pool holds trivially copyable voxels
  }
  std::size_t layerRegionBytes(int layer) const noexcept {
    return layer_region_bytes_[static_cast<std::size_t>(layer)];
  }
  /// @brief Resets every voxel of one layer of a region to the layer's clear value.
  void clearLayer(std::uint32_t slot, int layer) noexcept;

  /// @brief Calls fn(slot, coord) for every region, in slot order.
  template <class Fn>
  void forEachRegion(Fn&& fn) const {
    for (std::uint32_t slot = 0; slot < capacity_; ++slot) {
      if (used_[slot] != 0) {
        fn(slot, coords_[slot]);
      }
    }
  }

  /// @brief The 63-bit index key of an in-range region coordinate (never all ones). Inline: it
  /// runs for every span a walk makes, and as a call its Vec3i argument was stored as three
  /// 32-bit words and reloaded as a 64-bit register, a store-forwarding stall that took half of
  /// the parallel integrator's survey step (perf, docs/benchmarks.md).
  static std::uint64_t packCoord(Vec3i region) noexcept {
    const auto x = static_cast<std::uint64_t>(region.x + kCoordBias) & kCoordMask;
    const auto y = static_cast<std::uint64_t>(region.y + kCoordBias) & kCoordMask;
    const auto z = static_cast<std::uint64_t>(region.z + kCoordBias) & kCoordMask;
    return x | (y << 21) | (z << 42);
  }
  /// @brief Inverse of packCoord().
  static Vec3i unpackCoord(std::uint64_t key) noexcept {
    return Vec3i{static_cast<std::int32_t>(key & kCoordMask) - kCoordBias,
                 static_cast<std::int32_t>((key >> 21) & kCoordMask) - kCoordBias,
                 static_cast<std::int32_t>((key >> 42) & kCoordMask) - kCoordBias};
  }

  /// @brief True when every component of `region` fits the index.
  static bool inRange(Vec3i region) noexcept {
    return region.x >= -kMaxRegionCoord && region.x <= kMaxRegionCoord &&
           region.y >= -kMaxRegionCoord && region.y <= kMaxRegionCoord &&
           region.z >= -kMaxRegionCoord && region.z <= kMaxRegionCoord;
  }

 private:
  LayerSchema schema_;
  std::int32_t region_voxels_ = 0;
  std::uint32_t voxels_per_region_ = 0;
  std::uint32_t capacity_ = 0;
  std::uint32_t size_ = 0;
  platform::PageBlock pool_;
  std::vector<std::size_t> layer_offset_;
  std::vector<std::size_t> layer_region_bytes_;
  std::vector<Vec3i> coords_;
  std::vector<std::uint8_t> used_;
  std::vector<std::uint8_t> fresh_;  // slot never used: its pages are still the OS's zero pages
  std::vector<std::uint8_t> sparse_zero_;  // sparse zero-clearing layers discarded, not yet used
  std::vector<std::uint32_t> free_slots_;  // stack
  RegionIndex index_;                      // packed coordinate -> slot
};

}  // namespace raymap
