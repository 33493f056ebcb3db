// SPDX-License-Identifier: BSD-3-Clause
// The part of a device backend that is the same on every GPU API: batches planned on the host
// while the device runs the previous one (two staging sets), the kernel order of each semantics,
// region moves through the device cache, counters and statistics. The OpenCL and CUDA backends
// derive from it and supply the device calls.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <optional>
#include <span>
#include <vector>

#include "kernels/common/batch.h"
#include "kernels/common/ndt.h"
#include "src/device/staging/batch_plan.hpp"
#include "src/device/staging/device_options.hpp"
#include "src/device/staging/device_planner.hpp"
#include "src/device/staging/device_region_cache.hpp"
#include "src/device/staging/span_grouping.hpp"
#include "src/device/staging/transfer_staging.hpp"
#include "src/map/backend.hpp"
#include "src/map/layer_schema.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::gpu {

/// The kernels of the occupancy integration (kernels/device/integrate_occupancy.h).
enum class OccupancyKernel : std::uint8_t {
  kTagHitGroups,    ///< per-ray semantics: tag the voxels with samples before the misses
  kIntegrateSpans,  ///< one work-item per span record (or per region, when grouped): the misses
                    ///< (and per-scan marks, path lengths, TSDF)
  kApplyHitGroups,  ///< one work-item per voxel with samples: hits (and, per ray, the replay)
};

/// The kernels of the NDT-OM / NDT-TM integration (kernels/device/integrate_ndt.h), launched in
/// this order: the batch's misses against the Gaussians as they were, then its hits per voxel.
enum class NdtKernel : std::uint8_t {
  kIntegrateSpans,  ///< one work-item per span record (or per region, when grouped): NDT misses
                    ///< (and NDT-TM miss counts)
  kApplyHitGroups,  ///< one work-item per voxel with samples: its hits folded in ray order
};

/// @brief The mode bits of `map` (kernels/common/map_mode.h): which device kernels integrate it.
/// rm_map_mode_has_kernels() of the result is false for a map no device program can run.
std::uint32_t mapModeBits(const VoxelMap& map) noexcept;

/// @brief True for a layer the device kernels write only where a sample lands (the hit-group
/// kernels): voxel means, NDT Gaussians, NDT-TM intensities. A region no sample reached since
/// its last download keeps those layers on the host as they are, so they are not downloaded
/// again (an NDT map's Gaussians are 40 of its 52 bytes a voxel). Every other layer is written
/// by the span kernels as well (NDT-TM's hit/miss counts count passes there).
bool sampleLayer(LayerKind kind) noexcept;

/// @brief Told of every batch a device backend plans, as the integration kernels get it: the
/// tests compare device plans with host plans of the same rays through it.
/// Observing a device plan reads it back from the device and waits: for checks, not for speed.
class PlanObserver {
 public:
  PlanObserver() = default;
  PlanObserver(const PlanObserver&) = delete;
  PlanObserver& operator=(const PlanObserver&) = delete;
  virtual ~PlanObserver() = default;
  /// `batch`: the rays, span records (and, with span work per region, the grouped records and
  /// runs), hit groups and hit rays of one batch; `where`: who planned it.
  virtual void planned(const BatchArrays& batch, Planning where) = 0;
};

