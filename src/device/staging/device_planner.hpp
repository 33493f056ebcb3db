// SPDX-License-Identifier: BSD-3-Clause
// Planning batches on the device: the host's half of it (sizes, the sequence of planning kernels,
// the placement of a batch's regions, the resolve phase). API-agnostic; the OpenCL and CUDA
// backends run the kernels (kernels/device/plan_kernels.h) through PlanDevice.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>
#include <vector>

#include "raymap/expected.hpp"

#include "kernels/common/batch.h"
#include "kernels/common/plan_abi.h"
#include "src/device/staging/batch_plan.hpp"
#include "src/map/backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::gpu {

/// Where a batch is planned.
enum class Planning : std::uint8_t {
  kHost,    ///< the host walks every ray's regions (BatchPlanner): the reference
  kDevice,  ///< the device does (DevicePlanner); the host places the batch's distinct regions
};

/// @brief The planning named `name` as `--device-planning` and raymapd's
/// `backend.device_planning` spell it ("host", "device"); nullopt for any other name.
std::optional<Planning> planningNamed(std::string_view name) noexcept;
const char* toString(Planning planning) noexcept;

/// The planning kernels, in the order of RM_PLAN_KERNELS (kernels/common/plan_abi.h).
enum class PlanKernel : std::uint8_t {
  kBegin,
  kCount,
  kCut,
  kEmit,
  kScanTiles,
  kScanAdd,
  kRadixHistogram,
  kRadixScatter,
  kGroupHeads,
  kGroupBuild,
  kCompact,
  kFinish,
  kResolveRegions,
  kResolveSpans,
  kResolveGroups,
  kGatherSpans,
  kClearRegions,
  kClearTable,
  kPrepare,  ///< RM_PREPARE_KERNELS from here: the ray preparation (double precision)
  kPrepareCount,
  kDeskew,
};
inline constexpr std::size_t kPlanKernelCount = 21;
/// The first ray preparation kernel: OpenCL builds those from a program of their own.
inline constexpr std::size_t kFirstPrepareKernel = static_cast<std::size_t>(PlanKernel::kPrepare);
/// @brief The kernel's entry point ("rm_plan_emit").
const char* planKernelName(PlanKernel kernel) noexcept;

/// The device buffers of one staging set that planning kernels use. The first ones are the
/// batch's own (the integration kernels read them); the rest belong to planning.
enum class PlanBuffer : std::uint8_t {
  kNone,         ///< an argument the kernel does not use (bound to a placeholder)
  kRays,         ///< rm_prepared_ray[max_rays]
  kSpans,        ///< rm_span_record[max_spans]
  kGroups,       ///< rm_hit_group[max_rays]
  kHitRays,      ///< u32[max_rays]
  kRegionSpans,  ///< rm_span_record[max_spans], span work per region only
  kSpanRuns,     ///< rm_span_run[], span work per region only
  kStatus,       ///< u32[RM_PLAN_STATUS_WORDS]
  kCounts,       ///< u32[max_rays + 1]: spans per ray
  kCrossed,      ///< u32[max_rays]: regions per ray, in the window or not
  kOffsets,      ///< u32[max_rays + 1]: their exclusive scan
  kHitKeys,      ///< u32[max_rays]: hit keys, then the sort's ping-pong
  kHitOrder,     ///< u32[max_rays]: rays of the hit keys
  kHitKeysAlt,   ///< u32[max_rays]
  kHitOrderAlt,  ///< u32[max_rays]
  kHeads,        ///< u32[max_rays + 1]: 1 where a voxel's samples start
  kGroupIndex,   ///< u32[max_rays + 1]: their exclusive scan
  kHistogram,    ///< u32[RM_RADIX_BUCKETS * tiles of the longest sort]
  kScanSums0,    ///< u32[]: tile sums of a scan, one buffer per level
  kScanSums1,
  kScanSums2,
  kScanSums3,
  kTable,       ///< u32[4 * table entries]: the region table
  kEntryMap,    ///< u32[2 * table entries]: slot and rank of each entry
  kRegions,     ///< rm_plan_region[region_cap]
  kResolution,  ///< rm_plan_resolution[region_cap]
  kSpanRanks,   ///< u32[max_spans], span work per region only: the grouping sort's ping-pong
  kSpanOrder,
  kSpanRanksAlt,
  kSpanOrderAlt,
  kRawRays,        ///< rm_raw_ray[max_rays], preparation on the device only
  kPrepareParams,  ///< one rm_prepare_params, preparation on the device only
  kOutcomes,       ///< u32[max_rays]: RM_PREPARE_* of each ray, preparation on the device only
  kPoints,         ///< rm_scan_point[max_rays], preparation on the device only
  kPoseSamples,    ///< rm_pose_sample[kMaxPoseSamples], preparation on the device only
  kSegments,       ///< rm_deskew_segment[kMaxSegments], preparation on the device only
};
inline constexpr std::size_t kPlanBufferCount = 36;
/// Pose samples and segments a batch of points deskewed on the device may carry; a batch with
/// more is deskewed on the host.
inline constexpr std::size_t kMaxPoseSamples = RM_DESKEW_MAX_POSE_SAMPLES;
inline constexpr std::size_t kMaxSegments = RM_DESKEW_MAX_SEGMENTS;
/// Scan levels a planner may use (kScanSums0..3): tile sums of tile sums, down to one tile.
inline constexpr unsigned kScanLevels = 4;

