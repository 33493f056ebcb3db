// SPDX-License-Identifier: BSD-3-Clause
// CPU backend: single-threaded reference and region-partitioned multi-threaded integration.
#include "src/map/cpu_backend.hpp"

#include <algorithm>
#include <bit>
#include <vector>

#include "kernels/common/key_math.h"
#include "platform/process.hpp"
#include "src/map/cpu_voxel_ops.hpp"
#include "src/map/ray_region_walk.hpp"
#include "src/map/worker_pool.hpp"

namespace raymap {

const char* toString(IntegrateError error) noexcept {
  switch (error) {
    case IntegrateError::kStoreFull:
      return "region store full";
    case IntegrateError::kDeviceFailure:
      return "device failure";
  }
  return "unknown integration error";
}

namespace {

using detail::RegionLayers;

/// Remembers the last region looked up: consecutive spans and rays mostly stay in one region.
struct RegionCache {
  Vec3i region{};
  std::uint32_t slot = RegionStore::kNoSlot;
  bool valid = false;
};

/// Fixed-capacity open-addressing table: region key -> estimated work, per worker.
class RegionWorkTable {
 public:
  explicit RegionWorkTable(std::size_t max_regions) {
    const std::size_t buckets = std::bit_ceil(max_regions * 2u + 2u);
    keys_.assign(buckets, kEmpty);
    work_.assign(buckets, 0.0);
    used_.reserve(max_regions + 1u);
    mask_ = buckets - 1;
    limit_ = max_regions;
  }
  /// Adds work to a region; false when more distinct regions than the limit were seen.
  bool add(std::uint64_t key, double work) noexcept {
    std::size_t b = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
    for (;; b = (b + 1) & mask_) {
      if (keys_[b] == key) {
        work_[b] += work;
        return true;
      }
      if (keys_[b] == kEmpty) {
        if (used_.size() >= limit_) {
          return false;
        }
        keys_[b] = key;
        work_[b] = work;
        used_.push_back(b);
        return true;
      }
    }
  }
  template <class Fn>
  void forEach(Fn&& fn) const {
    for (std::size_t b : used_) {
      fn(keys_[b], work_[b]);
    }
  }
  void clear() noexcept {
    for (std::size_t b : used_) {
      keys_[b] = kEmpty;
    }
    used_.clear();
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::vector<std::uint64_t> keys_;
  std::vector<double> work_;
  std::vector<std::size_t> used_;
  std::size_t mask_ = 0;
  std::size_t limit_ = 0;
};

class CpuBackend final : public Backend {
 public:
  CpuBackend(VoxelMap& map, unsigned threads)
      : map_(map),
        n_(map.geometry().region_voxels),
        params_(map.occupancy().toKernel()),
        per_scan_(map.semantics() == Semantics::kPerScan),
        pool_(threads) {
    const std::uint32_t capacity = map.store().capacity();
    worker_stats_.assign(pool_.size(), WorkerStats{});
    if (pool_.size() > 1) {
      tables_.reserve(pool_.size());
      for (unsigned w = 0; w < pool_.size(); ++w) {
        tables_.emplace_back(capacity);
      }
      owner_.assign(capacity, kNoOwner);
      created_.assign(capacity, 0);
      slot_work_.assign(capacity, 0.0);
      touched_.reserve(capacity);
      order_.reserve(capacity);
      loads_.assign(pool_.size(), 0.0);
      overflow_flags_.assign(pool_.size(), 0);
    }
  }

  const char* name() const noexcept override { return "cpu"; }
  unsigned threads() const noexcept override { return pool_.size(); }

  Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept override {
    sequence_ = per_scan_ ? map_.beginScan() : 0u;
    Expected<void, IntegrateError> result =
        pool_.size() > 1 ? integrateParallel(rays) : integrateSerial(rays);
    for (WorkerStats& w : worker_stats_) {
      stats_.voxels_visited += w.voxels_visited;
      stats_.spans_outside_window += w.spans_outside_window;
      w = WorkerStats{};
    }
    if (result) {
      ++stats_.batches;
      stats_.rays += rays.size();
    }
    return result;
  }

