// SPDX-License-Identifier: BSD-3-Clause
// Region-partitioned multi-threaded integration.
#include "src/map/cpu_parallel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace raymap::detail {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) noexcept {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

ParallelIntegrator::WorkTable::WorkTable(std::size_t max_regions)
    : keys_(max_regions), work_(keys_.bucketCount(), 0.0) {
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
  bool added = false;
  const std::size_t b = keys_.insert(key, &added);
  if (b == RegionKeySet::kNoBucket) {
    return false;  // more regions than the store can hold: the batch cannot fit
  }
  work_[b] = added ? work : work_[b] + work;
  return true;
}

void ParallelIntegrator::WorkTable::clear() noexcept {
  keys_.clear();
  front_keys_.fill(kEmpty);
}

ParallelIntegrator::ParallelIntegrator(unsigned workers, std::uint32_t store_capacity,
                                       std::int32_t region_voxels, std::size_t expected_batch_rays)
    : pool_(workers), slots_(store_capacity) {
  const unsigned n = pool_.size();
  scratch_.reserve(n);
  for (unsigned w = 0; w < n; ++w) {
    WorkerScratch& scratch =
        scratch_.emplace_back(store_capacity, ScanBits::voxelWordsFor(region_voxels));
    // Address space only: pages become resident as batches write them.
    (void)scratch.spans.reserve(expected_batch_rays * 6u / n + 1024u);
  }
  (void)rays_.reserve(expected_batch_rays);
  in_batch_.assign(store_capacity, 0);
  created_.assign(store_capacity, 0);
  slot_work_.assign(store_capacity, 0.0);
  touched_.reserve(store_capacity);
  order_.reserve(store_capacity);
  regions_.reserve(store_capacity);
  blocks_ = n == 1 ? 1u : std::min(n * kBlocksPerWorker, kMaxBlocks);
  block_worker_.assign(blocks_, 0u);
  step_cursors_.assign(static_cast<std::size_t>(blocks_) * store_capacity, 0u);
  hit_cursors_.assign(static_cast<std::size_t>(blocks_) * store_capacity, 0u);
  // A batch's steps: its spans (up to 6 per ray) and sample hits.
  (void)steps_.reserve(expected_batch_rays * 7u + 1024u);
  (void)hits_.reserve(expected_batch_rays + 1024u);
}

std::pair<std::size_t, std::size_t> ParallelIntegrator::rangeOf(unsigned block,
                                                                std::size_t count) const noexcept {
  return {count * block / blocks_, count * (block + 1u) / blocks_};
}

unsigned ParallelIntegrator::takeBlock() noexcept {
  // Relaxed: the counter only has to give each block to one worker; what a block's worker wrote
  // in the previous step is ordered by the pool's hand-off between steps.
  const std::size_t b = next_block_.fetch_add(1, std::memory_order_relaxed);
  return b < blocks_ ? static_cast<unsigned>(b) : kNoBlock;
}

void ParallelIntegrator::releaseSlots() noexcept {
  for (std::uint32_t slot : touched_) {
    in_batch_[slot] = 0;
    for (unsigned b = 0; b < blocks_; ++b) {
      stepCursor(b, slot) = 0;
      hitCursor(b, slot) = 0;
    }
  }
  touched_.clear();
}

bool ParallelIntegrator::walksInSurvey(const IntegrationContext& ctx) noexcept {
  const VoxelMap& map = *ctx.map;
  return ctx.per_scan && ctx.scan_bits != nullptr && !ctx.ndt && map.occupancyLayer() >= 0 &&
         map.tsdfLayer() < 0 && map.traversalLayer() < 0;
}

void ParallelIntegrator::abandonBatch(VoxelMap& map) noexcept {
  // Regions created for the batch still need their clear values.
  for (std::uint32_t slot : touched_) {
    if (created_[slot] != 0) {
      map.store().clearRegion(slot);
      created_[slot] = 0;
    }
  }
  releaseSlots();
}

