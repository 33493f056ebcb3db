// SPDX-License-Identifier: BSD-3-Clause
// Region-partitioned multi-threaded integration.
#include "src/map/cpu_parallel.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace raymap::detail {

ParallelIntegrator::WorkTable::WorkTable(std::size_t max_regions) {
  const std::size_t buckets = std::bit_ceil(max_regions * 2u + 2u);
  keys_.assign(buckets, kEmpty);
  work_.assign(buckets, 0.0);
  used_.reserve(max_regions + 1u);
  mask_ = buckets - 1;
  limit_ = max_regions;
  front_keys_.fill(kEmpty);
}

bool ParallelIntegrator::WorkTable::add(std::uint64_t key, double work) noexcept {
  const std::size_t f = directMappedIndex(key);
  if (front_keys_[f] == key) {
    front_work_[f] += work;
    return true;
  }
  const bool ok = front_keys_[f] == kEmpty || addToTable(front_keys_[f], front_work_[f]);
  front_keys_[f] = key;
  front_work_[f] = work;
  return ok;
}

bool ParallelIntegrator::WorkTable::flush() noexcept {
  bool ok = true;
  for (std::size_t f = 0; f < kFrontEntries; ++f) {
    if (front_keys_[f] != kEmpty) {
      ok = addToTable(front_keys_[f], front_work_[f]) && ok;
      front_keys_[f] = kEmpty;
    }
  }
  return ok;
}

bool ParallelIntegrator::WorkTable::addToTable(std::uint64_t key, double work) noexcept {
  for (std::size_t b = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;;
       b = (b + 1) & mask_) {
    if (keys_[b] == key) {
      work_[b] += work;
      return true;
    }
    if (keys_[b] == kEmpty) {
      if (used_.size() >= limit_) {
        return false;  // more regions than the store can hold: the batch cannot fit
      }
      keys_[b] = key;
      work_[b] = work;
      used_.push_back(b);
      return true;
    }
  }
}

void ParallelIntegrator::WorkTable::clear() noexcept {
  for (std::size_t b : used_) {
    keys_[b] = kEmpty;
  }
  used_.clear();
  front_keys_.fill(kEmpty);
}

ParallelIntegrator::ParallelIntegrator(unsigned workers, std::uint32_t store_capacity,
                                       std::size_t expected_batch_rays)
    : pool_(workers) {
  const unsigned n = pool_.size();
  tables_.reserve(n);
  spans_.resize(n);
  for (unsigned w = 0; w < n; ++w) {
    tables_.emplace_back(store_capacity);
    spans_[w].reserve(expected_batch_rays * 6u / n + 1024u);
  }
  overflow_.assign(n, 0);
  rays_.resize(expected_batch_rays);
  owner_.assign(store_capacity, kNoOwner);
  created_.assign(store_capacity, 0);
  slot_work_.assign(store_capacity, 0.0);
  touched_.reserve(store_capacity);
  order_.reserve(store_capacity);
  loads_.assign(n, 0.0);
}

std::pair<std::size_t, std::size_t> ParallelIntegrator::rangeOf(unsigned worker,
                                                                std::size_t count) const noexcept {
  const std::size_t n = pool_.size();
  return {count * worker / n, count * (worker + 1u) / n};
}

void ParallelIntegrator::releaseOwners() noexcept {
  for (std::uint32_t slot : touched_) {
    owner_[slot] = kNoOwner;
  }
  touched_.clear();
}