/// @brief The sizes every buffer of a device plan is made for. Value type.
struct DevicePlanSizes {
  std::uint32_t max_rays = 0;
  std::uint32_t max_spans = 0;
  std::uint32_t table_entries = 0;           ///< a power of two; entries * voxels per region < 2^31
  std::uint32_t region_cap = 0;              ///< region records read back at most
  std::uint32_t group_size = RM_PLAN_GROUP;  ///< work-items per work-group (RM_PLAN_GROUP)
  bool by_region = false;                    ///< span work per region: the grouping sort
  bool prepare = false;                      ///< rays are prepared on the device (kPrepare)
  std::uint32_t voxels_per_region = 0;

  std::uint32_t tile() const noexcept { return group_size * RM_PLAN_ITEMS; }
  /// Bytes of `buffer` (the batch's own buffers: 0, the backend sizes them).
  std::size_t bytes(PlanBuffer buffer) const noexcept;
  /// Words of each scan level's tile sums for a scan of up to `elements`.
  std::array<std::uint32_t, kScanLevels> scanLevels(std::uint32_t elements) const noexcept;
  /// Elements the longest scan of a plan covers.
  std::uint32_t longestScan() const noexcept;
};

/// @brief The sizes for a map, its batch limits and the backend's layer buffers: `slots` cache
/// slots (0: shared memory, where `layer_regions` is the store's capacity); `group_size`: the
/// device's work-group size for the planning kernels (a power of two, 64 to 256). Fails with
/// kUnsupported, saying why, when the map's regions are too large for 32-bit hit keys.
Result<DevicePlanSizes> devicePlanSizes(const VoxelMap& map, const BatchLimits& limits,
                                        std::uint32_t slots, std::uint32_t layer_regions,
                                        bool by_region, std::uint32_t group_size);

/// @brief One launch of a planning kernel: its arguments, its buffers (kernels/device/
/// plan_kernels.h says what each kernel reads where) and the work-items it needs.
struct PlanLaunch {
  PlanKernel kernel = PlanKernel::kBegin;
  rm_plan_args args{};
  std::array<PlanBuffer, RM_PLAN_BUFFERS> buffers{};
  std::uint32_t items = 1;  ///< rounded up to whole work-groups by the device
};

/// @brief What a device API does for the planner, on the backend's one in-order queue.
class PlanDevice {
 public:
  PlanDevice() = default;
  PlanDevice(const PlanDevice&) = delete;
  PlanDevice& operator=(const PlanDevice&) = delete;
  virtual ~PlanDevice() = default;
  /// Enqueues `launch` on staging set `set`'s buffers.
  virtual bool launchPlan(unsigned set, const PlanLaunch& launch) noexcept = 0;
  /// Enqueues a copy of `bytes` from `host` into `buffer` at byte `offset`. `host` (from the
  /// backend's staging memory resource) is not written again until the set's batch has retired.
  virtual bool writePlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset,
                               const void* host, std::size_t bytes) noexcept = 0;
  /// Enqueues a copy of `bytes` of `buffer` from byte `offset` into `host` (staging memory).
  virtual bool readPlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset, void* host,
                              std::size_t bytes) noexcept = 0;
  /// Marks the end of the reads enqueued so far for `set` and starts the device.
  virtual bool markPlanRead(unsigned set) noexcept = 0;
  /// Waits for the reads before the last markPlanRead(set).
  virtual bool waitPlanRead(unsigned set) noexcept = 0;
};