bool ParallelIntegrator::surveyRay(const IntegrationContext& ctx, const PreparedRay& ray,
                                   RayRecord& record, WorkerScratch& scratch, bool walk_in_survey,
                                   SurveyTally& tally) noexcept {
  const VoxelMap& map = *ctx.map;
  RayRegionWalk walk(ray, ctx.region_voxels);
  const rm_ray_walk_frame& f = walk.frame();
  // Voxel steps of the whole ray: a span's share is proportional to its length.
  const double steps = std::abs(static_cast<double>(f.end.x - f.start.x)) +
                       std::abs(static_cast<double>(f.end.y - f.start.y)) +
                       std::abs(static_cast<double>(f.end.z - f.start.z));
  record.walk = walk.voxelRay();
  record.sample_is_start = f.sample_is_start != 0;
  record.first_span = static_cast<std::uint32_t>(tally.span_count);
  RaySpan span;
  while (walk.next(&span)) {
    const std::uint64_t key = RegionStore::packCoord(span.region);
    // A region outside a rolling window is never created (its span is counted in the resolve
    // step, or here when the survey walks): it must not count against the store's capacity
    // either, or a long ray would fail a batch that the single-threaded path integrates.
    const bool in_window = map.inWindow(span.region);
    if (in_window &&
        !scratch.table.add(key, 1.0 + steps * static_cast<double>(span.t1 - span.t0))) {
      scratch.overflow = true;
      return false;
    }
    if (walk_in_survey) {  // the span's misses now, into this worker's plane
      if (!in_window) {
        ++tally.outside_window;
        continue;
      }
      std::uint64_t* plane = scratch.planes.planeFor(key);
      if (plane == nullptr) {
        (scratch.planes.full() ? scratch.overflow : scratch.out_of_memory) = true;
        return false;
      }
      tally.voxels_visited += walkSpan(record.walk, record.sample_is_start, span, ctx.region_voxels,
                                       PerScanMiss{plane});
      continue;
    }
    platform::PageArray<SpanRecord>& spans = scratch.spans;
    if (tally.span_count == spans.capacity() &&
        !spans.reserve(2u * tally.span_count + 1024u, tally.span_count)) {
      scratch.out_of_memory = true;  // a batch larger than expected and no memory to grow
      return false;
    }
    spans[tally.span_count++] = SpanRecord{key, span.t0, span.t1};
  }
  record.span_count = static_cast<std::uint32_t>(tally.span_count) - record.first_span;
  const auto [region, index] = walk.sampleCell();
  record.sample_key = RegionStore::packCoord(region);
  record.sample_index = index;
  return true;
}

void ParallelIntegrator::surveyWorker(unsigned w, const IntegrationContext& ctx,
                                      std::span<const PreparedRay> rays, WorkerStats& stats,
                                      bool walk_in_survey) noexcept {
  WorkerScratch& scratch = scratch_[w];
  SurveyTally tally;  // summed here, written to stats once
  scratch.overflow = false;
  scratch.out_of_memory = false;
  scratch.planes.clear();
  for (unsigned b = takeBlock(); b != kNoBlock; b = takeBlock()) {
    block_worker_[b] = w;  // its spans are in this worker's list
    const auto [begin, end] = rangeOf(b, rays.size());
    for (std::size_t r = begin; r < end; ++r) {
      if (!surveyRay(ctx, rays[r], rays_[r], scratch, walk_in_survey, tally)) {
        return;
      }
    }
  }
  if (!scratch.table.flush()) {
    scratch.overflow = true;
  }
  stats.voxels_visited += tally.voxels_visited;
  stats.spans_outside_window += tally.outside_window;
}

Expected<void, IntegrateError> ParallelIntegrator::createRegions(VoxelMap& map) noexcept {
  Expected<void, IntegrateError> status;
  for (const WorkerScratch& scratch : scratch_) {
    if (scratch.overflow) {
      status = Unexpected(IntegrateError::kStoreFull);
    }
    if (scratch.out_of_memory) {
      status = Unexpected(IntegrateError::kOutOfMemory);
    }
  }
  for (unsigned w = 0; w < pool_.size() && status; ++w) {
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
        return;  // outside a rolling window: its spans are skipped and counted when resolved
      }
      if (in_batch_[*slot] == 0) {
        in_batch_[*slot] = 1;
        slot_work_[*slot] = 0.0;
        touched_.push_back(*slot);
      }
      created_[*slot] = created ? 1 : created_[*slot];
      // A new region is cleared by the worker that applies it: writing it and faulting its
      // pages in costs about a quarter of its voxels' worth of walk steps.
      const double clear_work =
          created ? 0.25 * static_cast<double>(map.store().voxelsPerRegion()) : 0.0;
      slot_work_[*slot] += work + clear_work;
    });
  }
  for (WorkerScratch& scratch : scratch_) {
    scratch.table.clear();
  }
  return status;
}