  Expected<void, IntegrateError> synchronise() noexcept override { return {}; }
  BackendStats stats() const noexcept override { return stats_; }

 private:
  static constexpr std::uint8_t kNoOwner = 0xFF;

  struct WorkerStats {
    std::uint64_t voxels_visited = 0;
    std::uint64_t spans_outside_window = 0;
  };

  RegionLayers layersOf(std::uint32_t slot) const noexcept {
    const RegionStore& store = map_.store();
    RegionLayers layers;
    layers.occupancy = store.layerData<float>(slot, map_.occupancyLayer());
    if (map_.meanLayer() >= 0) {
      layers.mean = store.layerData<rm_voxel_mean>(slot, map_.meanLayer());
    }
    if (map_.scanMarkLayer() >= 0) {
      layers.marks = store.layerData<std::uint32_t>(slot, map_.scanMarkLayer());
    }
    return layers;
  }

  /// Region and in-region index of a ray's sample voxel.
  std::pair<Vec3i, std::uint32_t> sampleCell(const PreparedRay& ray) const noexcept {
    const rm_vec3i region = rm_region_of_voxel(ray.sample_voxel, n_);
    const rm_vec3i local = rm_local_of_voxel(ray.sample_voxel, n_);
    return {Vec3i{region.x, region.y, region.z}, rm_local_index(local, n_)};
  }

  /// Walks the voxels of one span with the semantics' miss rule.
  std::uint32_t missSpan(const RayRegionWalk& ray, const RaySpan& span,
                         const RegionLayers& layers) const noexcept {
    if (per_scan_) {
      return detail::walkSpan(
          ray, span, n_, detail::PerScanMiss{layers.occupancy, layers.marks, sequence_, params_});
    }
    return detail::walkSpan(ray, span, n_, detail::PerRayMiss{layers.occupancy, params_});
  }

  // ---- single-threaded reference ----

  /// Slot of a region, created on demand (cached). kNoSlot: outside the window.
  Expected<std::uint32_t, IntegrateError> acquire(Vec3i region, RegionCache* cache) noexcept {
    if (cache->valid && cache->region == region) {
      return cache->slot;
    }
    auto slot = map_.acquireRegion(region);
    if (!slot) {
      if (slot.error() == StoreError::kFull) {
        return Unexpected(IntegrateError::kStoreFull);
      }
      *cache = RegionCache{region, RegionStore::kNoSlot, true};
      return RegionStore::kNoSlot;
    }
    *cache = RegionCache{region, *slot, true};
    return *slot;
  }

  Expected<void, IntegrateError> integrateSerial(std::span<const PreparedRay> rays) noexcept {
    WorkerStats& ws = worker_stats_[0];
    RegionCache cache;
    if (per_scan_) {
      for (const PreparedRay& ray : rays) {
        if ((ray.flags & RM_RAY_END_HIT) == 0u) {
          continue;
        }
        const auto [region, index] = sampleCell(ray);
        auto slot = acquire(region, &cache);
        if (!slot) {
          return Unexpected(slot.error());
        }
        if (*slot != RegionStore::kNoSlot) {
          detail::applyScanHit(layersOf(*slot), index, sequence_, params_);
        }
      }
    }
    for (const PreparedRay& ray : rays) {
      RayRegionWalk walk(ray, n_);
      RaySpan span;
      while (walk.next(&span)) {
        auto slot = acquire(span.region, &cache);
        if (!slot) {
          return Unexpected(slot.error());
        }
        if (*slot == RegionStore::kNoSlot) {
          ++ws.spans_outside_window;
          continue;
        }
        ws.voxels_visited += missSpan(walk, span, layersOf(*slot));
      }
      if ((ray.flags & RM_RAY_END_HIT) != 0u) {
        const auto [region, index] = sampleCell(ray);
        auto slot = acquire(region, &cache);
        if (!slot) {
          return Unexpected(slot.error());
        }
        if (*slot != RegionStore::kNoSlot) {
          detail::applySampleHit(ray, layersOf(*slot), index, per_scan_, params_);
          ++ws.voxels_visited;
        }
      }
    }
    return {};
  }

