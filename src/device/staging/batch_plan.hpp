// SPDX-License-Identifier: BSD-3-Clause
// Turns prepared rays into what a device kernel consumes: span records with device cache slots,
// and hit groups. Moves regions into the device cache as the batch needs them. API-agnostic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>
#include <vector>

#include "raymap/expected.hpp"

#include "kernels/common/batch.h"
#include "src/device/staging/device_region_cache.hpp"
#include "src/map/backend.hpp"
#include "src/map/ray_region_walk.hpp"
#include "src/map/region_slot_cache.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::gpu {

/// @brief Region moves between the host store and the device cache, done by a device backend.
/// Each call is ordered before the batch's kernels (and before later calls). A download may still
/// be in flight when it returns: the backend waits for it before anyone reads the host store
/// (synchronise()).
class RegionTransfer {
 public:
  virtual ~RegionTransfer() = default;
  RegionTransfer() = default;
  RegionTransfer(const RegionTransfer&) = delete;
  RegionTransfer& operator=(const RegionTransfer&) = delete;

  /// @brief Copies the layers of device slot `device_slot` into host store slot `host_slot`:
  /// every layer with `sample_layers`, else all but the layers written only where a sample lands
  /// (DeviceRegionCache::Entry::samples_dirty says which a region needs). `drained`: the caller
  /// has waited for the device and waits again before anyone reads the host store
  /// (synchronising, writing back), so the copy may go straight into the host store.
  virtual Expected<void, IntegrateError> download(std::uint32_t device_slot,
                                                  std::uint32_t host_slot, bool sample_layers,
                                                  bool drained) noexcept = 0;
  /// @brief Copies every layer of host store slot `host_slot` into device slot `device_slot`.
  virtual Expected<void, IntegrateError> upload(std::uint32_t device_slot,
                                                std::uint32_t host_slot) noexcept = 0;
  /// @brief Sets every voxel of device slot `device_slot` to its layer's clear value (a region
  /// new to the map: nothing to copy). `zero_layers_clear`: the slot's memory is known to be
  /// zero already (a shared-memory slot on the OS's zero pages), so layers that clear to zero
  /// are left alone and their pages are not touched.
  virtual Expected<void, IntegrateError> fillClear(std::uint32_t device_slot,
                                                   bool zero_layers_clear) noexcept = 0;
  /// @brief Waits until every move enqueued so far has finished (before the host writes a host
  /// store slot that a download may still be filling).
  virtual Expected<void, IntegrateError> waitForDevice() noexcept = 0;
};

/// @brief One batch in host memory, ready to copy to the device. The arrays come from a memory
/// resource the backend chooses (CUDA: page-locked memory, so copies are asynchronous DMA); they
/// are reserved once for the batch limits and never grow past them, so their storage never moves.
struct BatchArrays {
  explicit BatchArrays(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
      : rays(memory),
        spans(memory),
        groups(memory),
        hit_rays(memory),
        hit_keys(memory),
        region_spans(memory),
        span_runs(memory) {}

  std::pmr::vector<PreparedRay> rays;
  std::pmr::vector<rm_span_record> spans;
  std::pmr::vector<rm_hit_group> groups;     ///< one per voxel with samples, sorted by voxel
  std::pmr::vector<std::uint32_t> hit_rays;  ///< ray indices of each group's samples, in ray order
  std::pmr::vector<std::uint64_t> hit_keys;  ///< scratch: (device voxel << 32) | ray
  /// Span work per region only (RegionSpanGrouper): `spans` grouped by region, in ray order
  /// within each, and each region's run of them. Empty otherwise.
  std::pmr::vector<rm_span_record> region_spans;
  std::pmr::vector<rm_span_run> span_runs;

  void clear() noexcept {
    rays.clear();
    spans.clear();
    groups.clear();
    hit_rays.clear();
    hit_keys.clear();
    region_spans.clear();
    span_runs.clear();
  }
  /// The span records as the span kernel reads them: grouped by region when they have been.
  const std::pmr::vector<rm_span_record>& deviceSpans() const noexcept {
    return span_runs.empty() ? spans : region_spans;
  }
};

/// @brief Limits of one batch (the device staging buffers are sized from them).
struct BatchLimits {
  std::size_t max_rays = std::size_t{1} << 18;
  std::size_t max_spans = std::size_t{1} << 21;
};

/// @brief Counters of the planner over its lifetime.
struct PlanStats {
  std::uint64_t spans_outside_window = 0;
  std::uint64_t rays_too_long = 0;  ///< rays crossing more regions than the cache holds (skipped)
  std::uint64_t region_hits = 0;    ///< shared mode: spans in regions the map already had
  std::uint64_t region_misses = 0;  ///< shared mode: regions new to the map
};

/// @brief Plans batches for one map, one device cache and one transfer implementation.
///
/// For each ray it runs the coarse region walk (the same RayRegionWalk as the CPU backend),
/// makes sure every region exists in the host store (created uncleared: the device clears its copy
/// and the host copy is only read after a download) and is resident in the device cache, and
/// records one rm_span_record per region piece. Sample voxels are gathered and sorted into hit
/// groups. A batch ends when the rays end, the limits are reached, or the cache cannot hold
/// another region without evicting one the batch uses.
///
/// Without a cache (`cache` null) the planner works in shared mode: the device works on the host
/// store's memory in place, a region's device slot is its host slot, and nothing is ever copied
/// (new regions are still cleared on the device, in order with the kernels).
///
/// Thread-safety: none. Real-time: allocation-free once the arrays have reached the limits'
/// sizes (reserved at construction).
class BatchPlanner {
 public:
  BatchPlanner(VoxelMap& map, DeviceRegionCache* cache, RegionTransfer& transfer,
               const BatchLimits& limits);

