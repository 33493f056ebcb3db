// SPDX-License-Identifier: BSD-3-Clause
// Region-partitioned multi-threaded integration.
#include "src/map/cpu_parallel.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

namespace raymap::detail {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) noexcept {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

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
  scratch_.reserve(n);
  for (unsigned w = 0; w < n; ++w) {
    WorkerScratch& scratch = scratch_.emplace_back(store_capacity);
    scratch.spans.reserve(expected_batch_rays * 6u / n + 1024u);
    scratch.steps_for.resize(n);
    scratch.hits_for.resize(n);
    for (unsigned owner = 0; owner < n; ++owner) {
      // A ray range's steps (its spans and sample hits) dealt evenly over the owners.
      scratch.steps_for[owner].reserve(expected_batch_rays * 7u / (n * n) + 256u);
      scratch.hits_for[owner].reserve(expected_batch_rays / (n * n) + 256u);
    }
  }
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
  Clock::time_point step_start = Clock::now();
  auto survey = [&](unsigned w) {
    const auto [begin, end] = rangeOf(w, rays.size());
    WorkerScratch& scratch = scratch_[w];
    WorkTable& table = scratch.table;
    std::vector<SpanRecord>& spans = scratch.spans;
    spans.clear();
    scratch.overflow = false;
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
        // A region outside a rolling window is never created (its span is counted in step 4):
        // it must not count against the store's capacity either, or a long ray would fail a
        // batch that the single-threaded path integrates.
        if (map.inWindow(span.region) &&
            !table.add(key, 1.0 + steps * static_cast<double>(span.t1 - span.t0))) {
          scratch.overflow = true;
          return;
        }
        spans.push_back(SpanRecord{key, (span.first ? kFirst : 0u) | (span.last ? kLast : 0u),
                                   span.t0, span.t1, span.box_lo});
      }
      record.span_count = static_cast<std::uint32_t>(spans.size()) - record.first_span;
      const auto [region, index] = walk.sampleCell();
      record.sample_key = RegionStore::packCoord(region);
      record.sample_index = index;
    }
    if (!table.flush()) {
      scratch.overflow = true;
    }
  };
  pool_.run(survey);
  steps_.survey += secondsSince(step_start);
  step_start = Clock::now();

  // 2. Create the batch's regions (serial: the store is not thread-safe for inserts).
  Expected<void, IntegrateError> status;
  for (const WorkerScratch& scratch : scratch_) {
    if (scratch.overflow) {
      status = Unexpected(IntegrateError::kStoreFull);
    }
  }
  for (unsigned w = 0; w < workers && status; ++w) {
    scratch_[w].table.forEach([&](std::uint64_t key, double work) {
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
  for (WorkerScratch& scratch : scratch_) {
    scratch.table.clear();
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

  steps_.serial += secondsSince(step_start);
  step_start = Clock::now();

  // 4. Resolve (parallel): slots into the records and the records dealt to their owners, each
  //    worker its own survey's ray range, and first touch of the new regions by their owners.
  const bool hit_lists = ctx.per_scan || ctx.ndt;
  auto resolve = [&](unsigned w) {
    WorkerScratch& scratch = scratch_[w];
    RegionSlotCache& cache = caches[w];
    RegionStore& store = map.store();
    for (std::uint32_t slot : touched_) {
      if (owner_[slot] == w && created_[slot] != 0) {
        store.clearRegion(slot);
        created_[slot] = 0;
      }
    }
    for (unsigned owner = 0; owner < workers; ++owner) {
      scratch.steps_for[owner].clear();
      scratch.hits_for[owner].clear();
    }
    std::uint64_t outside_window = 0;  // counted in a local, written to stats[w] once
    const auto [begin, end] = rangeOf(w, rays.size());
    for (std::size_t r = begin; r < end; ++r) {
      RayRecord& record = rays_[r];
      const auto ray = static_cast<std::uint32_t>(r);
      for (std::uint32_t s = 0; s < record.span_count; ++s) {
        const SpanRecord& rec = scratch.spans[record.first_span + s];
        const std::uint32_t slot = findSlot(store, cache, rec.region_key);
        // Every region of the batch has an owner; a slot without one would be a region the
        // survey left out (outside the window), which the store does not keep: skipped the same.
        if (slot == RegionStore::kNoSlot || owner_[slot] == kNoOwner) {
          ++outside_window;
          continue;
        }
        scratch.steps_for[owner_[slot]].push_back(
            OwnedStep{ray, slot, rec.flags, rec.t0, rec.t1, rec.box_lo});
      }
      record.sample_slot = findSlot(store, cache, record.sample_key);
      if ((rays[r].flags & RM_RAY_END_HIT) == 0u || record.sample_slot == RegionStore::kNoSlot ||
          owner_[record.sample_slot] == kNoOwner) {
        continue;
      }
      const std::uint8_t owner = owner_[record.sample_slot];
      if (!ctx.ndt) {
        scratch.steps_for[owner].push_back(
            OwnedStep{ray, record.sample_slot, kHit, 0.0f, 0.0f, rm_vec3i_make(0, 0, 0)});
      }
      if (hit_lists) {
        scratch.hits_for[owner].push_back(ray);
      }
    }
    stats[w].spans_outside_window += outside_window;
  };
  pool_.run(resolve);
  steps_.resolve += secondsSince(step_start);
  step_start = Clock::now();

  // 5. Apply (parallel): every worker walks the steps dealt to it, range by range (ray order).
  auto apply = [&](unsigned w) {
    const Clock::time_point apply_start = Clock::now();
    std::uint64_t voxels_visited = 0;  // summed here: a counter written per span beside another
                                       // worker's would share its cache line
    if (ctx.per_scan) {
      for (const WorkerScratch& from : scratch_) {
        for (std::uint32_t r : from.hits_for[w]) {
          applyScanHit(regionLayers(ctx, rays_[r].sample_slot), rays_[r].sample_index, ctx.params);
        }
      }
    }
    const std::int32_t n = ctx.region_voxels;
    for (const WorkerScratch& from : scratch_) {
      for (const OwnedStep& step : from.steps_for[w]) {
        const PreparedRay& ray = rays[step.ray];
        const RayRecord& record = rays_[step.ray];
        if (step.flags == kHit) {
          applySampleHit(ray, regionLayers(ctx, step.slot), record.sample_index, ctx.per_scan,
                         ctx.params);
          ++voxels_visited;
          continue;
        }
        RaySpan span;
        span.t0 = step.t0;
        span.t1 = step.t1;
        span.box_lo = step.box_lo;
        span.box_hi =
            rm_vec3i_make(step.box_lo.x + n - 1, step.box_lo.y + n - 1, step.box_lo.z + n - 1);
        span.first = (step.flags & kFirst) != 0u;
        span.last = (step.flags & kLast) != 0u;
        voxels_visited += missSpan(ctx, record.walk, record.sample_is_start, ray.flags,
                                   ray.tsdf_end_m, span, regionLayers(ctx, step.slot));
      }
    }
    if (ctx.ndt) {
      // NDT: the batch's hits after all its misses, in ray order (kernels/common/ndt.h).
      for (const WorkerScratch& from : scratch_) {
        for (std::uint32_t r : from.hits_for[w]) {
          applyNdtHit(rays[r], regionLayers(ctx, rays_[r].sample_slot), rays_[r].sample_index,
                      ctx.params, ctx.ndt_params);
          ++voxels_visited;
        }
      }
    }
    stats[w].voxels_visited += voxels_visited;
    scratch_[w].apply_seconds = secondsSince(apply_start);
  };
  pool_.run(apply);
  steps_.apply += secondsSince(step_start);
  for (const WorkerScratch& scratch : scratch_) {
    steps_.apply_busy += scratch.apply_seconds;
  }
  releaseOwners();
  return {};
}

}  // namespace raymap::detail