/// @brief What the plan phase of a batch decided, once its read-back is in.
struct PlanOutcome {
  /// The device's plan cannot be used: the host plans these rays itself (BatchPlanner), exactly.
  /// Rare: more distinct regions than the cache has slots (the host cuts the batch there), a
  /// region far from the batch's first ray, a full region table, a ray with more spans than a
  /// batch holds.
  bool host_fallback = false;
  std::size_t rays =
      0;  ///< rays the plan covers (the batch ends before the first that did not fit)
  /// Rays prepared on the device (enqueuePreparePlan): what happened to the `rays` it covers,
  /// as RayPreparer counts it. Zero otherwise and after a host fallback.
  RayCounters prepared;
};

/// @brief Sizes of a resolved batch, for the integration launches.
struct PlannedBatch {
  std::size_t rays = 0;      ///< ray places the plan covers (rejected ones too, when prepared)
  std::size_t accepted = 0;  ///< of them, rays it integrates
  std::size_t spans = 0;
  std::size_t span_items = 0;  ///< span records, or regions with span work per region
  std::size_t groups = 0;
  std::size_t hits = 0;  ///< samples in the hit groups (per-ray scratch)
};

/// @brief Plans batches on the device, two staging sets at a time.
///
/// enqueuePlan() uploads a batch's rays and enqueues the plan phase with its read-back;
/// finishPlan() waits for the read-back and says how far the plan goes or that the host must plan
/// the batch itself; resolve() places the batch's distinct regions in the order of first
/// appearance through BatchPlanner::placeDevicePlanned (the same moves as a host plan) and
/// enqueues the resolve phase. The host's work is a sort and a placement per distinct region
/// (hundreds a batch), not a walk per ray. Device plans equal host plans span for span: the same
/// span records in the same order, the same hit groups (in another order) and the same slots.
///
/// Thread-safety: none (the backend's integrating thread). Real-time: allocation-free after
/// construction; finishPlan() blocks until the plan phase is done.
class DevicePlanner {
 public:
  /// `memory`: where the host's read-back and upload arrays live (CUDA: page-locked). Throws
  /// std::bad_alloc.
  DevicePlanner(VoxelMap& map, BatchPlanner& planner, std::uint32_t cache_slots,
                const DevicePlanSizes& sizes, PlanDevice& device,
                std::pmr::memory_resource* memory);

  const DevicePlanSizes& sizes() const noexcept { return sizes_; }

  /// @brief Enqueues what a new device's buffers need before the first plan (the empty region
  /// tables of both sets).
  bool initialise() noexcept;

  /// @brief Enqueues the plan phase of `rays` (1 to max_rays) on set `set`; `staging` holds them
  /// (the backend's page-locked ray array of the set), copied here.
  bool enqueuePlan(unsigned set, std::span<const PreparedRay> rays,
                   std::pmr::vector<PreparedRay>& staging) noexcept;

  /// @brief Enqueues the preparation (kernels/device/prepare.h) and the plan phase of world-frame
  /// `rays` (1 to max_rays) on set `set`, as RayPreparer prepares them with `params`. @pre
  /// sizes().prepare. The rays are copied into the set's staging memory.
  bool enqueuePreparePlan(unsigned set, std::span<const Ray> rays,
                          const rm_prepare_params& params) noexcept;

  /// @brief Enqueues the deskewing (kernels/common/deskew.h) of sensor-frame `points` (1 to
  /// max_rays) with `tables`, then their preparation and plan phase as enqueuePreparePlan().
  /// @pre sizes().prepare; the tables within kMaxPoseSamples and kMaxSegments.
  bool enqueueDeskewPlan(unsigned set, std::span<const rm_scan_point> points,
                         const DeskewTables& tables, const rm_prepare_params& params) noexcept;