Expected<void, IntegrateError> ParallelIntegrator::integrate(
    const IntegrationContext& ctx, std::span<const PreparedRay> rays,
    std::span<RegionSlotCache> caches, std::span<WorkerStats> stats) noexcept {
  VoxelMap& map = *ctx.map;
  const unsigned workers = pool_.size();
  if (rays_.size() < rays.size()) {
    rays_.resize(rays.size());  // a batch larger than expected: grows once
  }

  // 1. Survey.
  auto survey = [&](unsigned w) {
    const auto [begin, end] = rangeOf(w, rays.size());
    WorkTable& table = tables_[w];
    std::vector<SpanRecord>& spans = spans_[w];
    spans.clear();
    overflow_[w] = 0;
    for (std::size_t r = begin; r < end; ++r) {
      RayRegionWalk walk(rays[r], ctx.region_voxels);
      const rm_ray_walk_frame& f = walk.frame();
      // Voxel steps of the whole ray: a span's share is proportional to its length.
      const double steps = std::abs(static_cast<double>(f.end.x - f.start.x)) +
                           std::abs(static_cast<double>(f.end.y - f.start.y)) +
                           std::abs(static_cast<double>(f.end.z - f.start.z));
      RayRecord& record = rays_[r];
      record.walk = walk.voxelRay();
      record.sample_is_start = f.sample_is_start != 0;
      record.first_span = static_cast<std::uint32_t>(spans.size());
      RaySpan span;
      while (walk.next(&span)) {
        const std::uint64_t key = RegionStore::packCoord(span.region);
        if (!table.add(key, 1.0 + steps * static_cast<double>(span.t1 - span.t0))) {
          overflow_[w] = 1;
          return;
        }
        spans.push_back(SpanRecord{key, RegionStore::kNoSlot,
                                   (span.first ? kFirst : 0u) | (span.last ? kLast : 0u), span.t0,
                                   span.t1, span.box_lo});
      }
      record.span_count = static_cast<std::uint32_t>(spans.size()) - record.first_span;
      const auto [region, index] = walk.sampleCell();
      record.sample_key = RegionStore::packCoord(region);
      record.sample_index = index;
    }
    if (!table.flush()) {
      overflow_[w] = 1;
    }
  };
  pool_.run(survey);

  // 2. Create the batch's regions (serial: the store is not thread-safe for inserts).
  Expected<void, IntegrateError> status;
  for (unsigned w = 0; w < workers; ++w) {
    if (overflow_[w] != 0) {
      status = Unexpected(IntegrateError::kStoreFull);
    }
  }
  for (unsigned w = 0; w < workers && status; ++w) {
    tables_[w].forEach([&](std::uint64_t key, double work) {
      if (!status) {
        return;
      }
      bool created = false;
      auto slot = map.acquireRegionUncleared(RegionStore::unpackCoord(key), &created);
      if (!slot) {
        if (slot.error() == StoreError::kFull) {
          status = Unexpected(IntegrateError::kStoreFull);
        } else if (slot.error() == StoreError::kTierFailed) {
          status = Unexpected(IntegrateError::kTierFailed);
        }
        return;  // outside a rolling window: its spans are skipped and counted in step 4
      }
      if (owner_[*slot] == kNoOwner) {
        owner_[*slot] = 0;
        slot_work_[*slot] = 0.0;
        touched_.push_back(*slot);
      }
      created_[*slot] = created ? 1 : created_[*slot];
      // Its owner clears a new region: writing it and faulting its pages in costs about a
      // quarter of its voxels' worth of walk steps.
      const double clear_work =
          created ? 0.25 * static_cast<double>(map.store().voxelsPerRegion()) : 0.0;
      slot_work_[*slot] += work + clear_work;
    });
  }
  for (WorkTable& table : tables_) {
    table.clear();
  }
  if (!status) {
    // Regions created before the failure still need their clear values.
    for (std::uint32_t slot : touched_) {
      if (created_[slot] != 0) {
        map.store().clearRegion(slot);
        created_[slot] = 0;
      }
    }
    releaseOwners();
    return status;
  }

  // 3. Largest region first, to the least-loaded worker.
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

  // 4. Resolve (parallel): slots into the records, each worker its own survey's records, and
  //    first touch of the new regions by their owners.
  auto resolve = [&](unsigned w) {
    RegionSlotCache& cache = caches[w];
    RegionStore& store = map.store();
    for (std::uint32_t slot : touched_) {
      if (owner_[slot] == w && created_[slot] != 0) {
        store.clearRegion(slot);
        created_[slot] = 0;
      }
    }
    for (SpanRecord& rec : spans_[w]) {
      rec.slot = findSlot(store, cache, rec.region_key);
    }
    const auto [begin, end] = rangeOf(w, rays.size());
    for (std::size_t r = begin; r < end; ++r) {
      rays_[r].sample_slot = findSlot(store, cache, rays_[r].sample_key);
    }
  };
  pool_.run(resolve);

  // 5. Apply (parallel): every worker goes through all spans in ray order and walks its own.
  auto apply = [&](unsigned w) {
    WorkerStats& ws = stats[w];
    if (ctx.per_scan) {
      for (std::size_t r = 0; r < rays.size(); ++r) {
        const std::uint32_t slot = rays_[r].sample_slot;
        if ((rays[r].flags & RM_RAY_END_HIT) != 0u && slot != RegionStore::kNoSlot &&
            owner_[slot] == w) {
          applyScanHit(regionLayers(map, slot), rays_[r].sample_index, ctx.sequence, ctx.params);
        }
      }
    }
    const std::int32_t n = ctx.region_voxels;
    for (unsigned v = 0; v < workers; ++v) {
      const auto [begin, end] = rangeOf(v, rays.size());
      const std::vector<SpanRecord>& spans = spans_[v];
      for (std::size_t r = begin; r < end; ++r) {
        const RayRecord& record = rays_[r];
        for (std::uint32_t s = 0; s < record.span_count; ++s) {
          const SpanRecord& rec = spans[record.first_span + s];
          if (rec.slot == RegionStore::kNoSlot) {
            ws.spans_outside_window += w == 0 ? 1u : 0u;  // counted once
            continue;
          }
          if (owner_[rec.slot] != w) {
            continue;
          }
          RaySpan span;
          span.t0 = rec.t0;
          span.t1 = rec.t1;
          span.box_lo = rec.box_lo;
          span.box_hi =
              rm_vec3i_make(rec.box_lo.x + n - 1, rec.box_lo.y + n - 1, rec.box_lo.z + n - 1);
          span.first = (rec.flags & kFirst) != 0u;
          span.last = (rec.flags & kLast) != 0u;
          ws.voxels_visited += missSpan(ctx, record.walk, record.sample_is_start, rays[r].flags,
                                        rays[r].tsdf_end_m, span, regionLayers(map, rec.slot));
        }
        const PreparedRay& ray = rays[r];
        if ((ray.flags & RM_RAY_END_HIT) != 0u && record.sample_slot != RegionStore::kNoSlot &&
            owner_[record.sample_slot] == w && !ctx.ndt) {
          applySampleHit(ray, regionLayers(map, record.sample_slot), record.sample_index,
                         ctx.per_scan, ctx.params);
          ++ws.voxels_visited;
        }
      }
    }
    if (ctx.ndt) {
      // NDT: the batch's hits after all its misses, in ray order (kernels/common/ndt.h).
      for (std::size_t r = 0; r < rays.size(); ++r) {
        const RayRecord& record = rays_[r];
        if ((rays[r].flags & RM_RAY_END_HIT) != 0u && record.sample_slot != RegionStore::kNoSlot &&
            owner_[record.sample_slot] == w) {
          applyNdtHit(rays[r], regionLayers(map, record.sample_slot), record.sample_index,
                      ctx.params, ctx.ndt_params);
          ++ws.voxels_visited;
        }
      }
    }
  };
  pool_.run(apply);
  releaseOwners();
  return {};
}

}  // namespace raymap::detail
