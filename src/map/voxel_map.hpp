// SPDX-License-Identifier: BSD-3-Clause
// A voxel map: geometry, occupancy parameters, layer schema and the region store under a policy
// (global or rolling window).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "raymap/error.hpp"

#include "kernels/common/voxel_mean.h"
#include "src/core/vec3.hpp"
#include "src/map/layer_schema.hpp"
#include "src/map/map_params.hpp"
#include "src/map/region_store.hpp"
#include "src/map/region_tiers.hpp"

namespace raymap {

/// How the region store is managed.
enum class StorePolicy : std::uint8_t {
  /// Offline maps: regions are created up to the pool's capacity; past it, integration fails, or
  /// with MapConfig::tiers enabled the least recently used regions move to the cold tiers.
  kGlobal = 0,
  kRolling = 1,  ///< robot-centric window that follows a centre; regions leaving it are recycled
};

const char* toString(StorePolicy policy) noexcept;

/// @brief Everything needed to build a map. Aggregate with defaults; checked by validate().
struct MapConfig {
  static constexpr std::uint64_t kDefaultMemoryBudget = std::uint64_t{4} << 30;  // 4 GiB
  /// Smallest pool a map with cold tiers may have, regions.
  static constexpr std::uint64_t kMinTieredRegions = 16;

  MapGeometry geometry;
  OccupancyParams occupancy;
  Semantics semantics = Semantics::kPerRay;
  MapMode mode = MapMode::kOccupancy;  ///< NDT modes add the NDT layers (per-ray semantics only)
  NdtParams ndt;                       ///< used by the NDT modes
  /// Used by the TSDF mode, which needs occupancy_layer and voxel_mean false (forTsdf() sets
  /// them).
  TsdfParams tsdf;
  bool voxel_mean = true;  ///< keep the voxel-mean layer
  /// Keep the traversal layer (metres of ray path per voxel) for decay rates: samples per metre
  /// (kernels/common/decay.h). Needs the voxel mean (its count is the samples). With the
  /// occupancy layer it is an occupancy map that also keeps decay rates; without it (forDecay())
  /// a decay-rate map only.
  bool decay_rate = false;
  /// Keep the occupancy layer. A map without it holds a distance field (mode kTsdf) or decay
  /// rates only (decay_rate, forDecay()); it answers occupancy queries with "unobserved", and
  /// what needs occupancy (height maps, occupied/free export) refuses it with an error.
  bool occupancy_layer = true;
  StorePolicy policy = StorePolicy::kGlobal;
  /// Global policy: the pool holds floor(memory_budget / bytes-per-region) regions.
  std::uint64_t memory_budget_bytes = kDefaultMemoryBudget;
  /// Global policy: what happens past the pool (off: integration fails with kStoreFull; on: cold
  /// regions are compressed, then spilled; docs/large-maps.md). Not for rolling maps.
  RegionTierConfig tiers;
  /// Rolling policy: window size in regions per axis (the pool holds exactly this many).
  Vec3i window_regions{16, 16, 4};
  bool prefault = false;  ///< touch all pool pages at creation (real-time users)
  /// Per-scan maps: keep the 32-bit scan-mark layer (4 bytes a voxel, never saved) with which
  /// the device backends elect one writer per voxel and scan (kernels/common/scan_mark.h). The
  /// CPU backend keeps its once-per-scan rule in a bit per voxel outside the map (ScanBits) and
  /// never reads the layer: a map only the CPU integrates can leave it out and hold a third more
  /// regions in the same memory budget (the tools and raymapd do so when the backend is the
  /// CPU). A device backend refuses a per-scan map without it, with an error that says so.
  bool device_scan_marks = true;

