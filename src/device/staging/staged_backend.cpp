// SPDX-License-Identifier: BSD-3-Clause
// The API-independent half of the device backends: batch loop, kernel order, region moves.
#include "src/device/staging/staged_backend.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <string>

#include "kernels/common/map_mode.h"

namespace raymap::gpu {
namespace {

static_assert(sizeof(rm_span_record) == 32, "device ABI");
static_assert(sizeof(rm_hit_group) == 16, "device ABI");
static_assert(sizeof(rm_span_run) == 8, "device ABI");
static_assert(sizeof(rm_integrate_params) == 80, "device ABI");
static_assert(sizeof(rm_tsdf_voxel) == 8, "device ABI");
static_assert(sizeof(rm_ndt_params) == 32, "device ABI");
static_assert(sizeof(rm_ndt_voxel) == 40, "device ABI");
static_assert(sizeof(rm_ndt_hit_miss) == 8 && sizeof(rm_ndt_intensity) == 8, "device ABI");

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) noexcept {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Bytes of the region-move staging ring: the options', or 64 MiB; never less than four regions
/// of every layer (a region is moved layer by layer, each copy whole).
std::size_t transferStagingBytes(const VoxelMap& map, const DeviceBackendOptions& options) {
  std::size_t region = 0;
  for (int l = 0; l < map.store().schema().size(); ++l) {
    region += map.store().layerRegionBytes(l);
  }
  const std::size_t wanted = options.transfer_staging_bytes != 0
                                 ? static_cast<std::size_t>(options.transfer_staging_bytes)
                                 : std::size_t{64} << 20;
  return std::max(wanted, 4 * region);
}

}  // namespace

bool sampleLayer(LayerKind kind) noexcept {
  return kind == LayerKind::kVoxelMean || kind == LayerKind::kNdt || kind == LayerKind::kIntensity;
}

std::uint32_t mapModeBits(const VoxelMap& map) noexcept {
  return rm_map_mode_bits(map.occupancyLayer() >= 0 ? 1u : 0u,
                          map.semantics() == Semantics::kPerScan ? 1u : 0u,
                          map.traversalLayer() >= 0 ? 1u : 0u, map.tsdfLayer() >= 0 ? 1u : 0u,
                          isNdt(map.mode()) ? 1u : 0u);
}

StagedBackend::StagedBackend(VoxelMap& map, std::uint32_t slots, bool wide_counters,
                             const DeviceBackendOptions& options,
                             std::pmr::memory_resource* staging_memory)
    : map_(&map),
      cache_(slots > 0 ? std::optional<DeviceRegionCache>(std::in_place, slots) : std::nullopt),
      transfers_(slots > 0 ? std::optional<TransferStaging>(std::in_place,
                                                            transferStagingBytes(map, options),
                                                            map.store().capacity(), staging_memory)
                           : std::nullopt),
      limits_(batchLimits(map, options)),
      planner_(map, cache_ ? &*cache_ : nullptr, *this, limits_),
      sets_{StagingSet(staging_memory), StagingSet(staging_memory)},
      wide_counters_(wide_counters),
      ndt_(isNdt(map.mode())),
      staging_memory_(staging_memory) {
  params_.occupancy = map.occupancy().toKernel();
  params_.region_voxels = map.geometry().region_voxels;
  params_.voxels_per_region = map.store().voxelsPerRegion();
  params_.per_scan = map.semantics() == Semantics::kPerScan ? 1u : 0u;
  params_.has_mean = map.meanLayer() >= 0 ? 1u : 0u;
  params_.has_traversal = map.traversalLayer() >= 0 ? 1u : 0u;
  // As the CPU backend rounds it (IntegrationContext::resolution): equal per-voxel lengths.
  params_.resolution = static_cast<float>(map.geometry().resolution);
  params_.has_tsdf = map.tsdfLayer() >= 0 ? 1u : 0u;
  params_.has_occupancy = map.occupancyLayer() >= 0 ? 1u : 0u;
  params_.tsdf = map.config().tsdf.toKernel(map.geometry().resolution);
  if (ndt_) {
    ndt_params_ = map.config().ndt.toKernel(map.geometry().resolution, map.occupancy(), map.mode());
  }
  map_mode_ = mapModeBits(map);
  stats_.cache_slots = layerRegions();
  for (StagingSet& set : sets_) {
    planner_.reserve(set.arrays);
  }
  if (map.tiered()) {
    map.setEvictionHook(this);
    map.keepPreviousEpoch();  // the batch in flight keeps its regions while the next is planned
  }
}

StagedBackend::~StagedBackend() {
  if (map_->tiered()) {
    map_->setEvictionHook(nullptr);
  }
}

bool StagedBackend::drain() noexcept {
  if (!finish()) {
    return false;
  }
  if (transfers_) {
    transfers_->completeAll();
  }
  return true;
}

bool StagedBackend::beforeEviction(std::span<const std::uint32_t> host_slots) noexcept {
  // Nothing in flight may still write the regions leaving (the map pins the batch being planned
  // and the one before it; this also covers work enqueued for readers).
  if (!makeCurrent() || !drain()) {
    return false;
  }
  if (!cache_) {
    return syncSharedMemory();  // the device worked in the pool itself: make its writes visible
  }
  return planner_.writeBack(host_slots).has_value();
}

void StagedBackend::groupSpansByRegion() {
  grouper_.emplace(layerRegions());
  for (StagingSet& set : sets_) {
    grouper_->reserve(set.arrays, limits_);
  }
}

Result<DevicePlanSizes> StagedBackend::devicePlanSizesFor(std::uint32_t group_size) const {
  return devicePlanSizes(*map_, limits_, cache_ ? cache_->capacity() : 0u, layerRegions(),
                         spansByRegion(), group_size);
}

Expected<void, Error> StagedBackend::planOnDevice(const DevicePlanSizes& sizes) noexcept {
  try {
    device_planner_.emplace(*map_, planner_, cache_ ? cache_->capacity() : 0u, sizes,
                            static_cast<PlanDevice&>(*this), staging_memory_);
    if (sizes.prepare) {
      // The host's deskewing and preparation when it takes over.
      host_prepared_.resize(limits_.max_rays);
      host_rays_.resize(limits_.max_rays);
    }
  } catch (const std::bad_alloc&) {
    return fail(ErrorCode::kCapacity,
                "planning on the device: no host memory (page-locked on CUDA) for its arrays");
  }
  if (!makeCurrent() || !device_planner_->initialise() || !finish()) {
    device_planner_.reset();
    return fail(ErrorCode::kCapacity, "planning on the device: clearing its region tables failed");
  }
  return {};
}

void StagedBackend::observePlans(PlanObserver* observer) {
  plan_observer_ = observer;
  if (observer != nullptr && device_planner_ && !observed_) {
    observed_.emplace(staging_memory_);
  }
}

Expected<void, Error> StagedBackend::checkMapIsSupported() const {
  if (params_.per_scan != 0u && map_->scanMarkLayer() < 0) {
    return fail(ErrorCode::kUnsupported,
                "per-scan map without scan marks (MapConfig::device_scan_marks false, for the CPU "
                "backend only): device backends need them; create the map with them");
  }
  if (rm_map_mode_has_kernels(map_mode_) != 0) {
    return {};
  }
  return fail(ErrorCode::kUnsupported,
              "device backends have no kernels for this map's mode (mode bits " +
                  std::to_string(map_mode_) + ", kernels/common/map_mode.h): use the CPU backend");
}

std::uint32_t StagedBackend::layerRegions() const noexcept {
  return cache_ ? cache_->capacity() : map_->store().capacity();
}

std::size_t StagedBackend::counterBytes() const noexcept {
  return RM_COUNTER_COUNT * (wide_counters_ ? 8u : 4u);
}

std::size_t StagedBackend::scratchWords() const noexcept {
  // NDT maps need no tags or runs of misses (submit()); one word keeps the buffer valid (OpenCL
  // refuses empty buffers) instead of about 3 MiB a staging set.
  return ndt_ || params_.has_occupancy == 0u ? 1u
                                             : RM_SCRATCH_WORDS(limits_.max_rays, limits_.max_rays);
}

Expected<void, IntegrateError> StagedBackend::integrate(
    std::span<const PreparedRay> rays) noexcept {
  const VoxelMap::IntegrationScope integrating(*map_);
  if (!makeCurrent()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  params_.sequence = params_.per_scan != 0u ? map_->beginScan() : 0u;
  planner_.revalidate();
  auto ok = device_planner_ ? integrateDevicePlanned(rays) : integrateHostPlanned(rays);
  if (!ok) {
    return ok;
  }
  ++stats_.batches;
  return {};
}

Expected<void, IntegrateError> StagedBackend::integrateHostPlanned(
    std::span<const PreparedRay> rays) noexcept {
  while (!rays.empty()) {
    const unsigned set = next_set_;
    const Clock::time_point t_wait = Clock::now();
    if (auto ok = retire(set); !ok) {
      return ok;
    }
    const Clock::time_point t_plan = Clock::now();
    stats_.wait_seconds += std::chrono::duration<double>(t_plan - t_wait).count();
    map_->beginEpoch();  // a tiered map keeps this batch's and the in-flight batch's regions
    auto consumed = planner_.plan(rays, sets_[set].arrays);
    stats_.plan_seconds += secondsSince(t_plan);
    if (!consumed) {
      return Unexpected(consumed.error());
    }
    rays = rays.subspan(*consumed);
    if (sets_[set].arrays.rays.empty()) {
      continue;  // every ray was skipped
    }
    if (auto ok = submit(set); !ok) {
      return ok;
    }
    next_set_ = (next_set_ + 1) % kStagingSets;
  }
  return {};
}

bool StagedBackend::enqueueDevicePlan(std::span<const PreparedRay> rays, std::size_t first,
                                      unsigned* set) noexcept {
  *set = next_set_;
  next_set_ = (next_set_ + 1) % kStagingSets;
  const std::size_t count = std::min(limits_.max_rays, rays.size() - first);
  // The set's batch before last may still run: its device buffers are rewritten in queue order,
  // and its host ray array was last read by that batch's plan phase, which is done.
  return device_planner_->enqueuePlan(*set, rays.subspan(first, count), sets_[*set].arrays.rays);
}

Expected<PlanOutcome, IntegrateError> StagedBackend::awaitPlan(unsigned set,
                                                               Clock::time_point* t_plan) noexcept {
  const Clock::time_point t_wait = Clock::now();
  auto outcome = device_planner_->finishPlan(set);
  if (!outcome) {
    return outcome;
  }
  // The set's batch before last was enqueued before this plan phase: done, only counted here.
  if (auto ok = retire(set); !ok) {
    return Unexpected(ok.error());
  }
  *t_plan = Clock::now();
  stats_.wait_seconds += std::chrono::duration<double>(*t_plan - t_wait).count();
  map_->beginEpoch();
  return outcome;
}

Expected<void, IntegrateError> StagedBackend::integrateDevicePlanned(
    std::span<const PreparedRay> rays) noexcept {
  // Queue order, batch k on set k % 2: ... plan(k), resolve+kernels(k - 1), plan(k + 1),
  // resolve+kernels(k) ... The host waits for plan(k)'s read-back, enqueues plan(k + 1), then
  // places batch k's regions while the device integrates batch k - 1 and plans batch k + 1.
  if (rays.empty()) {
    return {};
  }
  unsigned set = 0;
  std::size_t first = 0;
  if (!enqueueDevicePlan(rays, 0, &set)) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  for (bool pending = true; pending;) {
    pending = false;
    Clock::time_point t_plan;
    auto outcome = awaitPlan(set, &t_plan);
    if (!outcome) {
      return Unexpected(outcome.error());
    }
    const unsigned this_set = set;
    // The next batch's plan phase goes into the queue before this batch's resolve phase, so the
    // device has work while the host places regions.
    auto plan_next = [&](std::size_t next) {
      if (next >= rays.size()) {
        return true;
      }
      first = next;
      pending = true;
      return enqueueDevicePlan(rays, next, &set);
    };
    Expected<void, IntegrateError> submitted;
    if (outcome->host_fallback) {
      if (!device_planner_->discard(this_set)) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
      auto planned = planner_.plan(rays.subspan(first), sets_[this_set].arrays);
      if (!planned) {
        return Unexpected(planned.error());
      }
      // Submitted before the next plan phase: the next batch on this set rewrites its host ray
      // array once that plan phase's read-back is in, and this batch's uploads read it.
      if (!sets_[this_set].arrays.rays.empty()) {
        submitted = submit(this_set);
      }
      if (submitted && !plan_next(first + *planned)) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
    } else {
      if (!plan_next(first + outcome->rays)) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
      auto batch = device_planner_->resolve(this_set);
      submitted = batch ? submitDevicePlanned(this_set, *batch)
                        : Expected<void, IntegrateError>(Unexpected(batch.error()));
    }
    stats_.plan_seconds += secondsSince(t_plan);
    if (!submitted) {
      return submitted;
    }
  }
  return {};
}

bool StagedBackend::preparesOnDevice(const RayFilter& filter) const noexcept {
  // NDT maps depend on where batches end (a batch's misses meet the Gaussians as they were at its
  // start), and those ends are counted in prepared rays, which only the preparation knows: the
  // host prepares for them, so the maps stay the host path's.
  return device_planner_ && device_planner_->sizes().prepare && !ndt_ &&
         filter.segment_length_m <= 0.0;
}

Expected<std::size_t, IntegrateError> StagedBackend::integrateRays(const RayPreparer& preparer,
                                                                   const rm_prepare_params& params,
                                                                   std::span<const Ray> rays,
                                                                   RayCounters& counters) noexcept {
  RAYMAP_EXPECTS(preparesOnDevice(preparer.filter()));
  const VoxelMap::IntegrationScope integrating(*map_);
  if (!makeCurrent()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  params_.sequence = params_.per_scan != 0u ? map_->beginScan() : 0u;
  planner_.revalidate();
  // A scan of more rays than a device batch holds is cut into batches by its prepared rays on
  // the host path, which the device cannot know before preparing: the host prepares it, so the
  // parts (each with per-scan semantics) are the same.
  auto integrated = params_.per_scan != 0u && rays.size() > limits_.max_rays
                        ? integrateHostPrepared(preparer, params, rays, counters)
                        : integrateDevicePrepared(preparer, params, rays, counters);
  if (integrated) {
    ++stats_.batches;
  }
  return integrated;
}

Expected<std::size_t, IntegrateError> StagedBackend::integrateHostPrepared(
    const RayPreparer& preparer, const rm_prepare_params& params, std::span<const Ray> rays,
    RayCounters& counters) noexcept {
  std::size_t integrated = 0;
  while (!rays.empty()) {
    // No segmentation (preparesOnDevice()): a ray is one prepared ray at most, so each pass
    // consumes rays until the scratch is full.
    const RayPreparer::Progress p = preparer.prepareWith(params, rays, host_prepared_, counters);
    rays = rays.subspan(p.consumed);
    if (p.written > 0) {
      // The planner copies the rays into the staging set's arrays: the scratch is free again.
      if (auto ok =
              integrateHostPlanned(std::span<const PreparedRay>(host_prepared_.data(), p.written));
          !ok) {
        return Unexpected(ok.error());
      }
      integrated += p.written;
    }
    if (p.consumed == 0) {
      break;
    }
  }
  return integrated;
}

Expected<std::size_t, IntegrateError> StagedBackend::integrateDevicePrepared(
    const RayPreparer& preparer, const rm_prepare_params& params, std::span<const Ray> rays,
    RayCounters& counters) noexcept {
  return integrateOnDevice(
      rays.size(), counters,
      [&](unsigned set, std::size_t from, std::size_t count) {
        return device_planner_->enqueuePreparePlan(set, rays.subspan(from, count), params);
      },
      [&](std::size_t first) {
        return integrateHostPrepared(preparer, params, rays.subspan(first), counters);
      });
}

bool StagedBackend::deskewsOnDevice(const RayFilter& filter, const DeskewTables& tables,
                                    std::size_t points) const noexcept {
  // Per scan, a call is one scan: more points than a device batch would be cut by prepared rays.
  return preparesOnDevice(filter) && !tables.segments.empty() &&
         tables.segments.size() <= kMaxSegments && !tables.poses.empty() &&
         tables.poses.size() <= kMaxPoseSamples &&
         (params_.per_scan == 0u || points <= limits_.max_rays);
}

Expected<std::size_t, IntegrateError> StagedBackend::integratePoints(
    const RayPreparer& preparer, const rm_prepare_params& params,
    std::span<const rm_scan_point> points, const DeskewTables& tables,
    RayCounters& counters) noexcept {
  RAYMAP_EXPECTS(deskewsOnDevice(preparer.filter(), tables, points.size()));
  const VoxelMap::IntegrationScope integrating(*map_);
  if (!makeCurrent()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  params_.sequence = params_.per_scan != 0u ? map_->beginScan() : 0u;
  planner_.revalidate();
  const std::uint64_t prepared_before = stats_.rays_prepared_on_device;
  auto integrated = integrateOnDevice(
      points.size(), counters,
      [&](unsigned set, std::size_t from, std::size_t count) {
        return device_planner_->enqueueDeskewPlan(set, points.subspan(from, count), tables, params);
      },
      [&](std::size_t first) -> Expected<std::size_t, IntegrateError> {
        // Deskewed on the host as the device would, a device batch at a time (per scan the call
        // is at most one: deskewsOnDevice()), then prepared and planned on the host.
        std::size_t done = 0;
        for (std::size_t from = first; from < points.size(); from += host_rays_.size()) {
          const std::size_t count = std::min(host_rays_.size(), points.size() - from);
          for (std::size_t i = 0; i < count; ++i) {
            host_rays_[i] = deskewedRay(points[from + i], tables);
          }
          auto part = integrateHostPrepared(
              preparer, params, std::span<const Ray>(host_rays_.data(), count), counters);
          if (!part) {
            return part;
          }
          done += *part;
        }
        return done;
      });
  stats_.points_deskewed_on_device += stats_.rays_prepared_on_device - prepared_before;
  if (integrated) {
    ++stats_.batches;
  }
  return integrated;
}

template <class Enqueue, class HostRest>
Expected<std::size_t, IntegrateError> StagedBackend::integrateOnDevice(
    std::size_t total, RayCounters& counters, Enqueue&& enqueue_batch,
    HostRest&& host_rest) noexcept {
  // The pipeline of integrateDevicePlanned(), with each batch's preparation enqueued before its
  // plan phase; its counters come back with the plan's status.
  if (total == 0) {
    return std::size_t{0};
  }
  std::size_t integrated = 0;
  std::size_t first = 0;
  unsigned set = 0;
  auto enqueue = [&](std::size_t from) {
    set = next_set_;
    next_set_ = (next_set_ + 1) % kStagingSets;
    first = from;
    return enqueue_batch(set, from, std::min(limits_.max_rays, total - from));
  };
  if (!enqueue(0)) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  for (bool pending = true; pending;) {
    pending = false;
    Clock::time_point t_plan;
    auto outcome = awaitPlan(set, &t_plan);
    if (!outcome) {
      return Unexpected(outcome.error());
    }
    const unsigned this_set = set;
    if (outcome->host_fallback) {
      // The host prepares and plans the rest of the call, exactly as on the host path (nothing of
      // this batch was counted or integrated).
      if (!device_planner_->discard(this_set)) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
      stats_.plan_seconds += secondsSince(t_plan);
      auto rest = host_rest(first);
      if (!rest) {
        return rest;
      }
      return integrated + *rest;
    }
    counters += outcome->prepared;
    stats_.rays_prepared_on_device += outcome->rays;
    // The next batch's preparation and plan phase go into the queue before this batch's resolve
    // phase, so the device has work while the host places regions.
    const std::size_t next = first + outcome->rays;
    if (next < total) {
      pending = true;
      if (!enqueue(next)) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
    }
    auto batch = device_planner_->resolve(this_set);
    auto submitted = batch ? submitDevicePlanned(this_set, *batch)
                           : Expected<void, IntegrateError>(Unexpected(batch.error()));
    stats_.plan_seconds += secondsSince(t_plan);
    if (!submitted) {
      return Unexpected(submitted.error());
    }
    integrated += batch->accepted;
  }
  return integrated;
}

Expected<void, IntegrateError> StagedBackend::synchronise() noexcept {
  const Clock::time_point start = Clock::now();
  if (!makeCurrent() || !drain()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  for (unsigned set = 0; set < kStagingSets; ++set) {
    if (auto ok = retire(set); !ok) {
      return ok;
    }
  }
  auto ok = planner_.downloadAll();
  if (ok && !drain()) {
    ok = Unexpected(IntegrateError::kDeviceFailure);
  }
  if (ok && !cache_ && !syncSharedMemory()) {
    ok = Unexpected(IntegrateError::kDeviceFailure);
  }
  stats_.sync_seconds += secondsSince(start);
  return ok;
}

BackendStats StagedBackend::stats() const noexcept {
  BackendStats s = stats_;
  if (device_planner_) {
    s.planned_on_device = true;
    s.plans_on_host = device_planner_->fallbacks();
    s.bytes_to_device += device_planner_->bytesToDevice();
    s.bytes_from_device += device_planner_->bytesFromDevice();
  }
  const PlanStats& p = planner_.stats();
  s.spans_outside_window = p.spans_outside_window;
  s.rays_skipped = p.rays_too_long;
  s.cache_hits = cache_ ? cache_->hits() : p.region_hits;
  s.cache_misses = cache_ ? cache_->misses() : p.region_misses;
  s.cache_evictions = cache_ ? cache_->evictions() : 0;
  return s;
}

Expected<void, IntegrateError> StagedBackend::download(std::uint32_t device_slot,
                                                       std::uint32_t host_slot, bool sample_layers,
                                                       bool drained) noexcept {
  return copyRegion(device_slot, host_slot, /*to_device=*/false, sample_layers, drained);
}

Expected<void, IntegrateError> StagedBackend::upload(std::uint32_t device_slot,
                                                     std::uint32_t host_slot) noexcept {
  return copyRegion(device_slot, host_slot, /*to_device=*/true);
}

Expected<void, IntegrateError> StagedBackend::fillClear(std::uint32_t device_slot,
                                                        bool zero_layers_clear) noexcept {
  const RegionStore& store = map_->store();
  for (int l = 0; l < store.schema().size(); ++l) {
    if (zero_layers_clear && store.schema().at(l).clearsToZero()) {
      continue;
    }
    const std::size_t bytes = store.layerRegionBytes(l);
    if (!fillLayer(l, bytes * device_slot, bytes, store.schema().at(l))) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
  }
  return {};
}

Expected<void, IntegrateError> StagedBackend::waitForDevice() noexcept {
  if (!drain()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  return {};
}

Expected<StagedBackend::ReadPlacement, IntegrateError> StagedBackend::placeForRead(
    std::span<const std::uint32_t> host_slots, std::span<std::uint32_t> device_slots) noexcept {
  if (!makeCurrent()) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  planner_.revalidate();
  const std::uint64_t uploaded = stats_.region_bytes_to_device;
  auto placed = planner_.placeForRead(host_slots, device_slots);
  if (!placed) {
    return Unexpected(placed.error());
  }
  return ReadPlacement{*placed, stats_.region_bytes_to_device - uploaded};
}

Expected<void, IntegrateError> StagedBackend::copyRegion(std::uint32_t device_slot,
                                                         std::uint32_t host_slot, bool to_device,
                                                         bool sample_layers,
                                                         bool drained) noexcept {
  const RegionStore& store = map_->store();
  // Evicted and wanted back before its download reached the host store.
  const bool returning = to_device && transfers_->downloadPending(host_slot);
  for (int l = 0; l < store.schema().size(); ++l) {
    if (!sample_layers && sampleLayer(store.schema().at(l).kind)) {
      continue;  // unchanged on the device since the host's copy (no sample in the region)
    }
    const std::size_t bytes = store.layerRegionBytes(l);
    std::byte* host = store.layerBytes(host_slot, l);
    // What the device copies from or into: where the layer's download lands, for a region
    // wanted back (the in-order queue runs the download first, and the copy reads that memory
    // when it runs); the host store itself for a download while the queue is drained (nothing
    // runs and nobody reads the store before the next drain); else new space in the ring, which
    // the device passes before the next batch submitted completes.
    std::byte* staged =
        returning ? transfers_->stagedDownload(host, bytes, submitted_ + 1) : nullptr;
    const bool direct = drained && !to_device;
    const bool fresh = staged == nullptr && !direct;
    if (fresh) {
      staged = transfers_->reserve(bytes, submitted_ + 1);
      if (staged == nullptr) {
        ++stats_.transfer_stalls;  // the ring is full: wait for the queue, then reuse all of it
        if (!drain() || (staged = transfers_->reserve(bytes, submitted_ + 1)) == nullptr) {
          return Unexpected(IntegrateError::kDeviceFailure);
        }
      }
      if (to_device) {
        std::memcpy(staged, host, bytes);
      }
    }
    if (!copyLayer(l, bytes * device_slot, direct ? host : staged, bytes, to_device)) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    if (fresh && !to_device) {
      transfers_->noteDownload(staged, host, bytes, host_slot);
    }
    (to_device ? stats_.bytes_to_device : stats_.bytes_from_device) += bytes;
    (to_device ? stats_.region_bytes_to_device : stats_.region_bytes_from_device) += bytes;
  }
  return {};
}

Expected<void, IntegrateError> StagedBackend::retire(unsigned set) noexcept {
  if (!sets_[set].in_flight) {
    return {};
  }
  sets_[set].in_flight = false;
  const void* counters = waitForBatch(set);
  if (counters == nullptr) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  if (transfers_) {
    transfers_->complete(sets_[set].number);  // its region moves are done
  }
  std::uint64_t visits = 0;
  std::uint64_t dropped = 0;
  if (wide_counters_) {
    const auto* words = static_cast<const std::uint64_t*>(counters);
    for (std::uint32_t b = 0; b < RM_COUNTER_BUCKETS; ++b) {
      visits += words[b];
    }
    dropped = words[RM_COUNTER_DROPPED];
  } else {
    const auto* words = static_cast<const std::uint32_t*>(counters);
    for (std::uint32_t b = 0; b < RM_COUNTER_BUCKETS; ++b) {
      visits += words[b];
    }
    dropped = words[RM_COUNTER_DROPPED];
  }
  stats_.voxels_visited += visits;
  stats_.updates_dropped += dropped;
  return {};
}

rm_integrate_params StagedBackend::launchParams(std::size_t items,
                                                std::size_t groups) const noexcept {
  rm_integrate_params p = params_;
  p.item_count = static_cast<std::uint32_t>(items);
  p.group_count = static_cast<std::uint32_t>(groups);
  return p;
}

bool StagedBackend::launchOver(OccupancyKernel kernel, unsigned set, std::size_t items,
                               std::size_t groups) noexcept {
  return items == 0 || launch(kernel, set, launchParams(items, groups));
}

bool StagedBackend::launchNdtOver(NdtKernel kernel, unsigned set, std::size_t items,
                                  std::size_t groups) noexcept {
  return items == 0 || launchNdt(kernel, set, launchParams(items, groups), ndt_params_);
}

Expected<void, IntegrateError> StagedBackend::submit(unsigned set) noexcept {
  if (grouper_) {
    grouper_->group(sets_[set].arrays);
  }
  const BatchArrays& a = sets_[set].arrays;
  if (plan_observer_ != nullptr) {
    plan_observer_->planned(a, Planning::kHost);
  }
  PlannedBatch batch;
  batch.rays = a.rays.size();
  batch.accepted = batch.rays;
  batch.spans = a.spans.size();
  // The span kernel's work-items: one per span record, or one per region.
  batch.span_items = grouper_ ? a.span_runs.size() : a.spans.size();
  batch.groups = a.groups.size();
  batch.hits = a.hit_rays.size();
  if (!uploadBatch(set, &a)) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  stats_.bytes_to_device +=
      a.rays.size() * sizeof(PreparedRay) + a.spans.size() * sizeof(rm_span_record) +
      a.span_runs.size() * sizeof(rm_span_run) + a.groups.size() * sizeof(rm_hit_group) +
      a.hit_rays.size() * sizeof(std::uint32_t);
  return launchBatch(set, batch);
}

Expected<void, IntegrateError> StagedBackend::submitDevicePlanned(
    unsigned set, const PlannedBatch& batch) noexcept {
  if (plan_observer_ != nullptr && observed_) {
    if (!device_planner_->readBack(set, batch, *observed_)) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    plan_observer_->planned(*observed_, Planning::kDevice);
  }
  if (!uploadBatch(set, nullptr)) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  return launchBatch(set, batch);
}

Expected<void, IntegrateError> StagedBackend::launchBatch(unsigned set,
                                                          const PlannedBatch& batch) noexcept {
  const std::size_t spans = batch.span_items;
  const std::size_t groups = batch.groups;
  bool ok = true;
  if (ndt_) {
    // All misses of the batch against the Gaussians as they were, then the hits voxel by voxel
    // in ray order (kernels/common/ndt.h); no scratch, no tags.
    ok = launchNdtOver(NdtKernel::kIntegrateSpans, set, spans, groups) &&
         launchNdtOver(NdtKernel::kApplyHitGroups, set, groups, groups);
  } else if (params_.has_occupancy == 0u) {
    // No occupancy to order hits and misses in (TSDF maps, decay rates only): the spans, then the
    // voxel means of the samples (TSDF batches have none).
    ok = launchOver(OccupancyKernel::kIntegrateSpans, set, spans, groups) &&
         launchOver(OccupancyKernel::kApplyHitGroups, set, groups, groups);
  } else if (params_.per_scan != 0u) {
    // Hits first: the scan mark they leave makes the misses skip those voxels (occupied wins).
    ok = launchOver(OccupancyKernel::kApplyHitGroups, set, groups, groups) &&
         launchOver(OccupancyKernel::kIntegrateSpans, set, spans, groups);
  } else {
    // Tag the voxels with samples, walk the misses (counting runs of misses between the samples
    // of tagged voxels), then replay the tagged voxels in ray order.
    const std::size_t runs = batch.hits + groups;
    ok = (runs == 0 || clearScratch(set, groups, runs)) &&
         launchOver(OccupancyKernel::kTagHitGroups, set, groups, groups) &&
         launchOver(OccupancyKernel::kIntegrateSpans, set, spans, groups) &&
         launchOver(OccupancyKernel::kApplyHitGroups, set, groups, groups);
  }
  ok = ok && endBatch(set);
  if (!ok) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  sets_[set].in_flight = true;
  sets_[set].number = ++submitted_;
  stats_.bytes_from_device += counterBytes();
  stats_.rays += batch.accepted;
  return {};
}

}  // namespace raymap::gpu
