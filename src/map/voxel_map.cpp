// SPDX-License-Identifier: BSD-3-Clause
// VoxelMap: keys, policies, queries.
#include "src/map/voxel_map.hpp"

#include <algorithm>
#include <limits>
#include <new>
#include <tuple>

#include "kernels/common/key_math.h"
#include "kernels/common/occupancy.h"
#include "kernels/common/scan_mark.h"

namespace raymap {
namespace {

rm_vec3i toKernel(Vec3i v) noexcept { return rm_vec3i{v.x, v.y, v.z}; }
Vec3i fromKernel(rm_vec3i v) noexcept { return Vec3i{v.x, v.y, v.z}; }

}  // namespace

const char* toString(StorePolicy policy) noexcept {
  return policy == StorePolicy::kRolling ? "rolling" : "global";
}

std::string mapModeName(const MapConfig& config) {
  if (!config.decay_rate) {
    return toString(config.mode);
  }
  if (!config.occupancy_layer) {
    return "decay";
  }
  return std::string(toString(config.mode)) + "+decay";
}

LayerSchema MapConfig::schema() const {
  LayerSchema schema;
  if (occupancy_layer) {
    (void)schema.add(LayerKind::kOccupancy);
  }
  if (voxel_mean) {
    (void)schema.add(LayerKind::kVoxelMean);
  }
  if (semantics == Semantics::kPerScan && device_scan_marks) {
    (void)schema.add(LayerKind::kScanMark);
  }
  if (isNdt(mode)) {
    (void)schema.add(LayerKind::kNdt);
  }
  if (mode == MapMode::kNdtTm) {
    (void)schema.add(LayerKind::kHitMiss);
    (void)schema.add(LayerKind::kIntensity);
  }
  if (decay_rate) {
    (void)schema.add(LayerKind::kTraversal);
  }
  if (mode == MapMode::kTsdf) {
    (void)schema.add(LayerKind::kTsdf);
  }
  return schema;
}

std::uint64_t MapConfig::capacityRegions() const {
  if (policy == StorePolicy::kRolling) {
    return std::uint64_t(std::max(window_regions.x, 0)) *
           std::uint64_t(std::max(window_regions.y, 0)) *
           std::uint64_t(std::max(window_regions.z, 0));
  }
  const std::uint64_t per_region = schema().bytesPerRegion(geometry.voxelsPerRegion());
  return per_region == 0 ? 0 : memory_budget_bytes / per_region;
}

Expected<void, Error> MapConfig::validateLayers() const {
  if (isNdt(mode)) {
    if (auto ok = ndt.validate(); !ok) {
      return ok;
    }
    if (semantics != Semantics::kPerRay) {
      return fail(ErrorCode::kInvalidArgument,
                  std::string(toString(mode)) +
                      " maps need per-ray semantics (each ray's miss depends on where it crosses "
                      "a voxel's Gaussian; per-scan marks would drop all but one)");
    }
    if (!occupancy_layer) {
      return fail(ErrorCode::kInvalidArgument,
                  std::string(toString(mode)) + " maps need the occupancy layer");
    }
  }
  if (mode == MapMode::kTsdf) {
    if (auto ok = tsdf.validate(geometry.resolution); !ok) {
      return ok;
    }
    if (occupancy_layer || voxel_mean || decay_rate) {
      return fail(ErrorCode::kInvalidArgument,
                  "tsdf maps hold the distance field only: no occupancy, voxel-mean or decay-rate "
                  "layer (their rays are walked on behind the surface and take no hit)");
    }
    if (semantics != Semantics::kPerRay) {
      return fail(ErrorCode::kInvalidArgument,
                  "tsdf maps need per-ray semantics (every ray's distance is averaged in)");
    }
  }
  if (decay_rate && !voxel_mean) {
    return fail(ErrorCode::kInvalidArgument,
                "decay-rate maps need the voxel-mean layer (its sample count over the traversal "
                "is the rate)");
  }
  if (decay_rate && !occupancy_layer && semantics != Semantics::kPerRay) {
    return fail(ErrorCode::kInvalidArgument,
                "decay-rate maps without occupancy need per-ray semantics (per-scan marks choose "
                "one occupancy update per voxel and scan; every ray's path counts)");
  }
  if (!occupancy_layer && !decay_rate && mode != MapMode::kTsdf) {
    return fail(ErrorCode::kInvalidArgument,
                "a map without the occupancy layer needs the traversal layer (decay rate) or the "
                "TSDF mode: it would have nothing to integrate into");
  }
  return {};
}

Expected<void, Error> MapConfig::validateStore() const {
  if (policy == StorePolicy::kRolling && tiers.enabled) {
    return fail(ErrorCode::kInvalidArgument,
                "a rolling map has no cold tiers: its window is its fixed memory");
  }
  if (policy == StorePolicy::kRolling) {
    if (window_regions.x < 1 || window_regions.y < 1 || window_regions.z < 1 ||
        window_regions.x > 4096 || window_regions.y > 4096 || window_regions.z > 4096) {
      return fail(ErrorCode::kInvalidArgument,
                  "rolling window must be 1 to 4096 regions on each axis");
    }
  }
  const std::uint64_t capacity = capacityRegions();
  if (capacity == 0) {
    const std::uint64_t per_region = schema().bytesPerRegion(geometry.voxelsPerRegion());
    return fail(ErrorCode::kInvalidArgument, "memory budget of " +
                                                 std::to_string(memory_budget_bytes) +
                                                 " bytes holds no region (one region takes " +
                                                 std::to_string(per_region) + " bytes)");
  }
  if (tiers.enabled && capacity < kMinTieredRegions) {
    return fail(ErrorCode::kInvalidArgument,
                "memory budget of " + std::to_string(memory_budget_bytes) + " bytes holds " +
                    std::to_string(capacity) + " regions; a map with cold tiers needs at least " +
                    std::to_string(kMinTieredRegions) +
                    " in its pool (a region and its neighbours are read together): raise the "
                    "memory budget (map.max_memory), or turn the tiers off (map.tiers: false)");
  }
  if (capacity > std::numeric_limits<std::uint32_t>::max() / 4u) {
    return fail(ErrorCode::kInvalidArgument,
                "the configuration asks for " + std::to_string(capacity) + " regions; at most " +
                    std::to_string(std::numeric_limits<std::uint32_t>::max() / 4u) +
                    " are supported");
  }
  return {};
}

Expected<void, Error> MapConfig::validate() const {
  if (auto ok = geometry.validate(); !ok) {
    return ok;
  }
  if (auto ok = occupancy.validate(); !ok) {
    return ok;
  }
  if (auto ok = validateLayers(); !ok) {
    return ok;
  }
  return validateStore();
}

Result<VoxelMap> VoxelMap::create(const MapConfig& config) {
  if (auto ok = config.validate(); !ok) {
    return Unexpected(ok.error());
  }
  RegionStore::Config store_config;
  store_config.schema = config.schema();
  store_config.region_voxels = config.geometry.region_voxels;
  store_config.capacity = static_cast<std::uint32_t>(config.capacityRegions());
  store_config.prefault = config.prefault;
  auto store = RegionStore::create(store_config);
  if (!store) {
    return Unexpected(store.error());
  }
  std::unique_ptr<RegionTiers> tiers;
  if (config.tiers.enabled) {
    auto created =
        RegionTiers::create(config.tiers, store_config.schema, config.geometry.voxelsPerRegion());
    if (!created) {
      return Unexpected(created.error());
    }
    tiers = std::move(created).value();
  }
  VoxelMap map(config, std::move(store).value());
  if (tiers) {
    const std::uint32_t capacity = map.store_.capacity();
    map.tiers_ = std::move(tiers);
    map.slot_epoch_.assign(capacity, 0);
    map.slot_dirty_.assign(capacity, 1);
    map.slot_pins_.assign(capacity, 0);
    map.victims_.reserve(capacity);
    map.victim_slots_.reserve(capacity);
  }
  return map;
}

VoxelMap::VoxelMap(VoxelMap&&) noexcept = default;
VoxelMap& VoxelMap::operator=(VoxelMap&&) noexcept = default;
VoxelMap::~VoxelMap() = default;

VoxelMap::VoxelMap(MapConfig config, RegionStore store) noexcept
    : config_(config), store_(std::move(store)) {
  inv_resolution_ = 1.0 / config_.geometry.resolution;
  max_voxel_coord_ = RegionStore::kMaxRegionCoord * config_.geometry.region_voxels;
  const LayerSchema& schema = store_.schema();
  occupancy_layer_ = schema.indexOf(LayerKind::kOccupancy);
  mean_layer_ = schema.indexOf(LayerKind::kVoxelMean);
  scan_mark_layer_ = schema.indexOf(LayerKind::kScanMark);
  ndt_layer_ = schema.indexOf(LayerKind::kNdt);
  hit_miss_layer_ = schema.indexOf(LayerKind::kHitMiss);
  intensity_layer_ = schema.indexOf(LayerKind::kIntensity);
  traversal_layer_ = schema.indexOf(LayerKind::kTraversal);
  tsdf_layer_ = schema.indexOf(LayerKind::kTsdf);
}

Vec3i VoxelMap::voxelOf(Vec3d p) const noexcept {
  // Multiply by the inverse resolution, as OctoMap does, so both put boundary points in the same
  // voxel (0.3 * 10 == 3 but 0.3 / 0.1 < 3 in double).
  return Vec3i{static_cast<std::int32_t>(std::floor(p.x * inv_resolution_)),
               static_cast<std::int32_t>(std::floor(p.y * inv_resolution_)),
               static_cast<std::int32_t>(std::floor(p.z * inv_resolution_))};
}

bool VoxelMap::voxelInRange(Vec3d p) const noexcept {
  for (int a = 0; a < 3; ++a) {
    if (!flooredVoxelInRange(std::floor(p[a] * inv_resolution_))) {
      return false;
    }
  }
  return true;
}

Vec3d VoxelMap::voxelMinCorner(Vec3i v) const noexcept {
  const double r = config_.geometry.resolution;
  return Vec3d{v.x * r, v.y * r, v.z * r};
}

Vec3d VoxelMap::voxelCentre(Vec3i v) const noexcept {
  const double h = 0.5 * config_.geometry.resolution;
  return voxelMinCorner(v) + Vec3d{h, h, h};
}

Vec3i VoxelMap::regionOfVoxel(Vec3i voxel) const noexcept {
  return fromKernel(rm_region_of_voxel(toKernel(voxel), config_.geometry.region_voxels));
}

Vec3i VoxelMap::voxelAt(Vec3i region, std::uint32_t index) const noexcept {
  const std::int32_t n = config_.geometry.region_voxels;
  const rm_vec3i local = rm_local_of_index(index, n);
  return Vec3i{region.x * n + local.x, region.y * n + local.y, region.z * n + local.z};
}

Expected<std::uint32_t, StoreError> VoxelMap::acquireRegion(Vec3i region) noexcept {
  if (tiers_) {
    bool created = false;
    return acquireTiered(region, /*clear=*/true, &created);
  }
  if (!inWindow(region)) {
    return Unexpected(StoreError::kOutsideWindow);
  }
  return store_.findOrCreate(region);
}

Expected<std::uint32_t, StoreError> VoxelMap::acquireRegionUncleared(Vec3i region,
                                                                     bool* created) noexcept {
  *created = false;
  if (tiers_) {
    return acquireTiered(region, /*clear=*/false, created);
  }
  if (!inWindow(region)) {
    return Unexpected(StoreError::kOutsideWindow);
  }
  return store_.findOrCreateUncleared(region, created);
}

// ---- cold tiers ----

Expected<std::uint32_t, StoreError> VoxelMap::acquireTiered(Vec3i region, bool clear,
                                                            bool* created) noexcept {
  *created = false;
  if (!RegionStore::inRange(region)) {
    return Unexpected(StoreError::kOutOfRange);
  }
  const std::uint32_t slot = store_.find(region);
  if (slot == RegionStore::kNoSlot) {
    return bringIn(region, /*create=*/true, clear, /*write=*/true, created);
  }
  slot_epoch_[slot] = epoch_;
  if (slot_dirty_[slot] == 0) {
    slot_dirty_[slot] = 1;
    try {
      tiers_->dropCopy(RegionStore::packCoord(region));
    } catch (const std::bad_alloc&) {
      // dropCopy only frees; a copy left behind is replaced at the next eviction.
    }
  }
  return slot;
}

Expected<std::uint32_t, StoreError> VoxelMap::findForWrite(Vec3i region) noexcept {
  if (!tiers_) {
    return RegionStore::inRange(region) ? store_.find(region) : RegionStore::kNoSlot;
  }
  if (!RegionStore::inRange(region)) {
    return RegionStore::kNoSlot;
  }
  if (store_.find(region) == RegionStore::kNoSlot) {
    bool created = false;
    return bringIn(region, /*create=*/false, /*clear=*/false, /*write=*/true, &created);
  }
  bool created = false;
  return acquireTiered(region, /*clear=*/false, &created);
}

Expected<std::uint32_t, StoreError> VoxelMap::residentSlot(Vec3i region) const noexcept {
  if (!RegionStore::inRange(region)) {
    return RegionStore::kNoSlot;
  }
  const std::uint32_t slot = store_.find(region);
  if (!tiers_) {
    return slot;
  }
  refuseBesideIntegration();
  if (slot != RegionStore::kNoSlot) {
    slot_epoch_[slot] = epoch_;
    return slot;
  }
  bool created = false;
  return bringIn(region, /*create=*/false, /*clear=*/false, /*write=*/false, &created);
}

Expected<std::uint32_t, StoreError> VoxelMap::bringIn(Vec3i region, bool create, bool clear,
                                                      bool write, bool* created) const noexcept {
  *created = false;
  const std::uint64_t key = RegionStore::packCoord(region);
  try {
    const bool cold = tiers_->holdsCold(key);
    if (!cold && !create) {
      return RegionStore::kNoSlot;
    }
    if (store_.size() == store_.capacity()) {
      if (auto room = makeRoom(); !room) {
        return Unexpected(room.error());
      }
    }
    bool fresh = false;
    auto slot = store_.findOrCreateUncleared(region, &fresh);
    if (!slot) {
      return slot;
    }
    if (cold) {
      auto restored = tiers_->restore(key, store_, *slot, /*keep_copy=*/!write);
      if (!restored || !*restored) {
        store_.release(*slot);
        if (restored) {
          tier_error_ = Error{ErrorCode::kCorrupt, "a cold region vanished from the tiers"};
        }
        return Unexpected(StoreError::kTierFailed);
      }
      store_.noteWritten(*slot);
      slot_dirty_[*slot] = write ? 1 : 0;
    } else {
      *created = true;
      if (clear) {
        store_.clearRegion(*slot);
      }
      slot_dirty_[*slot] = 1;
    }
    slot_epoch_[*slot] = epoch_;
    return *slot;
  } catch (const std::bad_alloc&) {
    tier_error_ = Error{ErrorCode::kCapacity, "out of memory while moving regions between tiers"};
    return Unexpected(StoreError::kTierFailed);
  }
}

Expected<void, StoreError> VoxelMap::makeRoom() const noexcept {
  victims_.clear();
  for (std::uint32_t slot = 0; slot < store_.capacity(); ++slot) {
    if (store_.inUse(slot) && slot_pins_[slot] == 0 && slot_epoch_[slot] + kept_epochs_ <= epoch_) {
      victims_.emplace_back(slot_epoch_[slot], slot);
    }
  }
  if (victims_.empty()) {
    return Unexpected(StoreError::kFull);  // every region is in use now: the pool is too small
  }
  // A burst of the least recently used: the scan above is paid once per burst, not per region.
  // No larger than the staging buffers, or the burst would wait for the compressor (measured:
  // bursts of 156 regions with 16 buffers waited 6.2 s of a 35 s run).
  const std::size_t burst = std::clamp<std::size_t>(
      std::min<std::size_t>(store_.capacity() / 16u, config_.tiers.staging_regions), 1u, 256u);
  if (victims_.size() > burst) {
    std::nth_element(victims_.begin(), victims_.begin() + static_cast<std::ptrdiff_t>(burst),
                     victims_.end());
    victims_.resize(burst);
  }
  victim_slots_.clear();
  for (const auto& [epoch, slot] : victims_) {
    victim_slots_.push_back(slot);
  }
  if (eviction_hook_ != nullptr && !eviction_hook_->beforeEviction(victim_slots_)) {
    tier_error_ = Error{ErrorCode::kIo, "the device could not write back regions leaving the pool"};
    return Unexpected(StoreError::kTierFailed);
  }
  for (const auto& [epoch, slot] : victims_) {
    auto ok = tiers_->evict(RegionStore::packCoord(store_.coordOf(slot)), store_, slot, epoch,
                            slot_dirty_[slot] != 0);
    if (!ok) {
      return Unexpected(StoreError::kTierFailed);
    }
    if (eviction_hook_ == nullptr) {
      // Not while a device may use the pool in place (or have it page-locked): the pages of
      // the sparse layers go back to the OS, so the slot's next region costs what it writes.
      store_.discardSparseLayers(slot);
    }
    store_.release(slot);
  }
  regions_recycled_ += victims_.size();  // device caches revalidate their slots
  return {};
}

void VoxelMap::pin(std::uint32_t slot) const noexcept {
  if (tiers_) {
    ++slot_pins_[slot];
  }
}

void VoxelMap::unpin(std::uint32_t slot) const noexcept {
  if (tiers_ && slot_pins_[slot] > 0) {
    --slot_pins_[slot];
  }
}

std::uint64_t VoxelMap::regionCount() const {
  return store_.size() + (tiers_ ? tiers_->coldCount() : 0u);
}

std::vector<Vec3i> VoxelMap::regionCoordsInOrder() const {
  std::vector<Vec3i> coords;
  coords.reserve(static_cast<std::size_t>(regionCount()));
  store_.forEachRegion([&](std::uint32_t, Vec3i coord) { coords.push_back(coord); });
  if (tiers_) {
    for (const std::uint64_t key : tiers_->coldKeys()) {
      coords.push_back(RegionStore::unpackCoord(key));
    }
  }
  std::sort(coords.begin(), coords.end(), [](const Vec3i& a, const Vec3i& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  return coords;
}

std::optional<RegionTierStats> VoxelMap::tierStats() const {
  if (!tiers_) {
    return std::nullopt;
  }
  return tiers_->stats();
}

std::optional<Error> VoxelMap::tierFailure() const {
  if (tiers_) {
    if (auto failure = tiers_->failure()) {
      return failure;
    }
  }
  return tier_error_;
}

Expected<void, Error> VoxelMap::drainTiers() const {
  if (!tiers_) {
    return {};
  }
  return tiers_->drain();
}

RegionCursor::RegionCursor(const VoxelMap& map) : map_(&map), coords_(map.regionCoordsInOrder()) {}

RegionCursor::~RegionCursor() { release(); }

void RegionCursor::release() noexcept {
  if (slot_ != RegionStore::kNoSlot) {
    map_->unpin(slot_);
    slot_ = RegionStore::kNoSlot;
  }
}

bool RegionCursor::next() {
  release();
  if (failure_) {
    return false;
  }
  while (next_ < coords_.size()) {
    region_ = coords_[next_++];
    map_->beginEpoch();
    auto slot = map_->residentSlot(region_);
    if (!slot) {
      failure_ = map_->tierError(slot.error());
      return false;
    }
    if (*slot != RegionStore::kNoSlot) {
      slot_ = *slot;
      map_->pin(slot_);
      return true;
    }
  }
  return false;
}

Expected<void, Error> RegionCursor::status() const {
  if (failure_) {
    return Unexpected(*failure_);
  }
  return {};
}

Error VoxelMap::tierError(StoreError error) const {
  if (error == StoreError::kTierFailed) {
    if (auto failure = tierFailure()) {
      return *failure;
    }
  }
  if (error == StoreError::kFull) {
    return Error{ErrorCode::kCapacity,
                 "every one of the pool's " + std::to_string(store_.capacity()) +
                     " regions is in use at once; raise the memory budget (map.max_memory)"};
  }
  return Error{ErrorCode::kCapacity, toString(error)};
}

std::uint32_t VoxelMap::setWindowCentre(Vec3d p) noexcept {
  if (config_.policy != StorePolicy::kRolling) {
    return 0;
  }
  const double extent = config_.geometry.regionExtent();
  Vec3i min_region;
  for (int a = 0; a < 3; ++a) {
    // Window [p - n*E/2, p + n*E/2] snapped to region boundaries.
    min_region[a] = static_cast<std::int32_t>(
        std::floor(p[a] / extent - 0.5 * config_.window_regions[a] + 0.5));
  }
  if (min_region == window_min_) {
    return 0;
  }
  window_min_ = min_region;
  std::uint32_t recycled = 0;
  for (std::uint32_t slot = 0; slot < store_.capacity(); ++slot) {
    if (store_.inUse(slot) && !inWindow(store_.coordOf(slot))) {
      store_.release(slot);
      ++recycled;
    }
  }
  regions_recycled_ += recycled;
  return recycled;
}

void VoxelMap::refuseBesideIntegration() const noexcept {
  // A query of a tiered map beside a batch in flight would move the batch's regions under it
  // (large-maps.md). Without tiers a query moves nothing.
  RAYMAP_EXPECTS((!tiers_ || !integrating()) &&
                 "a tiered map was queried while a batch integrates into it");
}

std::uint32_t VoxelMap::clearWindow() noexcept {
  if (config_.policy != StorePolicy::kRolling) {
    return 0;
  }
  const std::uint32_t released = store_.size();
  store_.clear();
  regions_recycled_ += released;
  return released;
}

std::pair<Vec3d, Vec3d> VoxelMap::windowBounds() const noexcept {
  const double e = config_.geometry.regionExtent();
  const Vec3i hi = windowMaxRegion() + Vec3i{1, 1, 1};
  return {Vec3d{window_min_.x * e, window_min_.y * e, window_min_.z * e},
          Vec3d{hi.x * e, hi.y * e, hi.z * e}};
}

std::uint32_t VoxelMap::beginScan() noexcept {
  if (scan_sequence_ >= RM_SCAN_SEQUENCE_MAX) {
    // Marks only grow; after 2^31 scans start again from clean marks.
    if (scan_mark_layer_ >= 0) {
      store_.forEachRegion(
          [&](std::uint32_t slot, Vec3i) { store_.clearLayer(slot, scan_mark_layer_); });
    }
    scan_sequence_ = 0;
  }
  return ++scan_sequence_;
}

std::optional<std::pair<std::uint32_t, std::uint32_t>> VoxelMap::locate(
    Vec3i voxel) const noexcept {
  const std::int32_t n = config_.geometry.region_voxels;
  const rm_vec3i region = rm_region_of_voxel(toKernel(voxel), n);
  std::uint32_t slot = store_.find(fromKernel(region));
  refuseBesideIntegration();
  if (slot == RegionStore::kNoSlot && tiers_) {
    // A point query holds nothing: a new epoch lets the regions earlier queries brought in go.
    beginEpoch();
    auto resident = residentSlot(fromKernel(region));
    slot = resident ? *resident : RegionStore::kNoSlot;
  } else if (tiers_) {
    slot_epoch_[slot] = epoch_;
  }
  if (slot == RegionStore::kNoSlot) {
    return std::nullopt;
  }
  const rm_vec3i local = rm_local_in_region(toKernel(voxel), region, n);
  return std::make_pair(slot, rm_local_index(local, n));
}

float VoxelMap::occupancyValue(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || occupancy_layer_ < 0) {
    return RM_OCC_UNOBSERVED;
  }
  return store_.layerData<float>(at->first, occupancy_layer_)[at->second];
}

VoxelState VoxelMap::state(Vec3i voxel) const noexcept {
  return stateOfValue(occupancyValue(voxel));
}

VoxelState VoxelMap::stateOfValue(float log_odds) const noexcept {
  if (!rm_occupancy_observed(log_odds)) {
    return VoxelState::kUnobserved;
  }
  return rm_occupancy_occupied(log_odds, config_.occupancy.threshold) ? VoxelState::kOccupied
                                                                      : VoxelState::kFree;
}

rm_voxel_mean VoxelMap::mean(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || mean_layer_ < 0) {
    return rm_voxel_mean{0u, 0u};
  }
  return store_.layerData<rm_voxel_mean>(at->first, mean_layer_)[at->second];
}

rm_ndt_voxel VoxelMap::ndt(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || ndt_layer_ < 0) {
    return rm_ndt_voxel{};
  }
  return store_.layerData<rm_ndt_voxel>(at->first, ndt_layer_)[at->second];
}