  Expected<void, Error> validate() const;
  /// validate()'s parts: the mode's and layers' combinations (each mode with the layers and
  /// semantics it needs), and the store (a rolling window's size, the tiers, a budget that holds
  /// regions).
  Expected<void, Error> validateLayers() const;
  Expected<void, Error> validateStore() const;
  /// @brief This configuration as a TSDF-only map: mode kTsdf, no occupancy, mean or traversal.
  MapConfig forTsdf() const {
    MapConfig c = *this;
    c.mode = MapMode::kTsdf;
    c.occupancy_layer = false;
    c.voxel_mean = false;
    c.decay_rate = false;
    return c;
  }
  /// @brief This configuration as a decay-rate-only map: the voxel mean (its sample counts) and
  /// the traversal layer, no occupancy; per-ray semantics, occupancy mode (not NDT or TSDF).
  MapConfig forDecay() const {
    MapConfig c = *this;
    c.mode = MapMode::kOccupancy;
    c.semantics = Semantics::kPerRay;
    c.occupancy_layer = false;
    c.voxel_mean = true;
    c.decay_rate = true;
    return c;
  }
  /// @brief The layer schema this configuration implies.
  LayerSchema schema() const;
  /// @brief Number of regions the pool will hold.
  std::uint64_t capacityRegions() const;
};

/// @brief The map's kind as the tools name it: "occupancy", "ndt-om", "ndt-tm", "tsdf", "decay"
/// (decay rates only: voxel mean and traversal) or "<mode>+decay" (that mode with the traversal
/// layer, e.g. "occupancy+decay").
std::string mapModeName(const MapConfig& config);

/// @brief Counts over all stored regions, and the bounds of observed voxels (world frame, metres).
struct MapSummary {
  std::uint64_t regions = 0;
  std::uint64_t voxels_free = 0;
  std::uint64_t voxels_occupied = 0;
  std::uint64_t voxels_unobserved = 0;  ///< inside stored regions
  Vec3d observed_min{};                 ///< min corner of the observed voxels (if any)
  Vec3d observed_max{};                 ///< max corner
};

/// @brief Told before a tiered map moves regions out of its pool, by whoever keeps its own copy
/// of pool slots (a device region cache): it writes back what it changed and forgets the slots.
class RegionEvictionHook {
 public:
  RegionEvictionHook() = default;
  RegionEvictionHook(const RegionEvictionHook&) = delete;
  RegionEvictionHook& operator=(const RegionEvictionHook&) = delete;
  virtual ~RegionEvictionHook() = default;
  /// @brief The regions in `slots` leave the pool once this returns true; false fails the
  /// eviction (the map reports kTierFailed).
  virtual bool beforeEviction(std::span<const std::uint32_t> slots) noexcept = 0;

 protected:
  RegionEvictionHook(RegionEvictionHook&&) = default;
  RegionEvictionHook& operator=(RegionEvictionHook&&) = default;
};

/// @brief The map. Owns its store; move-only.
/// Thread-safety: const queries may run concurrently on a map without cold tiers; on a tiered map
/// a query that reaches a cold region brings it into the pool, so every call needs exclusive
/// access. Anything that creates, recycles or updates regions needs exclusive access (the
/// backends coordinate their own workers).
class VoxelMap {
 public:
  static Result<VoxelMap> create(const MapConfig& config);

  VoxelMap(VoxelMap&&) noexcept;
  VoxelMap& operator=(VoxelMap&&) noexcept;
  VoxelMap(const VoxelMap&) = delete;
  VoxelMap& operator=(const VoxelMap&) = delete;
  ~VoxelMap();

  const MapConfig& config() const noexcept { return config_; }
  const MapGeometry& geometry() const noexcept { return config_.geometry; }
  const OccupancyParams& occupancy() const noexcept { return config_.occupancy; }
  Semantics semantics() const noexcept { return config_.semantics; }
  RegionStore& store() noexcept { return store_; }
  const RegionStore& store() const noexcept { return store_; }