void ParallelIntegrator::orderRegions() noexcept {
  order_.clear();
  for (std::uint32_t slot : touched_) {
    order_.emplace_back(slot_work_[slot], slot);
  }
  std::sort(order_.begin(), order_.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
}

void ParallelIntegrator::countWorker(const IntegrationContext& ctx,
                                     std::span<const PreparedRay> rays, RegionSlotCache& cache,
                                     WorkerStats& stats, bool hit_lists) noexcept {
  const RegionStore& store = ctx.map->store();
  std::uint64_t outside_window = 0;  // counted in a local, written to stats once
  for (unsigned b = takeBlock(); b != kNoBlock; b = takeBlock()) {
    WorkerScratch& scratch = scratch_[block_worker_[b]];
    const auto [begin, end] = rangeOf(b, rays.size());
    for (std::size_t r = begin; r < end; ++r) {
      RayRecord& record = rays_[r];
      for (std::uint32_t s = 0; s < record.span_count; ++s) {
        SpanRecord& rec = scratch.spans[record.first_span + s];
        const std::uint32_t slot = findSlot(store, cache, rec.region);
        // Every region of the batch was created in createRegions(); a slot outside it is a
        // region the survey left out (outside the window), which the store does not keep:
        // skipped the same.
        if (slot == RegionStore::kNoSlot || in_batch_[slot] == 0) {
          rec.region = RegionStore::kNoSlot;
          ++outside_window;
          continue;
        }
        rec.region = slot;
        ++stepCursor(b, slot);
      }
      std::uint32_t sample_slot = findSlot(store, cache, record.sample_key);
      if ((rays[r].flags & RM_RAY_END_HIT) == 0u || sample_slot == RegionStore::kNoSlot ||
          in_batch_[sample_slot] == 0) {
        sample_slot = RegionStore::kNoSlot;  // no hit to apply
      } else {
        stepCursor(b, sample_slot) += ctx.ndt ? 0u : 1u;
        hitCursor(b, sample_slot) += hit_lists ? 1u : 0u;
      }
      record.sample_slot = sample_slot;
    }
  }
  stats.spans_outside_window += outside_window;
}

std::pair<std::uint32_t, std::uint32_t> ParallelIntegrator::placeRegions() noexcept {
  regions_.clear();
  std::uint32_t steps_total = 0;
  std::uint32_t hits_total = 0;
  for (const auto& entry : order_) {
    const std::uint32_t slot = entry.second;
    RegionWork& region = regions_.emplace_back();
    region.slot = slot;
    region.steps_begin = steps_total;
    region.hits_begin = hits_total;
    for (unsigned b = 0; b < blocks_; ++b) {  // blocks in ray order: steps in ray order
      std::uint32_t& steps = stepCursor(b, slot);
      std::uint32_t& hits = hitCursor(b, slot);
      const std::uint32_t step_count = steps;
      const std::uint32_t hit_count = hits;
      steps = steps_total;
      hits = hits_total;
      steps_total += step_count;
      hits_total += hit_count;
    }
    region.steps_end = steps_total;
    region.hits_end = hits_total;
  }
  return {steps_total, hits_total};
}

void ParallelIntegrator::placeWorker(const IntegrationContext& ctx, std::size_t ray_count,
                                     bool hit_lists) noexcept {
  for (unsigned b = takeBlock(); b != kNoBlock; b = takeBlock()) {
    const WorkerScratch& scratch = scratch_[block_worker_[b]];
    const auto [begin, end] = rangeOf(b, ray_count);
    for (std::size_t r = begin; r < end; ++r) {
      const RayRecord& record = rays_[r];
      const auto ray = static_cast<std::uint32_t>(r);
      for (std::uint32_t s = 0; s < record.span_count; ++s) {
        const SpanRecord& rec = scratch.spans[record.first_span + s];
        if (rec.region == RegionStore::kNoSlot) {
          continue;
        }
        // The region walk gives a ray's spans in walk order, every one recorded: the first
        // holds the walk's start voxel, the last its end voxel (RayRegionWalk::next).
        const std::uint32_t flags =
            (s == 0 ? kFirst : 0u) | (s + 1 == record.span_count ? kLast : 0u);
        const auto slot = static_cast<std::uint32_t>(rec.region);
        steps_[stepCursor(b, slot)++] = RegionStep{ray, flags, rec.t0, rec.t1};
      }
      const std::uint32_t sample_slot = record.sample_slot;
      if (sample_slot == RegionStore::kNoSlot) {
        continue;
      }
      if (!ctx.ndt) {
        steps_[stepCursor(b, sample_slot)++] = RegionStep{ray, kHit, 0.0f, 0.0f};
      }
      if (hit_lists) {
        hits_[hitCursor(b, sample_slot)++] = ray;
      }
    }
  }
}

std::uint64_t ParallelIntegrator::applyRegion(const RegionWork& region,
                                              const IntegrationContext& ctx,
                                              std::span<const PreparedRay> rays,
                                              bool walk_in_survey) noexcept {
  VoxelMap& map = *ctx.map;
  std::uint64_t voxels_visited = 0;
  const std::int32_t n = ctx.region_voxels;
  if (created_[region.slot] != 0) {
    map.store().clearRegion(region.slot);  // first touch by the worker that writes it
    created_[region.slot] = 0;
  }
  const RegionLayers layers = regionLayers(ctx, region.slot);
  const Vec3i coord = map.store().coordOf(region.slot);
  if (ctx.per_scan) {
    for (std::uint32_t h = region.hits_begin; h < region.hits_end; ++h) {
      applyScanHit(layers, rays_[hits_[h]].sample_index, ctx.params);
    }
  }
  for (std::uint32_t k = region.steps_begin; k < region.steps_end; ++k) {
    const RegionStep& step = steps_[k];
    const PreparedRay& ray = rays[step.ray];
    const RayRecord& record = rays_[step.ray];
    if (step.flags == kHit) {
      applySampleHit(ray, layers, record.sample_index, ctx.per_scan, ctx.params);
      ++voxels_visited;
      continue;
    }
    // The walk starts on the sample voxel for a reverse ray (rm_ray_walk_frame_make).
    RaySpan span;
    span.t0 = step.t0;
    span.t1 = step.t1;
    span.box_lo = RayRegionWalk::boxLo(
        coord, record.sample_is_start ? ray.sample_voxel : ray.origin_voxel, n);
    span.box_hi =
        rm_vec3i_make(span.box_lo.x + n - 1, span.box_lo.y + n - 1, span.box_lo.z + n - 1);
    span.first = (step.flags & kFirst) != 0u;
    span.last = (step.flags & kLast) != 0u;
    voxels_visited +=
        missSpan(ctx, record.walk, record.sample_is_start, ray.flags, ray.tsdf_end_m, span, layers);
  }
  if (walk_in_survey) {  // the misses the workers marked in the survey
    const std::size_t words = ctx.scan_bits->voxelWords();
    const std::uint64_t key = RegionStore::packCoord(coord);
    for (const WorkerScratch& scratch : scratch_) {
      if (const std::uint64_t* plane = scratch.planes.find(key); plane != nullptr) {
        for (std::size_t i = 0; i < words; ++i) {
          layers.scan_misses[i] |= plane[i];
        }
      }
    }
  }
  if (ctx.per_scan) {
    applyScanMisses(layers, ctx.scan_bits->voxelWords(), ctx.params);  // the scan's misses
  }
  if (ctx.ndt) {
    // NDT: the batch's hits after all its misses, in ray order (kernels/common/ndt.h).
    for (std::uint32_t h = region.hits_begin; h < region.hits_end; ++h) {
      const std::uint32_t r = hits_[h];
      applyNdtHit(rays[r], layers, rays_[r].sample_index, ctx.params, ctx.ndt_params);
      ++voxels_visited;
    }
  }
  return voxels_visited;
}

void ParallelIntegrator::applyWorker(unsigned w, const IntegrationContext& ctx,
                                     std::span<const PreparedRay> rays, WorkerStats& stats,
                                     bool walk_in_survey) noexcept {
  const Clock::time_point apply_start = Clock::now();
  std::uint64_t voxels_visited = 0;  // summed here: a counter written per span beside another
                                     // worker's would share its cache line
  for (;;) {
    // Relaxed: the lists were written before this step started (the pool's hand-off orders
    // them); the counter only has to give each region to one worker.
    const std::size_t next = next_region_.fetch_add(1, std::memory_order_relaxed);
    if (next >= regions_.size()) {
      break;
    }
    voxels_visited += applyRegion(regions_[next], ctx, rays, walk_in_survey);
  }
  stats.voxels_visited += voxels_visited;
  scratch_[w].apply_seconds = secondsSince(apply_start);
}

Expected<void, IntegrateError> ParallelIntegrator::integrate(
    const IntegrationContext& ctx, std::span<const PreparedRay> rays,
    std::span<RegionSlotCache> caches, std::span<WorkerStats> stats) noexcept {
  VoxelMap& map = *ctx.map;
  if (!rays_.reserve(rays.size())) {  // a batch larger than expected: grows once
    return Unexpected(IntegrateError::kOutOfMemory);
  }
  // 1. Survey: each ray's region spans, and the work per region.
  Clock::time_point step_start = Clock::now();
  next_block_.store(0, std::memory_order_relaxed);
  const bool walk_in_survey = walksInSurvey(ctx);
  auto survey = [&](unsigned w) { surveyWorker(w, ctx, rays, stats[w], walk_in_survey); };
  pool_.run(survey);
  steps_seconds_.survey += secondsSince(step_start);
  step_start = Clock::now();

  // 2. Create the batch's regions (serial: the store is not thread-safe for inserts).
  if (auto created = createRegions(map); !created) {
    abandonBatch(map);
    return created;
  }
  // 3. Largest region first: the apply step hands them out in this order.
  orderRegions();
  steps_seconds_.serial += secondsSince(step_start);
  step_start = Clock::now();

  // 4. Resolve: (a) slots into the records, steps and hits counted per region for each block
  //    of rays; (b) the counts become places in the flat lists; (c) each block's steps and hits
  //    are written there. Blocks are taken as workers come free, as in the survey.
  const bool hit_lists = ctx.per_scan || ctx.ndt;
  next_block_.store(0, std::memory_order_relaxed);
  auto count = [&](unsigned w) { countWorker(ctx, rays, caches[w], stats[w], hit_lists); };
  pool_.run(count);
  const auto [steps_total, hits_total] = placeRegions();
  // A batch larger than expected: grows once. Nothing was written to the map yet.
  if (!steps_.reserve(steps_total) || !hits_.reserve(hits_total)) {
    abandonBatch(map);
    return Unexpected(IntegrateError::kOutOfMemory);
  }
  next_block_.store(0, std::memory_order_relaxed);
  auto place = [&](unsigned /*worker*/) { placeWorker(ctx, rays.size(), hit_lists); };
  pool_.run(place);
  steps_seconds_.resolve += secondsSince(step_start);
  step_start = Clock::now();

  // 5. Apply (parallel): regions taken one at a time, largest first; each region's steps in ray
  //    order.
  next_region_.store(0, std::memory_order_relaxed);
  auto apply = [&](unsigned w) { applyWorker(w, ctx, rays, stats[w], walk_in_survey); };
  pool_.run(apply);
  steps_seconds_.apply += secondsSince(step_start);
  for (const WorkerScratch& scratch : scratch_) {
    steps_seconds_.apply_busy += scratch.apply_seconds;
  }
  releaseSlots();
  return {};
}

}  // namespace raymap::detail