  // ---- multi-threaded path ----

  Expected<void, IntegrateError> integrateParallel(std::span<const PreparedRay> rays) noexcept {
    const unsigned workers = pool_.size();
    const std::size_t count = rays.size();
    // 1. Region-level walk of every ray, in parallel: which regions, and how much work in each.
    bool table_overflow = false;
    std::vector<std::uint8_t>& overflow = overflow_flags_;
    std::fill(overflow.begin(), overflow.end(), std::uint8_t{0});
    auto survey = [&](unsigned w) {
      const std::size_t begin = count * w / workers;
      const std::size_t end = count * (w + 1) / workers;
      RegionWorkTable& table = tables_[w];
      for (std::size_t r = begin; r < end; ++r) {
        RayRegionWalk walk(rays[r], n_);
        const rm_ray_walk_frame& f = walk.frame();
        // Voxel steps of the whole ray: a span's share is proportional to its length.
        const double steps = std::abs(f.end.x - f.start.x) + std::abs(f.end.y - f.start.y) +
                             std::abs(f.end.z - f.start.z);
        RaySpan span;
        while (walk.next(&span)) {
          const double work = 1.0 + steps * static_cast<double>(span.t1 - span.t0);
          if (!table.add(RegionStore::packCoord(span.region), work)) {
            overflow[w] = 1;
            return;
          }
        }
        const auto [region, index] = sampleCell(rays[r]);
        (void)index;
        if (!table.add(RegionStore::packCoord(region), 1.0)) {
          overflow[w] = 1;
          return;
        }
      }
    };
    pool_.run(survey);
    for (std::uint8_t o : overflow) {
      table_overflow = table_overflow || o != 0;
    }
    // 2. Create the regions (serial: the store is not thread-safe for inserts) and sum the work.
    Expected<void, IntegrateError> status;
    touched_.clear();
    for (unsigned w = 0; w < workers && status && !table_overflow; ++w) {
      tables_[w].forEach([&](std::uint64_t key, double work) {
        if (!status) {
          return;
        }
        bool created = false;
        auto slot = map_.acquireRegionUncleared(RegionStore::unpackCoord(key), &created);
        if (!slot) {
          if (slot.error() == StoreError::kFull) {
            status = Unexpected(IntegrateError::kStoreFull);
          }
          return;  // outside the window: its spans are skipped and counted below
        }
        if (owner_[*slot] == kNoOwner) {
          owner_[*slot] = 0;
          slot_work_[*slot] = 0.0;
          touched_.push_back(*slot);
        }
        if (created) {
          created_[*slot] = 1;  // cleared by its owner in step 4, in parallel
        }
        slot_work_[*slot] += work;
      });
    }
    for (RegionWorkTable& table : tables_) {
      table.clear();
    }
    if (table_overflow) {
      status = Unexpected(IntegrateError::kStoreFull);
    }
    if (!status) {
      // Regions created before the failure still need their clear values.
      for (std::uint32_t slot : touched_) {
        if (created_[slot] != 0) {
          map_.store().clearRegion(slot);
          created_[slot] = 0;
        }
      }
      releaseOwners();
      return status;
    }
    // 3. Largest region first to the least-loaded worker.
    order_.clear();
    for (std::uint32_t slot : touched_) {
      order_.emplace_back(slot_work_[slot], slot);
    }
    std::sort(order_.begin(), order_.end(), [](const auto& a, const auto& b) {
      return a.first > b.first || (a.first == b.first && a.second < b.second);
    });
    std::fill(loads_.begin(), loads_.end(), 0.0);
    for (const auto& [work, slot] : order_) {
      const auto lightest =
          static_cast<std::size_t>(std::min_element(loads_.begin(), loads_.end()) - loads_.begin());
      owner_[slot] = static_cast<std::uint8_t>(lightest);
      loads_[lightest] += work;
    }
    // 4. Every worker walks the whole batch and updates only its own regions, in ray order.
    auto apply = [&](unsigned w) {
      WorkerStats& ws = worker_stats_[w];
      RegionStore& store = map_.store();
      for (std::uint32_t slot : touched_) {
        if (owner_[slot] == w && created_[slot] != 0) {
          store.clearRegion(slot);  // first touch of new regions, spread over the workers
          created_[slot] = 0;
        }
      }
      RegionCache cache;
      auto ownSlot = [&](Vec3i region) -> std::uint32_t {
        if (!(cache.valid && cache.region == region)) {
          cache = RegionCache{region, store.find(region), true};
        }
        return cache.slot;
      };
      if (per_scan_) {
        for (const PreparedRay& ray : rays) {
          if ((ray.flags & RM_RAY_END_HIT) == 0u) {
            continue;
          }
          const auto [region, index] = sampleCell(ray);
          const std::uint32_t slot = ownSlot(region);
          if (slot != RegionStore::kNoSlot && owner_[slot] == w) {
            detail::applyScanHit(layersOf(slot), index, sequence_, params_);
          }
        }
      }
      for (const PreparedRay& ray : rays) {
        RayRegionWalk walk(ray, n_);
        RaySpan span;
        while (walk.next(&span)) {
          const std::uint32_t slot = ownSlot(span.region);
          if (slot == RegionStore::kNoSlot) {
            ws.spans_outside_window += w == 0 ? 1u : 0u;  // count once
            continue;
          }
          if (owner_[slot] == w) {
            ws.voxels_visited += missSpan(walk, span, layersOf(slot));
          }
        }
        if ((ray.flags & RM_RAY_END_HIT) != 0u) {
          const auto [region, index] = sampleCell(ray);
          const std::uint32_t slot = ownSlot(region);
          if (slot != RegionStore::kNoSlot && owner_[slot] == w) {
            detail::applySampleHit(ray, layersOf(slot), index, per_scan_, params_);
            ++ws.voxels_visited;
          }
        }
      }
    };
    pool_.run(apply);
    releaseOwners();
    return {};
  }