  int occupancyLayer() const noexcept { return occupancy_layer_; }
  int meanLayer() const noexcept { return mean_layer_; }            ///< -1 without voxel means
  int scanMarkLayer() const noexcept { return scan_mark_layer_; }   ///< -1 for per-ray maps
  int ndtLayer() const noexcept { return ndt_layer_; }              ///< -1 unless NDT
  int hitMissLayer() const noexcept { return hit_miss_layer_; }     ///< -1 unless NDT-TM
  int intensityLayer() const noexcept { return intensity_layer_; }  ///< -1 unless NDT-TM
  int traversalLayer() const noexcept { return traversal_layer_; }  ///< -1 unless decay rate
  int tsdfLayer() const noexcept { return tsdf_layer_; }            ///< -1 unless TSDF
  MapMode mode() const noexcept { return config_.mode; }

  // ---- keys (world frame, metres) ----
  /// @brief Global voxel holding a world point: floor(p / resolution) per axis. @pre voxelInRange
  Vec3i voxelOf(Vec3d p_world) const noexcept;
  /// @brief True when p_world has a voxel whose region the store can index.
  bool voxelInRange(Vec3d p_world) const noexcept;
  /// @brief voxelInRange()'s test of one axis, on floor(coordinate / resolution) as a double
  /// (for callers that have taken the floor already). False for NaN.
  bool flooredVoxelInRange(double voxel) const noexcept {
    const double limit = static_cast<double>(max_voxel_coord_);
    return voxel > -limit && voxel < limit;
  }
  Vec3d voxelMinCorner(Vec3i voxel) const noexcept;
  Vec3d voxelCentre(Vec3i voxel) const noexcept;
  /// @brief World position (metres) of a point the layers keep in voxel units from the voxel's
  /// minimum corner (the voxel mean, an NDT Gaussian's mean).
  Vec3d pointInVoxel(Vec3i voxel, rm_vec3f local) const noexcept {
    return voxelMinCorner(voxel) + Vec3d{static_cast<double>(local.x), static_cast<double>(local.y),
                                         static_cast<double>(local.z)} *
                                       config_.geometry.resolution;
  }
  Vec3i regionOfVoxel(Vec3i voxel) const noexcept;
  /// @brief Global voxel of the voxel at linear `index` of `region` (see
  /// kernels/common/key_math.h).
  Vec3i voxelAt(Vec3i region, std::uint32_t index) const noexcept;
  /// @brief Largest |global voxel coordinate| the map accepts on any axis.
  std::int32_t maxVoxelCoord() const noexcept { return max_voxel_coord_; }

  // ---- regions under the policy ----
  /// @brief Slot of a region, created if needed. Global: kFull when the pool is exhausted.
  /// Rolling: kOutsideWindow for regions outside the window. @rt allocates: no.
  Expected<std::uint32_t, StoreError> acquireRegion(Vec3i region) noexcept;
  /// @brief acquireRegion() that leaves a created region (*created) uncleared; the caller clears
  /// it with store().clearRegion() before use (see RegionStore::findOrCreateUncleared).
  Expected<std::uint32_t, StoreError> acquireRegionUncleared(Vec3i region, bool* created) noexcept;

  // ---- cold tiers (global maps past their pool; docs/large-maps.md) ----
  /// Pool slots, region coordinates and layer pointers from store() stay valid only until the
  /// next call that may bring a region in (acquire, a query, residentSlot()), unless pinned.
  bool tiered() const noexcept { return tiers_ != nullptr; }

  /// @brief Marks a batch integrating into this map for the scope's life (backends, around each
  /// integrate call). A query of a tiered map brings regions into the pool and may evict those
  /// of a batch in flight: residentSlot() (every query, export, save and height-map plan) refuses
  /// to run meanwhile with a contract violation naming the rule, where it would otherwise corrupt
  /// the batch unseen. Tiered maps are for one thread at a time. Thread-safety: any thread.
  /// @rt allocates: no.
  class IntegrationScope {
   public:
    // acq_rel on the count, acquire in integrating(): a query that sees no batch integrating
    // also sees the writes of the batches that ended (the count is a guard for a contract
    // check, not the map's synchronisation: that is the caller's lock).
    explicit IntegrationScope(const VoxelMap& map) noexcept : count_(map.integrating_.get()) {
      if (count_ != nullptr) {
        count_->fetch_add(1, std::memory_order_acq_rel);
      }
    }
    ~IntegrationScope() {
      if (count_ != nullptr) {
        count_->fetch_sub(1, std::memory_order_acq_rel);
      }
    }
    IntegrationScope(const IntegrationScope&) = delete;
    IntegrationScope& operator=(const IntegrationScope&) = delete;