  /// @brief Waits for set `set`'s plan phase and reads what the host needs.
  Expected<PlanOutcome, IntegrateError> finishPlan(unsigned set) noexcept;

  /// @brief Drops set `set`'s plan (after a host fallback): enqueues the clearing of its table.
  bool discard(unsigned set) noexcept;

  /// @brief Places the regions of set `set`'s plan and enqueues the resolve phase (after
  /// finishPlan() without fallback). Call VoxelMap::beginEpoch() first, as for a host plan.
  Expected<PlannedBatch, IntegrateError> resolve(unsigned set) noexcept;

  /// @brief Copies the resolved plan of set `set` into `out` (blocking): for a PlanObserver,
  /// which compares it with a host plan of the same rays (tests/device/test_device_planning.cpp).
  bool readBack(unsigned set, const PlannedBatch& batch, BatchArrays& out) noexcept;

  /// Batches the host planned instead (PlanOutcome::host_fallback), over the planner's lifetime.
  std::uint64_t fallbacks() const noexcept { return fallbacks_; }
  /// Bytes the planner copied to the device (rays, region slots, runs) and back (status, region
  /// records), over its lifetime.
  std::uint64_t bytesToDevice() const noexcept { return bytes_to_device_; }
  std::uint64_t bytesFromDevice() const noexcept { return bytes_from_device_; }

 private:
  struct SetState {
    explicit SetState(std::pmr::memory_resource* memory)
        : status(RM_PLAN_STATUS_WORDS, 0u, memory),
          regions(memory),
          resolution(memory),
          runs(memory),
          raw(memory),
          params(1, rm_prepare_params{}, memory),
          points(memory),
          samples(memory),
          segments(memory) {}
    std::pmr::vector<std::uint32_t> status;
    std::pmr::vector<rm_plan_region> regions;  // read back
    std::pmr::vector<rm_plan_resolution> resolution;
    std::pmr::vector<rm_span_run> runs;  // span work per region
    std::pmr::vector<rm_raw_ray> raw;    // preparation on the device: the rays uploaded
    std::pmr::vector<rm_prepare_params> params;
    std::pmr::vector<rm_scan_point> points;  // deskewing on the device: what was uploaded
    std::pmr::vector<rm_pose_sample> samples;
    std::pmr::vector<rm_deskew_segment> segments;
    bool prepared = false;           // the plan's rays were prepared on the device
    std::uint32_t rays = 0;          // rays of the plan phase
    std::uint32_t regions_read = 0;  // records the read-back covered
    rm_vec3i key_origin{};
  };

  bool launch(unsigned set, PlanKernel kernel, const rm_plan_args& args, std::uint32_t items,
              std::initializer_list<PlanBuffer> buffers) noexcept;
  /// Exclusive scan of `in` (n words) into `out` (may be `in`).
  bool scan(unsigned set, PlanBuffer in, PlanBuffer out, std::uint32_t n) noexcept;
  /// Stable radix sort of (keys, values) over key bits [0, bits); returns where the result is
  /// (the buffers themselves or their alternates).
  bool sort(unsigned set, std::uint32_t n, std::uint32_t bits, PlanBuffer* keys, PlanBuffer* values,
            PlanBuffer keys_alt, PlanBuffer values_alt) noexcept;
  rm_plan_args baseArgs(const SetState& state) const noexcept;
  /// Enqueues the preparation of the set's rays in kRawRays, then enqueuePlanPhase().
  bool enqueuePrepareAndPlan(unsigned set, const rm_prepare_params& params) noexcept;
  /// Enqueues the plan phase of the set's rays (in the kRays buffer) and its read-back.
  bool enqueuePlanPhase(unsigned set) noexcept;

  VoxelMap* map_;
  BatchPlanner* planner_;
  std::uint32_t cache_slots_;  // 0: shared memory
  DevicePlanSizes sizes_;
  PlanDevice* device_;
  std::array<SetState, 2> sets_;
  std::vector<std::uint32_t> order_;  // scratch: regions by first appearance, then by rank
  std::uint32_t read_ahead_ = 256;    // region records read back with the status
  std::uint64_t fallbacks_ = 0;
  std::uint64_t bytes_to_device_ = 0;
  std::uint64_t bytes_from_device_ = 0;
};

}  // namespace raymap::gpu