/// @brief A device backend over an API-specific queue of copies and kernels.
///
/// integrate() plans a batch into one of two staging sets (waiting first for the batch that set
/// carried before), then asks the derived class to upload it, launch the kernels in the order the
/// semantics needs and read the counters back, all without waiting; the host then plans the next
/// batch into the other set while the device works. Every device call of one backend goes to one
/// in-order queue (OpenCL command queue, CUDA stream), which is what orders region moves, batches
/// and read-backs.
///
/// Thread-safety: none; the map must not be changed by others between integrate() and
/// synchronise(), except for rolling-window moves, which the next integrate() takes into account.
/// With planning on the device (DeviceBackendOptions::planning, DevicePlanner), integrate()
/// uploads a batch's rays and enqueues its plan phase, then, while the device plans it and
/// integrates the batch before, places the previous batch's distinct regions and enqueues its
/// resolve phase and kernels: the host's work per batch is a few hundred region placements, not
/// a region walk per ray. A batch the device plan cannot serve (more regions than the cache has
/// slots, among others: PlanOutcome) is planned on the host instead, exactly.
///
/// Real-time: integrate() allocates nothing once constructed; it blocks only to wait for the
/// device's batch before last (device planning: for the read-back of the batch's plan phase).
class StagedBackend : public Backend,
                      private RegionTransfer,
                      private RegionEvictionHook,
                      private PlanDevice {
 public:
  static constexpr unsigned kStagingSets = 2;

  /// Unregisters from a tiered map (the map outlives the backend).
  ~StagedBackend() override;
  StagedBackend(const StagedBackend&) = delete;
  StagedBackend& operator=(const StagedBackend&) = delete;
  StagedBackend(StagedBackend&&) = delete;
  StagedBackend& operator=(StagedBackend&&) = delete;

  Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept final;
  /// Rays are prepared on the device when planning is (planOnDevice() with sizes.prepare) and
  /// the filter has no segmentation.
  bool preparesOnDevice(const RayFilter& filter) const noexcept final;
  Expected<std::size_t, IntegrateError> integrateRays(const RayPreparer& preparer,
                                                      const rm_prepare_params& params,
                                                      std::span<const Ray> rays,
                                                      RayCounters& counters) noexcept final;
  /// Points are deskewed on the device where rays are prepared there and the tables fit its
  /// limits (kMaxSegments, kMaxPoseSamples); per scan, a call of at most one device batch.
  bool deskewsOnDevice(const RayFilter& filter, const DeskewTables& tables,
                       std::size_t points) const noexcept final;
  Expected<std::size_t, IntegrateError> integratePoints(const RayPreparer& preparer,
                                                        const rm_prepare_params& params,
                                                        std::span<const rm_scan_point> points,
                                                        const DeskewTables& tables,
                                                        RayCounters& counters) noexcept final;
  Expected<void, IntegrateError> synchronise() noexcept final;
  BackendStats stats() const noexcept final;
  unsigned threads() const noexcept final { return 1; }

  /// @brief What placeForRead() did.
  struct ReadPlacement {
    bool resident = false;             ///< every region is readable in the layer buffers
    std::uint64_t bytes_uploaded = 0;  ///< region bytes it copied to the device for that
  };
  /// @brief Lends the map's layers, where integration left them, to a reader that enqueues its
  /// kernels on this backend's queue next (the height-map generator): binds the device to the
  /// calling thread, takes window moves into account, and writes the layer-buffer slot of each
  /// region in host store slots `host_slots` into `device_slots` (same size). The reader's work
  /// runs after every batch integrated so far (one in-order queue); nothing waits here.
  /// Shared memory: the host slots themselves, nothing copied. Cache: regions not resident are
  /// uploaded (evicting others, downloaded if dirty) and stay pinned until the next integrate();
  /// `resident` is false when the cache cannot hold them all at once, and the reader must then
  /// synchronise() and read the host store. Same thread-safety as integrate(). @rt no allocation.
  Expected<ReadPlacement, IntegrateError> placeForRead(
      std::span<const std::uint32_t> host_slots, std::span<std::uint32_t> device_slots) noexcept;
  /// The map this backend integrates into.
  const VoxelMap& integratedMap() const noexcept { return *map_; }
  /// Where batches are planned.
  Planning planning() const noexcept {
    return device_planner_ ? Planning::kDevice : Planning::kHost;
  }
  /// @brief Tells `observer` (nullptr: nobody) of every batch planned from now on; it must
  /// outlive the backend or be removed first. Throws std::bad_alloc (the read-back arrays).
  void observePlans(PlanObserver* observer);

 protected:
  /// `slots` == 0: shared memory (the device works on the host store in place). `wide_counters`:
  /// the kernels count in 64-bit words (else 32-bit). `staging_memory` provides the host batch
  /// arrays (reserved here, for the limits) and must outlive the backend. Throws std::bad_alloc
  /// when the arrays cannot be allocated (factories turn it into an error).
  StagedBackend(VoxelMap& map, std::uint32_t slots, bool wide_counters,
                const DeviceBackendOptions& options,
                std::pmr::memory_resource* staging_memory = std::pmr::get_default_resource());

  VoxelMap& map() const noexcept { return *map_; }
  bool sharedMemory() const noexcept { return !cache_.has_value(); }
  /// Regions per layer buffer: the cache slots, or the host store's capacity in shared memory.
  std::uint32_t layerRegions() const noexcept;
  const BatchLimits& limits() const noexcept { return limits_; }
  std::size_t counterBytes() const noexcept;
  /// 32-bit words of a set's scratch buffer (one for NDT maps, which do not use it).
  std::size_t scratchWords() const noexcept;
  /// The map's mode bits (kernels/common/map_mode.h): which span and hit kernels run it.
  std::uint32_t mapMode() const noexcept { return map_mode_; }
  /// From now on, group each batch's span records by region (BatchArrays::region_spans,
  /// span_runs) and launch the span kernel over the regions: for programs built with
  /// RM_REGION_OWNED (kernels/device/device.h). Call before the first integrate(). Throws
  /// std::bad_alloc when the grouped lists cannot be reserved.
  void groupSpansByRegion();
  /// The span kernel runs one work-item per region (groupSpansByRegion()).
  bool spansByRegion() const noexcept { return grouper_.has_value(); }
  /// Fails with kUnsupported, saying why, when no device program has kernels for the map's mode
  /// or a per-scan map lacks its scan-mark layer (MapConfig::device_scan_marks).
  Expected<void, Error> checkMapIsSupported() const;
  /// The sizes of the planning buffers for kernels in work-groups of `group_size` (call after
  /// groupSpansByRegion(), if at all).
  Result<DevicePlanSizes> devicePlanSizesFor(std::uint32_t group_size) const;
  /// From now on, plan batches on the device with buffers of `sizes` (which the API layer has
  /// allocated, PlanDevice), and enqueue what its buffers need first. Call before the first
  /// integrate(). kCapacity when the host arrays cannot be allocated.
  Expected<void, Error> planOnDevice(const DevicePlanSizes& sizes) noexcept;

  // ---- what the API layer supplies; every call goes to the backend's one in-order queue ----

  /// Called first by integrate() and synchronise(): binds the device to the calling thread where
  /// the API needs it (CUDA's current device).
  virtual bool makeCurrent() noexcept { return true; }

  /// Copies the batch's arrays into set `set`'s device buffers (none for a batch planned on the
  /// device, `arrays` null) and zeroes its counters. The copy may still run when this returns:
  /// the host arrays are not written again before waitForBatch(set) has returned.
  virtual bool uploadBatch(unsigned set, const BatchArrays* arrays) noexcept = 0;
  /// Zeroes `words` 32-bit words of set `set`'s scratch buffer from `first_word` on.
  virtual bool clearScratch(unsigned set, std::size_t first_word, std::size_t words) noexcept = 0;
  /// Runs `kernel` over params.item_count work-items on set `set`'s buffers (items > 0).
  virtual bool launch(OccupancyKernel kernel, unsigned set,
                      const rm_integrate_params& params) noexcept = 0;
  /// NDT maps: runs `kernel` over params.item_count work-items on set `set`'s buffers and the
  /// map's NDT layers (items > 0).
  virtual bool launchNdt(NdtKernel kernel, unsigned set, const rm_integrate_params& params,
                         const rm_ndt_params& ndt_params) noexcept = 0;
  /// Reads set `set`'s counters back, marks the end of its batch and starts the device.
  virtual bool endBatch(unsigned set) noexcept = 0;
  /// Waits for set `set`'s batch; its RM_COUNTER_COUNT counter words (64-bit if wide, else
  /// 32-bit), or nullptr when the device failed.
  virtual const void* waitForBatch(unsigned set) noexcept = 0;
  /// Enqueues a copy of `bytes` of layer `layer` between the device (byte offset
  /// `device_offset`) and `host`: staging memory (TransferStaging, from the staging memory
  /// resource) that nobody touches until the device has passed the copy, or, for a download
  /// while the queue is drained (synchronising, writing back), the host store itself. Returns
  /// without waiting.
  virtual bool copyLayer(int layer, std::size_t device_offset, std::byte* host, std::size_t bytes,
                         bool to_device) noexcept = 0;
  /// Sets `bytes` of layer `layer` from `device_offset` on to the layer's clear value.
  virtual bool fillLayer(int layer, std::size_t device_offset, std::size_t bytes,
                         const LayerSpec& spec) noexcept = 0;
  /// Waits until the queue is empty.
  virtual bool finish() noexcept = 0;
  /// Shared memory, after finish(): makes the device's writes visible to host reads.
  virtual bool syncSharedMemory() noexcept { return true; }

 private:
  // ---- RegionEvictionHook (a tiered map moving regions out of its pool, while planning) ----
  bool beforeEviction(std::span<const std::uint32_t> host_slots) noexcept final;

  // ---- RegionTransfer (called by the planner) ----
  Expected<void, IntegrateError> download(std::uint32_t device_slot, std::uint32_t host_slot,
                                          bool sample_layers, bool drained) noexcept final;
  Expected<void, IntegrateError> upload(std::uint32_t device_slot,
                                        std::uint32_t host_slot) noexcept final;
  Expected<void, IntegrateError> fillClear(std::uint32_t device_slot,
                                           bool zero_layers_clear) noexcept final;
  Expected<void, IntegrateError> waitForDevice() noexcept final;

  // ---- the batch loop ----
  Expected<void, IntegrateError> integrateHostPlanned(std::span<const PreparedRay> rays) noexcept;
  Expected<void, IntegrateError> integrateDevicePlanned(std::span<const PreparedRay> rays) noexcept;
  /// Waits for set `set`'s plan phase, retires the set's batch before last and begins the map's
  /// epoch for the batch; `t_plan`: when the wait ended.
  Expected<PlanOutcome, IntegrateError> awaitPlan(
      unsigned set, std::chrono::steady_clock::time_point* t_plan) noexcept;
  /// integrateRays() with the preparation on the device, or (a fallback) on the host.
  Expected<std::size_t, IntegrateError> integrateDevicePrepared(const RayPreparer& preparer,
                                                                const rm_prepare_params& params,
                                                                std::span<const Ray> rays,
                                                                RayCounters& counters) noexcept;
  /// The device-planned pipeline over `total` rays or points: `enqueue_batch(set, from, count)`
  /// enqueues a batch's deskewing, preparation and plan phase; `host_rest(first)` integrates the
  /// rest on the host when the device cannot plan a batch.
  template <class Enqueue, class HostRest>
  Expected<std::size_t, IntegrateError> integrateOnDevice(std::size_t total, RayCounters& counters,
                                                          Enqueue&& enqueue_batch,
                                                          HostRest&& host_rest) noexcept;
  Expected<std::size_t, IntegrateError> integrateHostPrepared(const RayPreparer& preparer,
                                                              const rm_prepare_params& params,
                                                              std::span<const Ray> rays,
                                                              RayCounters& counters) noexcept;
  /// Enqueues the plan phase of the rays from `first` on (at most a batch) into the next set.
  bool enqueueDevicePlan(std::span<const PreparedRay> rays, std::size_t first,
                         unsigned* set) noexcept;

  /// Waits until the queue is empty and the downloads in staging are in the host store.
  bool drain() noexcept;
  /// Copies the region's layers, or (sample_layers false) all but sampleLayer() ones, through
  /// the staging ring: nothing waits unless the ring is full (transfer_stalls). A region wanted
  /// back before its download arrived goes up from where that download lands.
  Expected<void, IntegrateError> copyRegion(std::uint32_t device_slot, std::uint32_t host_slot,
                                            bool to_device, bool sample_layers = true,
                                            bool drained = false) noexcept;
  /// Waits for the set's previous batch (if any) and adds its device counters to the stats.
  Expected<void, IntegrateError> retire(unsigned set) noexcept;
  /// Enqueues the batch the host planned into `set`: copies, then launchBatch().
  Expected<void, IntegrateError> submit(unsigned set) noexcept;
  /// Enqueues the batch the device planned into `set` (resolved): launchBatch().
  Expected<void, IntegrateError> submitDevicePlanned(unsigned set,
                                                     const PlannedBatch& batch) noexcept;
  /// The kernels in the semantics' order over `batch`, then the counters' read-back.
  Expected<void, IntegrateError> launchBatch(unsigned set, const PlannedBatch& batch) noexcept;
  bool launchOver(OccupancyKernel kernel, unsigned set, std::size_t items,
                  std::size_t groups) noexcept;
  bool launchNdtOver(NdtKernel kernel, unsigned set, std::size_t items,
                     std::size_t groups) noexcept;
  /// The batch's launch parameters for `items` work-items, in a batch of `groups` hit groups.
  rm_integrate_params launchParams(std::size_t items, std::size_t groups) const noexcept;

  struct StagingSet {
    explicit StagingSet(std::pmr::memory_resource* memory) : arrays(memory) {}
    BatchArrays arrays;
    bool in_flight = false;
    std::uint64_t number = 0;  // the batch it carries (1, 2, ... in submission order)
  };

  static_assert(kStagingSets == 2, "sets_ is initialised with two sets");

  VoxelMap* map_;
  std::optional<DeviceRegionCache> cache_;    // empty: shared memory
  std::optional<TransferStaging> transfers_;  // region moves (cache only)
  std::uint64_t submitted_ = 0;               // batches submitted so far
  BatchLimits limits_;
  BatchPlanner planner_;
  std::array<StagingSet, kStagingSets> sets_;
  unsigned next_set_ = 0;
  bool wide_counters_;
  rm_integrate_params params_{};
  bool ndt_;                    // the map is NDT-OM or NDT-TM: the NDT kernels, per-ray batches
  rm_ndt_params ndt_params_{};  // NDT maps: the rules' parameters in voxel units
  std::uint32_t map_mode_ = 0;  // rm_map_mode_bits of the map (fixed for the backend's life)
  std::optional<RegionSpanGrouper> grouper_;     // span work per region (groupSpansByRegion())
  std::optional<DevicePlanner> device_planner_;  // planning on the device (planOnDevice())
  std::vector<PreparedRay> host_prepared_;       // preparation on the device: the host's fallback
  std::vector<Ray> host_rays_;                   // and its deskewing
  std::pmr::memory_resource* staging_memory_;
  PlanObserver* plan_observer_ = nullptr;
  std::optional<BatchArrays> observed_;  // a device plan read back for the observer
  BackendStats stats_;
};

}  // namespace raymap::gpu