   private:
    std::atomic<int>* count_;
  };
  /// @brief Whether a batch is integrating (an IntegrationScope is alive).
  bool integrating() const noexcept {
    return integrating_ != nullptr && integrating_->load(std::memory_order_acquire) > 0;
  }
  /// @brief Regions of the map in every tier (store().size() counts the pool only).
  std::uint64_t regionCount() const;
  /// @brief Every region's coordinate, in every tier, in coordinate order (z, y, x): what exports
  /// and files walk (RegionCursor), so equal maps give equal output whatever order their regions
  /// were created in. @rt allocates: yes.
  std::vector<Vec3i> regionCoordsInOrder() const;
  /// @brief Slot of a region the map holds, brought into the pool (its cold copy kept: reading it
  /// changes nothing) when it is cold; kNoSlot when the map has no such region. kFull when every
  /// slot is pinned or used in the last two epochs. @rt allocates: only on a tiered map.
  Expected<std::uint32_t, StoreError> residentSlot(Vec3i region) const noexcept;
  /// @brief Like residentSlot(), for a region about to change (its cold copy is dropped).
  Expected<std::uint32_t, StoreError> findForWrite(Vec3i region) noexcept;
  /// @brief Starts a new access epoch. Regions used in the current epoch are never evicted (nor
  /// in the one before, after keepPreviousEpoch()): a backend calls it once per batch. Without
  /// tiers: a counter only.
  void beginEpoch() const noexcept { ++epoch_; }
  /// @brief Also keeps the regions of the previous epoch: for a device backend, whose previous
  /// batch may still be running while the next is planned.
  void keepPreviousEpoch() noexcept { kept_epochs_ = 2; }
  /// @brief Keeps a resident region in the pool until unpin() (pins nest).
  void pin(std::uint32_t slot) const noexcept;
  void unpin(std::uint32_t slot) const noexcept;
  /// @brief Calls fn(coord, slot) for every region in every tier, in coordinate order; the slot
  /// is pinned during the call. Fails when a cold region cannot be read back.
  template <class Fn>
  Expected<void, Error> forEachRegionInCoordOrder(Fn&& fn) const;
  /// @brief Statistics of the cold tiers (nullopt without tiers).
  std::optional<RegionTierStats> tierStats() const;
  /// @brief Why the last kTierFailed happened (the tiers' I/O error, or a write-back failure).
  std::optional<Error> tierFailure() const;
  /// @brief The error a StoreError from acquireRegion()/residentSlot() stands for, with the
  /// tiers' reason for kTierFailed.
  Error tierError(StoreError error) const;
  /// @brief Waits until the background compressor has caught up (statistics are then final).
  Expected<void, Error> drainTiers() const;
  /// @brief Registers the one hook told before regions leave the pool (nullptr: none).
  void setEvictionHook(RegionEvictionHook* hook) noexcept { eviction_hook_ = hook; }

  /// @brief Rolling policy: releases every region, keeping the window where it is (the robot's
  /// pose jumped: what was mapped before is in another frame). Regions are recycled as when the
  /// window moves, so device backends see the same events. @return the regions released.
  /// @rt allocates: no (the store's free list has room for every slot).
  std::uint32_t clearWindow() noexcept;

