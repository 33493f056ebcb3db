// SPDX-License-Identifier: BSD-3-Clause
// Planning batches on the device: sizes, kernel sequences, placement of a batch's regions.
#include "src/device/staging/device_planner.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <iterator>
#include <numeric>
#include <string>

#include "raymap/assert.hpp"

#include "kernels/common/key_math.h"

namespace raymap::gpu {
namespace {

static_assert(sizeof(rm_plan_region) == 24, "device ABI");
static_assert(sizeof(rm_plan_resolution) == 8, "device ABI");
static_assert(sizeof(rm_plan_args) == 76, "device ABI");
static_assert(RM_RADIX_BUCKETS == 1u << RM_RADIX_BITS, "one bucket per digit value");

std::uint32_t ceilDiv(std::uint32_t a, std::uint32_t b) noexcept { return (a + b - 1u) / b; }

/// Key bits a sort must look at so that every key below `limit` sorts before RM_PLAN_NONE, whose
/// low bits are all ones.
std::uint32_t bitsBelow(std::uint64_t limit) noexcept {
  return static_cast<std::uint32_t>(std::bit_width(limit));
}

}  // namespace

std::optional<Planning> planningNamed(std::string_view name) noexcept {
  if (name == "host") {
    return Planning::kHost;
  }
  if (name == "device") {
    return Planning::kDevice;
  }
  return std::nullopt;
}

const char* toString(Planning planning) noexcept {
  return planning == Planning::kDevice ? "device" : "host";
}

const char* planKernelName(PlanKernel kernel) noexcept {
  // RM_PLAN_KERNELS lists them in the order of PlanKernel.
  static constexpr const char* kNames[] = {
#define RM_PLAN_KERNEL_NAME(name) "rm_plan_" #name,
      RM_PLAN_KERNELS(RM_PLAN_KERNEL_NAME) RM_PREPARE_KERNELS(RM_PLAN_KERNEL_NAME)
#undef RM_PLAN_KERNEL_NAME
  };
  static_assert(std::size(kNames) == kPlanKernelCount, "PlanKernel and RM_PLAN_KERNELS differ");
  return kNames[static_cast<std::size_t>(kernel)];
}

std::array<std::uint32_t, kScanLevels> DevicePlanSizes::scanLevels(
    std::uint32_t elements) const noexcept {
  std::array<std::uint32_t, kScanLevels> levels{};
  std::uint32_t n = elements;
  for (unsigned l = 0; l < kScanLevels; ++l) {
    n = ceilDiv(std::max(n, 1u), tile());
    levels[l] = n;
    if (n == 1u) {
      break;
    }
  }
  return levels;
}

std::uint32_t DevicePlanSizes::longestScan() const noexcept {
  const std::uint32_t longest_sort = by_region ? std::max(max_rays, max_spans) : max_rays;
  return std::max(max_rays + 1u, RM_RADIX_BUCKETS * ceilDiv(longest_sort, tile()));
}

std::size_t DevicePlanSizes::bytes(PlanBuffer buffer) const noexcept {
  constexpr std::size_t kWord = 4;
  const std::uint32_t longest_sort = by_region ? std::max(max_rays, max_spans) : max_rays;
  const auto levels = scanLevels(longestScan());
  switch (buffer) {
    case PlanBuffer::kNone:
    case PlanBuffer::kRays:
    case PlanBuffer::kSpans:
    case PlanBuffer::kGroups:
    case PlanBuffer::kHitRays:
    case PlanBuffer::kRegionSpans:
    case PlanBuffer::kSpanRuns:
      return 0;  // the batch's own buffers, sized by the backend
    case PlanBuffer::kStatus:
      return kWord * RM_PLAN_STATUS_WORDS;
    case PlanBuffer::kCounts:
    case PlanBuffer::kOffsets:
    case PlanBuffer::kHeads:
    case PlanBuffer::kGroupIndex:
      return kWord * (std::size_t{max_rays} + 1u);
    case PlanBuffer::kCrossed:
    case PlanBuffer::kHitKeys:
    case PlanBuffer::kHitOrder:
    case PlanBuffer::kHitKeysAlt:
    case PlanBuffer::kHitOrderAlt:
      return kWord * max_rays;
    case PlanBuffer::kHistogram:
      return kWord * RM_RADIX_BUCKETS * ceilDiv(longest_sort, tile());
    case PlanBuffer::kScanSums0:
    case PlanBuffer::kScanSums1:
    case PlanBuffer::kScanSums2:
    case PlanBuffer::kScanSums3: {
      const auto level =
          static_cast<std::size_t>(buffer) - static_cast<std::size_t>(PlanBuffer::kScanSums0);
      return kWord * std::max(levels[level], 1u);
    }
    case PlanBuffer::kTable:
      return kWord * 4u * table_entries;
    case PlanBuffer::kEntryMap:
      return kWord * 2u * table_entries;
    case PlanBuffer::kRegions:
      return sizeof(rm_plan_region) * region_cap;
    case PlanBuffer::kResolution:
      return sizeof(rm_plan_resolution) * region_cap;
    case PlanBuffer::kSpanRanks:
    case PlanBuffer::kSpanOrder:
    case PlanBuffer::kSpanRanksAlt:
    case PlanBuffer::kSpanOrderAlt:
      return kWord * (by_region ? std::size_t{max_spans} : 1u);
    case PlanBuffer::kRawRays:
      return prepare ? sizeof(rm_raw_ray) * max_rays : 0u;
    case PlanBuffer::kPrepareParams:
      return prepare ? sizeof(rm_prepare_params) : 0u;
    case PlanBuffer::kOutcomes:
      return prepare ? kWord * max_rays : 0u;
    case PlanBuffer::kPoints:
      return prepare ? sizeof(rm_scan_point) * max_rays : 0u;
    case PlanBuffer::kPoseSamples:
      return prepare ? sizeof(rm_pose_sample) * kMaxPoseSamples : 0u;
    case PlanBuffer::kSegments:
      return prepare ? sizeof(rm_deskew_segment) * kMaxSegments : 0u;
  }
  return 0;
}

Result<DevicePlanSizes> devicePlanSizes(const VoxelMap& map, const BatchLimits& limits,
                                        std::uint32_t slots, std::uint32_t layer_regions,
                                        bool by_region, std::uint32_t group_size) {
  RAYMAP_EXPECTS(std::has_single_bit(group_size) && group_size >= 64 && group_size <= 256);
  DevicePlanSizes s;
  s.max_rays = static_cast<std::uint32_t>(limits.max_rays);
  s.max_spans = static_cast<std::uint32_t>(std::min<std::size_t>(limits.max_spans, 1u << 30));
  s.group_size = group_size;
  s.by_region = by_region;
  s.voxels_per_region = map.store().voxelsPerRegion();
  // Hit keys are (table entry, voxel) in 31 bits, so a sort can tell them from NONE.
  const std::uint64_t entry_limit = (std::uint64_t{1} << 31) / s.voxels_per_region;
  if (entry_limit < 1024) {
    return fail(
        ErrorCode::kUnsupported,
        "planning on the device: regions of " + std::to_string(s.voxels_per_region) +
            " voxels are too large for its 32-bit hit keys; use backend.device_planning: host");
  }
  // A batch has at most one distinct region per span record, and a cache batch no more than
  // the slots (one more is how the host learns of a batch that does not fit).
  const std::uint64_t most_regions =
      std::min<std::uint64_t>(s.max_spans, slots > 0 ? std::uint64_t{slots} + 1u : layer_regions);
  std::uint64_t entries = std::bit_ceil(std::max<std::uint64_t>(1024, 2u * most_regions));
  entries = std::min<std::uint64_t>(entries, std::bit_floor(entry_limit));
  s.table_entries = static_cast<std::uint32_t>(entries);
  s.region_cap = static_cast<std::uint32_t>(std::min<std::uint64_t>(entries, most_regions));
  if (s.scanLevels(s.longestScan())[kScanLevels - 1] > 1u) {
    return fail(ErrorCode::kUnsupported,
                "planning on the device: batches of " + std::to_string(s.max_spans) +
                    " span records need more scan levels than it has; lower queues.batch_rays");
  }
  return s;
}

DevicePlanner::DevicePlanner(VoxelMap& map, BatchPlanner& planner, std::uint32_t cache_slots,
                             const DevicePlanSizes& sizes, PlanDevice& device,
                             std::pmr::memory_resource* memory)
    : map_(&map),
      planner_(&planner),
      cache_slots_(cache_slots),
      sizes_(sizes),
      device_(&device),
      sets_{SetState(memory), SetState(memory)} {
  for (SetState& s : sets_) {
    s.regions.resize(sizes.region_cap);
    s.resolution.resize(sizes.region_cap);
    s.runs.reserve(sizes.by_region ? sizes.region_cap : 0u);
    s.raw.reserve(sizes.prepare ? sizes.max_rays : 0u);
    s.points.reserve(sizes.prepare ? sizes.max_rays : 0u);
    s.samples.reserve(sizes.prepare ? kMaxPoseSamples : 0u);
    s.segments.reserve(sizes.prepare ? kMaxSegments : 0u);
  }
  order_.reserve(sizes.region_cap);
  read_ahead_ = std::min(read_ahead_, sizes.region_cap);
}

rm_plan_args DevicePlanner::baseArgs(const SetState& state) const noexcept {
  rm_plan_args a{};
  a.region_voxels = map_->geometry().region_voxels;
  a.voxels_per_region = sizes_.voxels_per_region;
  a.max_spans = sizes_.max_spans;
  a.table_mask = sizes_.table_entries - 1u;
  a.table_shift = 32u - static_cast<std::uint32_t>(std::countr_zero(sizes_.table_entries));
  a.region_cap = sizes_.region_cap;
  a.rolling = map_->config().policy == StorePolicy::kRolling ? 1u : 0u;
  const Vec3i lo = map_->windowMinRegion();
  const Vec3i hi = map_->windowMaxRegion();
  a.window_lo = rm_vec3i_make(lo.x, lo.y, lo.z);
  a.window_hi = rm_vec3i_make(hi.x, hi.y, hi.z);
  a.key_origin = state.key_origin;
  return a;
}

bool DevicePlanner::launch(unsigned set, PlanKernel kernel, const rm_plan_args& args,
                           std::uint32_t items,
                           std::initializer_list<PlanBuffer> buffers) noexcept {
  PlanLaunch l;
  l.kernel = kernel;
  l.args = args;
  l.items = std::max(items, 1u);
  RAYMAP_DEBUG_ASSERT(buffers.size() <= l.buffers.size());
  std::copy(buffers.begin(), buffers.end(), l.buffers.begin());
  return device_->launchPlan(set, l);
}

bool DevicePlanner::scan(unsigned set, PlanBuffer in, PlanBuffer out, std::uint32_t n) noexcept {
  // Level l scans its input (the array, then the level below's tile sums, in place) and writes
  // its tile sums into kScanSums<l>; the top level is one tile. The tile offsets are then added
  // back from the top down.
  const auto tiles = sizes_.scanLevels(n);
  const auto levels =
      static_cast<unsigned>(std::find(tiles.begin(), tiles.end(), 1u) - tiles.begin() + 1);
  if (levels > kScanLevels) {
    return false;  // more levels than devicePlanSizes() allows for
  }
  auto sums = [](unsigned l) {
    return static_cast<PlanBuffer>(static_cast<unsigned>(PlanBuffer::kScanSums0) + l);
  };
  auto input = [&](unsigned l) { return l == 0 ? in : sums(l - 1); };
  auto output = [&](unsigned l) { return l == 0 ? out : sums(l - 1); };
  rm_plan_args a{};
  for (unsigned l = 0; l < levels; ++l) {
    a.n = l == 0 ? n : tiles[l - 1];
    if (!launch(set, PlanKernel::kScanTiles, a, tiles[l] * sizes_.group_size,
                {input(l), output(l), sums(l)})) {
      return false;
    }
  }
  for (unsigned l = levels - 1; l-- > 0;) {
    a.n = l == 0 ? n : tiles[l - 1];
    if (!launch(set, PlanKernel::kScanAdd, a, tiles[l] * sizes_.group_size, {output(l), sums(l)})) {
      return false;
    }
  }
  return true;
}

bool DevicePlanner::sort(unsigned set, std::uint32_t n, std::uint32_t bits, PlanBuffer* keys,
                         PlanBuffer* values, PlanBuffer keys_alt, PlanBuffer values_alt) noexcept {
  if (n == 0) {
    return true;
  }
  rm_plan_args a{};
  a.n = n;
  a.tiles = ceilDiv(n, sizes_.tile());
  for (a.shift = 0; a.shift < bits; a.shift += RM_RADIX_BITS) {
    const std::uint32_t items = a.tiles * sizes_.group_size;
    if (!launch(set, PlanKernel::kRadixHistogram, a, items, {*keys, PlanBuffer::kHistogram}) ||
        !scan(set, PlanBuffer::kHistogram, PlanBuffer::kHistogram, RM_RADIX_BUCKETS * a.tiles) ||
        !launch(set, PlanKernel::kRadixScatter, a, items,
                {*keys, *values, PlanBuffer::kHistogram, keys_alt, values_alt})) {
      return false;
    }
    std::swap(*keys, keys_alt);
    std::swap(*values, values_alt);
  }
  return true;
}

bool DevicePlanner::initialise() noexcept {
  rm_plan_args a{};
  a.table_mask = sizes_.table_entries - 1u;
  for (unsigned set = 0; set < sets_.size(); ++set) {
    if (!launch(set, PlanKernel::kClearTable, a, sizes_.table_entries, {PlanBuffer::kTable})) {
      return false;
    }
  }
  return true;
}

bool DevicePlanner::enqueuePlan(unsigned set, std::span<const PreparedRay> rays,
                                std::pmr::vector<PreparedRay>& staging) noexcept {
  RAYMAP_EXPECTS(!rays.empty() && rays.size() <= sizes_.max_rays);
  SetState& st = sets_[set];
  st.rays = static_cast<std::uint32_t>(rays.size());
  st.regions_read = 0;
  st.key_origin = rm_region_of_voxel(rays.front().origin_voxel, map_->geometry().region_voxels);
  st.prepared = false;
  staging.assign(rays.begin(), rays.end());  // reserved for max_rays: no allocation
  bytes_to_device_ += staging.size() * sizeof(PreparedRay);
  return device_->writePlanBuffer(set, PlanBuffer::kRays, 0, staging.data(),
                                  staging.size() * sizeof(PreparedRay)) &&
         enqueuePlanPhase(set);
}

bool DevicePlanner::enqueuePreparePlan(unsigned set, std::span<const Ray> rays,
                                       const rm_prepare_params& params) noexcept {
  RAYMAP_EXPECTS(sizes_.prepare && !rays.empty() && rays.size() <= sizes_.max_rays);
  SetState& st = sets_[set];
  st.rays = static_cast<std::uint32_t>(rays.size());
  st.regions_read = 0;
  st.prepared = true;
  // The region keys of the plan are taken relative to the first ray's origin that has a voxel;
  // any nearby region serves (a batch reaching further than the keys do is planned on the host).
  st.key_origin = rm_vec3i_make(0, 0, 0);
  for (const Ray& ray : rays) {
    rm_vec3i voxel;
    rm_vec3f local;
    if (rm_prepare_key(&params, rm_vec3d{ray.origin.x, ray.origin.y, ray.origin.z}, &voxel,
                       &local)) {
      st.key_origin = rm_region_of_voxel(voxel, map_->geometry().region_voxels);
      break;
    }
  }
  // Ray and rm_raw_ray have one layout (src/map/ray_preparer.hpp): one copy, no conversion.
  st.raw.resize(rays.size());  // reserved for max_rays: no allocation
  std::memcpy(st.raw.data(), rays.data(), rays.size() * sizeof(rm_raw_ray));
  bytes_to_device_ += rays.size() * sizeof(rm_raw_ray);
  return device_->writePlanBuffer(set, PlanBuffer::kRawRays, 0, st.raw.data(),
                                  st.raw.size() * sizeof(rm_raw_ray)) &&
         enqueuePrepareAndPlan(set, params);
}

bool DevicePlanner::enqueueDeskewPlan(unsigned set, std::span<const rm_scan_point> points,
                                      const DeskewTables& tables,
                                      const rm_prepare_params& params) noexcept {
  RAYMAP_EXPECTS(sizes_.prepare && !points.empty() && points.size() <= sizes_.max_rays &&
                 !tables.segments.empty() && tables.segments.size() <= kMaxSegments &&
                 !tables.poses.empty() && tables.poses.size() <= kMaxPoseSamples);
  SetState& st = sets_[set];
  st.rays = static_cast<std::uint32_t>(points.size());
  st.regions_read = 0;
  st.prepared = true;
  // The region keys are taken relative to the base's first pose of the points' first segment:
  // any region near the batch serves.
  const rm_vec3d base =
      tables.poses[tables.segments[points.front().segment].first_pose].pose.position;
  rm_vec3i voxel;
  rm_vec3f local;
  st.key_origin = rm_prepare_key(&params, base, &voxel, &local)
                      ? rm_region_of_voxel(voxel, map_->geometry().region_voxels)
                      : rm_vec3i_make(0, 0, 0);
  // Reserved for max_rays, kMaxPoseSamples and kMaxSegments: no allocation.
  st.points.assign(points.begin(), points.end());
  st.samples.assign(tables.poses.begin(), tables.poses.end());
  st.segments.assign(tables.segments.begin(), tables.segments.end());
  rm_plan_args a = baseArgs(st);
  a.n = st.rays;
  bytes_to_device_ +=
      points.size_bytes() + tables.poses.size_bytes() + tables.segments.size_bytes();
  return device_->writePlanBuffer(set, PlanBuffer::kPoints, 0, st.points.data(),
                                  points.size_bytes()) &&
         device_->writePlanBuffer(set, PlanBuffer::kPoseSamples, 0, st.samples.data(),
                                  tables.poses.size_bytes()) &&
         device_->writePlanBuffer(set, PlanBuffer::kSegments, 0, st.segments.data(),
                                  tables.segments.size_bytes()) &&
         launch(set, PlanKernel::kDeskew, a, st.rays,
                {PlanBuffer::kPoints, PlanBuffer::kPoseSamples, PlanBuffer::kSegments,
                 PlanBuffer::kRawRays}) &&
         enqueuePrepareAndPlan(set, params);
}

bool DevicePlanner::enqueuePrepareAndPlan(unsigned set, const rm_prepare_params& params) noexcept {
  SetState& st = sets_[set];
  st.params[0] = params;
  rm_plan_args a = baseArgs(st);
  a.n = st.rays;
  bytes_to_device_ += sizeof(rm_prepare_params);
  return device_->writePlanBuffer(set, PlanBuffer::kPrepareParams, 0, st.params.data(),
                                  sizeof(rm_prepare_params)) &&
         launch(set, PlanKernel::kPrepare, a, st.rays,
                {PlanBuffer::kRawRays, PlanBuffer::kPrepareParams, PlanBuffer::kRays,
                 PlanBuffer::kOutcomes}) &&
         enqueuePlanPhase(set);
}

bool DevicePlanner::enqueuePlanPhase(unsigned set) noexcept {
  SetState& st = sets_[set];
  rm_plan_args a = baseArgs(st);
  const std::uint32_t n = st.rays;
  a.n = n;
  PlanBuffer keys = PlanBuffer::kHitKeys;
  PlanBuffer order = PlanBuffer::kHitOrder;
  const std::uint32_t key_bits =
      bitsBelow(std::uint64_t{sizes_.table_entries} * sizes_.voxels_per_region);
  bool ok =
      launch(set, PlanKernel::kBegin, a, 1, {PlanBuffer::kStatus}) &&
      launch(set, PlanKernel::kCount, a, n + 1u,
             {PlanBuffer::kRays, PlanBuffer::kCounts, PlanBuffer::kCrossed}) &&
      scan(set, PlanBuffer::kCounts, PlanBuffer::kOffsets, n + 1u) &&
      launch(set, PlanKernel::kCut, a, n,
             {PlanBuffer::kOffsets, PlanBuffer::kCrossed, PlanBuffer::kStatus}) &&
      launch(
          set, PlanKernel::kEmit, a, n,
          {PlanBuffer::kRays, PlanBuffer::kCounts, PlanBuffer::kOffsets, PlanBuffer::kSpans,
           PlanBuffer::kTable, PlanBuffer::kHitKeys, PlanBuffer::kHitOrder, PlanBuffer::kStatus}) &&
      sort(set, n, key_bits, &keys, &order, PlanBuffer::kHitKeysAlt, PlanBuffer::kHitOrderAlt);
  a.n = n;
  if (st.prepared) {
    ok = ok &&
         launch(set, PlanKernel::kPrepareCount, a, n, {PlanBuffer::kOutcomes, PlanBuffer::kStatus});
  }
  ok =
      ok && launch(set, PlanKernel::kGroupHeads, a, n + 1u, {keys, PlanBuffer::kHeads}) &&
      scan(set, PlanBuffer::kHeads, PlanBuffer::kGroupIndex, n + 1u) &&
      launch(set, PlanKernel::kGroupBuild, a, n,
             {keys, order, PlanBuffer::kHeads, PlanBuffer::kGroupIndex, PlanBuffer::kGroups,
              PlanBuffer::kHitRays}) &&
      launch(set, PlanKernel::kCompact, a, sizes_.table_entries,
             {PlanBuffer::kTable, PlanBuffer::kSpans, PlanBuffer::kRegions, PlanBuffer::kStatus}) &&
      launch(set, PlanKernel::kFinish, a, 1,
             {PlanBuffer::kOffsets, PlanBuffer::kGroupIndex, PlanBuffer::kStatus});
  // The status and, speculatively, as many region records as the last batches had.
  st.regions_read = read_ahead_;
  bytes_from_device_ += RM_PLAN_STATUS_WORDS * sizeof(std::uint32_t) +
                        std::size_t{st.regions_read} * sizeof(rm_plan_region);
  return ok &&
         device_->readPlanBuffer(set, PlanBuffer::kStatus, 0, st.status.data(),
                                 RM_PLAN_STATUS_WORDS * sizeof(std::uint32_t)) &&
         device_->readPlanBuffer(set, PlanBuffer::kRegions, 0, st.regions.data(),
                                 st.regions_read * sizeof(rm_plan_region)) &&
         device_->markPlanRead(set);
}

Expected<PlanOutcome, IntegrateError> DevicePlanner::finishPlan(unsigned set) noexcept {
  SetState& st = sets_[set];
  if (!device_->waitPlanRead(set)) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  const std::uint32_t cut = st.status[RM_PLAN_STATUS_CUT_RAY];
  const std::uint32_t rays = std::min(cut, st.rays);
  const std::uint32_t regions = st.status[RM_PLAN_STATUS_REGIONS];
  auto fallback = [this]() -> PlanOutcome {
    ++fallbacks_;
    return PlanOutcome{true, 0, {}};
  };
  if (st.status[RM_PLAN_STATUS_FAULT] != 0u || rays == 0u || regions > sizes_.region_cap ||
      (cache_slots_ > 0 && regions > cache_slots_)) {
    return fallback();
  }
  if (regions > st.regions_read) {
    const std::size_t more = regions - st.regions_read;
    if (!device_->readPlanBuffer(
            set, PlanBuffer::kRegions, st.regions_read * sizeof(rm_plan_region),
            st.regions.data() + st.regions_read, more * sizeof(rm_plan_region)) ||
        !device_->markPlanRead(set) || !device_->waitPlanRead(set)) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    bytes_from_device_ += more * sizeof(rm_plan_region);
  }
  st.regions_read = regions;
  read_ahead_ =
      std::clamp(regions + regions / 2u, std::min(256u, sizes_.region_cap), sizes_.region_cap);
  for (std::uint32_t k = 0; k < regions; ++k) {
    const rm_vec3i r = rm_plan_key_region(st.regions[k].key, st.key_origin);
    const Vec3i region{r.x, r.y, r.z};
    if (!RegionStore::inRange(region) || !map_->inWindow(region)) {
      return fallback();  // not for a device plan: the host planner counts such spans
    }
  }
  PlanOutcome outcome{false, rays, {}};
  if (st.prepared) {
    RayCounters& c = outcome.prepared;
    c.rays_in = rays;
    c.rays_accepted = st.status[RM_PLAN_STATUS_ACCEPTED];
    c.rays_invalid = st.status[RM_PLAN_STATUS_INVALID];
    c.rays_too_short = st.status[RM_PLAN_STATUS_TOO_SHORT];
    c.rays_out_of_bounds = st.status[RM_PLAN_STATUS_OUT_OF_BOUNDS];
    c.rays_outside_window = st.status[RM_PLAN_STATUS_OUTSIDE_WINDOW];
    c.rays_clipped = st.status[RM_PLAN_STATUS_CLIPPED];
    c.rays_no_return = st.status[RM_PLAN_STATUS_NO_RETURN];
    c.pieces_out = c.rays_accepted;  // no segmentation on the device
  }
  return outcome;
}

bool DevicePlanner::discard(unsigned set) noexcept {
  rm_plan_args a{};
  a.table_mask = sizes_.table_entries - 1u;
  return launch(set, PlanKernel::kClearTable, a, sizes_.table_entries, {PlanBuffer::kTable});
}

Expected<PlannedBatch, IntegrateError> DevicePlanner::resolve(unsigned set) noexcept {
  SetState& st = sets_[set];
  const std::uint32_t regions = st.regions_read;
  planner_->beginDevicePlanned();
  planner_->countSpansOutside(st.status[RM_PLAN_STATUS_OUTSIDE]);
  // Placed in the order of first appearance, as the host planner meets them.
  order_.resize(regions);
  std::iota(order_.begin(), order_.end(), 0u);
  std::sort(order_.begin(), order_.end(), [&st](std::uint32_t a, std::uint32_t b) {
    return st.regions[a].first_span < st.regions[b].first_span;
  });
  for (const std::uint32_t k : order_) {
    const rm_plan_region& r = st.regions[k];
    const rm_vec3i c = rm_plan_key_region(r.key, st.key_origin);
    auto slot = planner_->placeDevicePlanned(Vec3i{c.x, c.y, c.z}, r.spans, r.hits);
    if (!slot) {
      return Unexpected(slot.error());
    }
    st.resolution[k] = rm_plan_resolution{*slot, 0u};
  }
  const std::uint32_t spans = st.status[RM_PLAN_STATUS_SPANS];
  if (sizes_.by_region) {
    // Runs as RegionSpanGrouper orders them: most spans first, ties in order of first appearance.
    std::sort(order_.begin(), order_.end(), [&st](std::uint32_t a, std::uint32_t b) {
      const rm_plan_region& ra = st.regions[a];
      const rm_plan_region& rb = st.regions[b];
      return ra.spans != rb.spans ? ra.spans > rb.spans : ra.first_span < rb.first_span;
    });
    st.runs.resize(regions);
    std::uint32_t first = 0;
    for (std::uint32_t rank = 0; rank < regions; ++rank) {
      const rm_plan_region& r = st.regions[order_[rank]];
      st.resolution[order_[rank]].rank = rank;
      st.runs[rank] = rm_span_run{first, r.spans};
      first += r.spans;
    }
  }
  bytes_to_device_ +=
      regions * (sizeof(rm_plan_resolution) + (sizes_.by_region ? sizeof(rm_span_run) : 0u));
  rm_plan_args a = baseArgs(st);
  a.n = regions;
  bool ok =
      device_->writePlanBuffer(set, PlanBuffer::kResolution, 0, st.resolution.data(),
                               regions * sizeof(rm_plan_resolution)) &&
      (!sizes_.by_region || device_->writePlanBuffer(set, PlanBuffer::kSpanRuns, 0, st.runs.data(),
                                                     regions * sizeof(rm_span_run))) &&
      launch(set, PlanKernel::kResolveRegions, a, regions,
             {PlanBuffer::kRegions, PlanBuffer::kResolution, PlanBuffer::kEntryMap}) &&
      launch(set, PlanKernel::kClearRegions, a, regions,
             {PlanBuffer::kRegions, PlanBuffer::kTable});
  a.n = spans;
  a.shift = sizes_.by_region ? 1u : 0u;
  ok = ok && launch(set, PlanKernel::kResolveSpans, a, spans,
                    {PlanBuffer::kSpans, PlanBuffer::kEntryMap, PlanBuffer::kSpanRanks,
                     PlanBuffer::kSpanOrder});
  a.n = st.status[RM_PLAN_STATUS_GROUPS];
  ok = ok && launch(set, PlanKernel::kResolveGroups, a, a.n,
                    {PlanBuffer::kGroups, PlanBuffer::kEntryMap});
  if (ok && sizes_.by_region) {
    PlanBuffer ranks = PlanBuffer::kSpanRanks;
    PlanBuffer span_order = PlanBuffer::kSpanOrder;
    ok = sort(set, spans, regions > 1u ? bitsBelow(regions - 1u) : 0u, &ranks, &span_order,
              PlanBuffer::kSpanRanksAlt, PlanBuffer::kSpanOrderAlt);
    a.n = spans;
    ok = ok && launch(set, PlanKernel::kGatherSpans, a, spans,
                      {PlanBuffer::kSpans, span_order, PlanBuffer::kRegionSpans});
  }
  if (!ok) {
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  PlannedBatch b;
  b.rays = std::min(st.status[RM_PLAN_STATUS_CUT_RAY], st.rays);
  b.accepted = st.prepared ? st.status[RM_PLAN_STATUS_ACCEPTED] : b.rays;
  b.spans = spans;
  b.span_items = sizes_.by_region ? regions : spans;
  b.groups = st.status[RM_PLAN_STATUS_GROUPS];
  b.hits = st.status[RM_PLAN_STATUS_HITS];
  return b;
}

bool DevicePlanner::readBack(unsigned set, const PlannedBatch& batch, BatchArrays& out) noexcept {
  out.clear();
  out.rays.resize(batch.rays);
  out.spans.resize(batch.spans);
  out.groups.resize(batch.groups);
  out.hit_rays.resize(batch.hits);
  if (sizes_.by_region) {
    out.region_spans.resize(batch.spans);
    out.span_runs.assign(sets_[set].runs.begin(), sets_[set].runs.end());
  }
  auto read = [&](PlanBuffer buffer, void* host, std::size_t bytes) {
    return bytes == 0 || device_->readPlanBuffer(set, buffer, 0, host, bytes);
  };
  return read(PlanBuffer::kRays, out.rays.data(), out.rays.size() * sizeof(PreparedRay)) &&
         read(PlanBuffer::kSpans, out.spans.data(), out.spans.size() * sizeof(rm_span_record)) &&
         read(PlanBuffer::kGroups, out.groups.data(), out.groups.size() * sizeof(rm_hit_group)) &&
         read(PlanBuffer::kHitRays, out.hit_rays.data(),
              out.hit_rays.size() * sizeof(std::uint32_t)) &&
         read(PlanBuffer::kRegionSpans, out.region_spans.data(),
              out.region_spans.size() * sizeof(rm_span_record)) &&
         device_->markPlanRead(set) && device_->waitPlanRead(set);
}

}  // namespace raymap::gpu