rm_ndt_hit_miss VoxelMap::hitMiss(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || hit_miss_layer_ < 0) {
    return rm_ndt_hit_miss{};
  }
  return store_.layerData<rm_ndt_hit_miss>(at->first, hit_miss_layer_)[at->second];
}

rm_ndt_intensity VoxelMap::intensity(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || intensity_layer_ < 0) {
    return rm_ndt_intensity{};
  }
  return store_.layerData<rm_ndt_intensity>(at->first, intensity_layer_)[at->second];
}

float VoxelMap::traversal(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || traversal_layer_ < 0) {
    return 0.0f;
  }
  return store_.layerData<float>(at->first, traversal_layer_)[at->second];
}

rm_tsdf_voxel VoxelMap::tsdf(Vec3i voxel) const noexcept {
  const auto at = locate(voxel);
  if (!at || tsdf_layer_ < 0) {
    return rm_tsdf_voxel{0.0f, 0.0f};
  }
  return store_.layerData<rm_tsdf_voxel>(at->first, tsdf_layer_)[at->second];
}

MapSummary VoxelMap::summarise() const {
  MapSummary s;
  const std::int32_t n = config_.geometry.region_voxels;
  const float threshold = config_.occupancy.threshold;
  Vec3i lo{std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max(),
           std::numeric_limits<std::int32_t>::max()};
  Vec3i hi{std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min(),
           std::numeric_limits<std::int32_t>::min()};
  // A tiered map's cold regions are counted too (a failure to read one back is kept in
  // tierFailure() for the caller to report).
  (void)forEachRegionInCoordOrder([&](Vec3i region, std::uint32_t slot) {
    ++s.regions;
    if (occupancy_layer_ < 0) {
      s.voxels_unobserved += config_.geometry.voxelsPerRegion();
      return;
    }
    const float* occ = store_.layerData<float>(slot, occupancy_layer_);
    std::uint32_t index = 0;
    for (std::int32_t z = 0; z < n; ++z) {
      for (std::int32_t y = 0; y < n; ++y) {
        for (std::int32_t x = 0; x < n; ++x, ++index) {
          const float v = occ[index];
          if (!rm_occupancy_observed(v)) {
            ++s.voxels_unobserved;
            continue;
          }
          if (rm_occupancy_occupied(v, threshold)) {
            ++s.voxels_occupied;
          } else {
            ++s.voxels_free;
          }
          const Vec3i voxel{region.x * n + x, region.y * n + y, region.z * n + z};
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], voxel[a]);
            hi[a] = std::max(hi[a], voxel[a]);
          }
        }
      }
    }
  });
  if (s.voxels_free + s.voxels_occupied > 0) {
    s.observed_min = voxelMinCorner(lo);
    s.observed_max = voxelMinCorner(hi + Vec3i{1, 1, 1});
  }
  return s;
}

void VoxelMap::setInfo(const std::string& key, std::string value) {
  for (auto& [k, v] : info_) {
    if (k == key) {
      v = std::move(value);
      return;
    }
  }
  info_.emplace_back(key, std::move(value));
}

}  // namespace raymap