  // ---- rolling window ----
  /// @brief Moves the window so that it is centred (to the nearest region) on p_world; regions
  /// that leave it are recycled (their voxels become unobserved when reused). Global maps: no-op.
  /// @return the number of regions recycled. @rt allocates: no; O(capacity).
  std::uint32_t setWindowCentre(Vec3d p_world) noexcept;
  /// @brief Regions recycled by window moves since creation (monotone). Device backends compare it
  /// between batches to notice that cached regions left the window.
  std::uint64_t regionsRecycled() const noexcept { return regions_recycled_; }
  Vec3i windowMinRegion() const noexcept { return window_min_; }
  Vec3i windowMaxRegion() const noexcept {
    return window_min_ + config_.window_regions - Vec3i{1, 1, 1};
  }
  /// True when `r` lies in the rolling window (always for a growing map). Inline: the parallel
  /// integrator's survey asks it for every span.
  bool inWindow(Vec3i r) const noexcept {
    if (config_.policy != StorePolicy::kRolling) {
      return true;
    }
    const Vec3i hi = windowMaxRegion();
    return r.x >= window_min_.x && r.x <= hi.x && r.y >= window_min_.y && r.y <= hi.y &&
           r.z >= window_min_.z && r.z <= hi.z;
  }
  /// @brief World-frame box of the window, metres: {min corner, max corner}.
  std::pair<Vec3d, Vec3d> windowBounds() const noexcept;

  // ---- per-scan semantics ----
  /// @brief Sequence number for the next scan (starts at 1; on wrap all marks are reset).
  std::uint32_t beginScan() noexcept;

  // ---- queries ----
  float occupancyValue(Vec3i voxel) const noexcept;  ///< log-odds, +inf when unobserved
  VoxelState state(Vec3i voxel) const noexcept;
  /// @brief The state an occupancy value (log-odds) stands for under this map's threshold; what
  /// state() returns for a voxel holding it. For code that reads the occupancy layer directly.
  VoxelState stateOfValue(float log_odds) const noexcept;
  /// @brief Voxel mean of a voxel (zero count when absent or without the layer).
  rm_voxel_mean mean(Vec3i voxel) const noexcept;
  /// @brief NDT Gaussian of a voxel (count 0 when absent or without the layer).
  rm_ndt_voxel ndt(Vec3i voxel) const noexcept;
  /// @brief NDT-TM hit/miss counts and intensity of a voxel (zero when absent).
  rm_ndt_hit_miss hitMiss(Vec3i voxel) const noexcept;
  rm_ndt_intensity intensity(Vec3i voxel) const noexcept;
  /// @brief Metres of ray path inside a voxel (0 where none, or without the traversal layer).
  float traversal(Vec3i voxel) const noexcept;
  /// @brief TSDF distance (metres) and weight of a voxel (weight 0 where never updated, or
  /// without the layer).
  rm_tsdf_voxel tsdf(Vec3i voxel) const noexcept;
  /// @brief Counts over every region in every tier. On a tiered map a region that cannot be read
  /// back is left out and tierFailure() says why. @rt allocates: on a tiered map.
  MapSummary summarise() const;

  /// @brief Provenance stored with the map (source file, ray counts, ranges...), in order.
  std::vector<std::pair<std::string, std::string>>& info() noexcept { return info_; }
  const std::vector<std::pair<std::string, std::string>>& info() const noexcept { return info_; }
  void setInfo(const std::string& key, std::string value);

 private:
  VoxelMap(MapConfig config, RegionStore store) noexcept;
  /// @brief Slot and in-region index of a voxel, or nullopt if its region is absent.
  std::optional<std::pair<std::uint32_t, std::uint32_t>> locate(Vec3i voxel) const noexcept;
  /// @brief Tiered maps: the region not in the pool brought in (restored, or created when
  /// `create`); kNoSlot when absent and not created.
  Expected<std::uint32_t, StoreError> bringIn(Vec3i region, bool create, bool clear, bool write,
                                              bool* created) const noexcept;
  /// @brief Tiered maps: moves the least recently used unpinned regions to the tiers.
  Expected<void, StoreError> makeRoom() const noexcept;
  Expected<std::uint32_t, StoreError> acquireTiered(Vec3i region, bool clear,
                                                    bool* created) noexcept;