  void releaseOwners() noexcept {
    for (std::uint32_t slot : touched_) {
      owner_[slot] = kNoOwner;
    }
    touched_.clear();
  }

  VoxelMap& map_;
  std::int32_t n_;
  rm_occupancy_params params_;
  bool per_scan_;
  std::uint32_t sequence_ = 0;
  WorkerPool pool_;
  BackendStats stats_;
  std::vector<WorkerStats> worker_stats_;
  // Multi-threaded scratch, sized at construction.
  std::vector<RegionWorkTable> tables_;
  std::vector<std::uint8_t> owner_;
  std::vector<std::uint8_t> created_;  // region created in this batch, not cleared yet
  std::vector<double> slot_work_;
  std::vector<std::uint32_t> touched_;
  std::vector<std::pair<double, std::uint32_t>> order_;
  std::vector<double> loads_;
  std::vector<std::uint8_t> overflow_flags_;
};

}  // namespace

Result<std::unique_ptr<Backend>> createCpuBackend(VoxelMap& map, const CpuBackendOptions& options) {
  unsigned threads = options.threads == 0 ? platform::availableCores() : options.threads;
  if (threads > CpuBackendOptions::kMaxThreads) {
    return fail(ErrorCode::kInvalidArgument, "threads must be at most " +
                                                 std::to_string(CpuBackendOptions::kMaxThreads) +
                                                 " (got " + std::to_string(threads) + ")");
  }
  if (map.occupancyLayer() < 0) {
    return fail(ErrorCode::kInvalidArgument, "the CPU backend needs an occupancy layer");
  }
  return std::unique_ptr<Backend>(new CpuBackend(map, threads));
}

}  // namespace raymap