  /// @brief Reserves arrays for the limits.
  void reserve(BatchArrays& out) const;

  /// @brief Forgets cached regions whose host region a window move recycled. Call before
  /// planning; cheap when the window has not moved.
  void revalidate() noexcept;

  /// @brief Plans a batch from the front of `rays` into `out` (cleared first) and returns how
  /// many rays it consumed (at least one while rays remain, unless an error). kStoreFull: the host
  /// store cannot create a region (global map full); kDeviceFailure: a region move failed.
  Expected<std::size_t, IntegrateError> plan(std::span<const PreparedRay> rays,
                                             BatchArrays& out) noexcept;

  /// @brief Enqueues the download of every dirty resident region; the host store is current once
  /// the backend has waited for the device.
  Expected<void, IntegrateError> downloadAll() noexcept;

  /// @brief Before a tiered map moves the regions in host slots `host_slots` out of its pool:
  /// downloads the dirty device copies among them, forgets them all, and waits for the device.
  Expected<void, IntegrateError> writeBack(std::span<const std::uint32_t> host_slots) noexcept;

  /// @brief Makes the regions in host store slots `host_slots` readable on the device by work
  /// enqueued next, and writes each one's device slot into `device_slots` (same size): for a
  /// reader such as the height map. Shared mode: the host slots themselves, nothing moves.
  /// Cache: regions not resident are uploaded (evicting the least recently used ones, downloaded
  /// if dirty) and pinned until the next plan; resident ones keep their dirty flags. Returns
  /// false when the cache cannot hold them all at once (the caller reads the host store instead,
  /// after synchronise()). Call revalidate() first.
  Expected<bool, IntegrateError> placeForRead(std::span<const std::uint32_t> host_slots,
                                              std::span<std::uint32_t> device_slots) noexcept;

  const PlanStats& stats() const noexcept { return stats_; }

  // ---- batches planned on the device (DevicePlanner): the same placements, region by region ----

  /// @brief Starts a batch whose regions the device has listed: regions placed from now on are
  /// pinned until the next batch.
  void beginDevicePlanned() noexcept;
  /// @brief Places one region of a device-planned batch, in the batch's order of first
  /// appearance (what plan() does at the region's first span): creates it in the host store
  /// (uncleared) if new and gives it a device slot, moving regions as plan() would. `spans`: the
  /// batch's span records in it (counted as plan() counts them); `samples`: its samples (the
  /// region's sample layers become dirty). Precondition: the batch has at most as many regions
  /// as the cache has slots, and `region` is in the store's range and window. kStoreFull,
  /// kTierFailed, kDeviceFailure as plan().
  Expected<std::uint32_t, IntegrateError> placeDevicePlanned(Vec3i region, std::uint32_t spans,
                                                             std::uint32_t samples) noexcept;
  /// @brief Counts span records a device-planned batch skipped outside the rolling window.
  void countSpansOutside(std::uint64_t spans) noexcept { stats_.spans_outside_window += spans; }

 private:
  /// The region's host store slot, created uncleared if new (then marked uninitialised: the
  /// device clears its copy). On failure the store's reason: batchError() says whether it ends
  /// the batch or only skips the region.
  Expected<std::uint32_t, StoreError> acquireHostRegion(Vec3i region) noexcept;
  /// Shared mode: the region's host slot, cleared on the device if it is new.
  Expected<std::uint32_t, IntegrateError> sharedRegion(std::uint32_t host_slot) noexcept;
  /// Device slot for a region of the current batch; kNoSlot + *full when the cache is pinned full.
  /// `write`: the batch changes the region (it becomes dirty).
  Expected<std::uint32_t, IntegrateError> placeRegion(Vec3i region, std::uint32_t host_slot,
                                                      bool* full, bool write = true) noexcept;
  void buildHitGroups(BatchArrays& out) const;
  /// plan()'s steps for one ray: its region spans into the batch (true: the batch's spans or
  /// its region cache are full, and the ray's spans are not all placed), then its end hit.
  Expected<bool, IntegrateError> planSpans(RayRegionWalk& walk, std::uint32_t ray_index,
                                           BatchArrays& out) noexcept;
  void planHit(const RayRegionWalk& walk, std::uint32_t ray_index, BatchArrays& out) noexcept;

  VoxelMap* map_;
  DeviceRegionCache* cache_;
  RegionTransfer* transfer_;
  BatchLimits limits_;
  std::int32_t region_voxels_;
  std::uint32_t voxels_per_region_;
  std::vector<std::uint8_t> host_uninitialised_;  // per host slot: created, never written
  std::uint64_t seen_recycled_ = 0;
  // Regions placed in the current batch (packed coordinate -> device slot): neighbouring rays
  // cross the same few regions, and a placed region stays pinned until the batch ends.
  detail::RegionSlotCache batch_regions_;
  PlanStats stats_;
};

}  // namespace raymap::gpu