  MapConfig config_;
  // Mutable: on a tiered map, reading a cold region brings it into the pool, which changes what
  // is resident, never what the map holds.
  mutable RegionStore store_;
  double inv_resolution_ = 10.0;
  std::int32_t max_voxel_coord_ = 0;
  int occupancy_layer_ = -1;
  int mean_layer_ = -1;
  int scan_mark_layer_ = -1;
  int ndt_layer_ = -1;
  int hit_miss_layer_ = -1;
  int intensity_layer_ = -1;
  int traversal_layer_ = -1;
  int tsdf_layer_ = -1;
  Vec3i window_min_{};
  std::uint32_t scan_sequence_ = 0;
  mutable std::uint64_t regions_recycled_ = 0;
  std::vector<std::pair<std::string, std::string>> info_;
  // Cold tiers (global maps with MapConfig::tiers.enabled; empty vectors otherwise).
  std::unique_ptr<RegionTiers> tiers_;
  /// Stops the program when a tiered map is queried while a batch integrates (IntegrationScope).
  void refuseBesideIntegration() const noexcept;
  // Batches integrating now (IntegrationScope); on the heap so that the map stays movable.
  std::unique_ptr<std::atomic<int>> integrating_ = std::make_unique<std::atomic<int>>(0);
  RegionEvictionHook* eviction_hook_ = nullptr;
  mutable std::uint64_t epoch_ = 2;
  std::uint64_t kept_epochs_ = 1;                  // epochs whose regions stay in the pool
  mutable std::vector<std::uint64_t> slot_epoch_;  // epoch of each slot's last use
  mutable std::vector<std::uint8_t> slot_dirty_;   // changed since restored with its cold copy
  mutable std::vector<std::uint8_t> slot_pins_;
  mutable std::vector<std::pair<std::uint64_t, std::uint32_t>> victims_;  // (epoch, slot)
  mutable std::vector<std::uint32_t> victim_slots_;
  mutable std::optional<Error> tier_error_;  // failures outside the tiers (hook, memory)
};

/// @brief Walks every region of a map, in every tier, in coordinate order (z, y, x), so equal
/// maps give equal output whatever order their regions were created in. On a tiered map each cold
/// region is brought into the pool in turn (read-only: its cold copy is kept) and the current one
/// stays pinned until next() or the cursor's end, so a map larger than memory streams through.
/// Usage: `RegionCursor c(map); while (c.next()) { use c.region(), c.slot() } check c.status()`.
/// Thread-safety: one thread, with the map's exclusive access on a tiered map.
class RegionCursor {
 public:
  explicit RegionCursor(const VoxelMap& map);
  ~RegionCursor();
  RegionCursor(const RegionCursor&) = delete;
  RegionCursor& operator=(const RegionCursor&) = delete;
  RegionCursor(RegionCursor&&) = delete;
  RegionCursor& operator=(RegionCursor&&) = delete;

  /// @brief Moves to the next region; false at the end, or when a cold region cannot be read
  /// back (status() then says why).
  bool next();
  Vec3i region() const noexcept { return region_; }
  std::uint32_t slot() const noexcept { return slot_; }
  /// @brief Regions in the walk.
  std::size_t size() const noexcept { return coords_.size(); }
  Expected<void, Error> status() const;

 private:
  void release() noexcept;

  const VoxelMap* map_;
  std::vector<Vec3i> coords_;
  std::size_t next_ = 0;
  Vec3i region_{};
  std::uint32_t slot_ = RegionStore::kNoSlot;
  std::optional<Error> failure_;
};

template <class Fn>
Expected<void, Error> VoxelMap::forEachRegionInCoordOrder(Fn&& fn) const {
  RegionCursor cursor(*this);
  while (cursor.next()) {
    fn(cursor.region(), cursor.slot());
  }
  return cursor.status();
}

}  // namespace raymap
