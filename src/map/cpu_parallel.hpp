// SPDX-License-Identifier: BSD-3-Clause
// The multi-threaded integrator of the CPU backend: regions partitioned over workers, no atomics.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "raymap/expected.hpp"

#include "platform/page_array.hpp"
#include "src/map/backend.hpp"
#include "src/map/cpu_voxel_ops.hpp"
#include "src/map/miss_planes.hpp"
#include "src/map/region_key_set.hpp"
#include "src/map/worker_pool.hpp"

namespace raymap::detail {

/// @brief Integrates a batch with several workers, giving every region to exactly one of them.
///
/// Design: five steps per batch.
///  1. Survey (parallel): the batch's rays are cut into contiguous blocks (a few per worker),
///     taken by the workers as they come free; each worker walks its blocks' rays at region level
///     once, records every span (region, t0, t1) and the sample cell per ray in a list
///     of its own, and sums the estimated work (voxel steps) per region in a private table.
///  2. Create (serial): the regions of the batch are inserted into the store, uncleared; if the
///     store is full the batch fails here, before any voxel changes.
///  3. Order (serial): regions sorted by estimated work, largest first.
///  4. Resolve (parallel, then a short serial prefix sum, then parallel; blocks taken as in the
///     survey): the slots of each block's spans are looked up and counted per region and block;
///     the counts become each block's place in one flat list of steps grouped by region (the
///     regions in step 3's order, within a region block by block, so in ray order); then each
///     block's steps and sample hits are written there.
///  5. Apply (parallel): workers take the regions one at a time from a shared counter, largest
///     first, and apply each region's steps in ray order, clearing a new region first (its first
///     touch is by the worker that writes it).
/// Each voxel is written by one worker, in ray order, so the map is bit-identical to the
/// single-threaded one and needs no atomics on voxels. Taking regions as workers come free keeps
/// every worker busy to the end of the batch, whatever the error of the work estimate or the
/// load of the machine (a static assignment by estimated work left one worker idle for 2-9 % of
/// the apply step on an idle 2-core VM and 10-17 % beside other processes; now 0-2 %;
/// docs/benchmarks.md), and one region's steps are applied together while its voxels are in
/// cache. What one worker writes during the survey and resolve steps lives in its own cache lines
/// (WorkerScratch is aligned to them, per-region counts are rows of their own, counters are
/// summed locally): two workers writing to one line cost the second core most of its worth
/// (measured, docs/benchmarks.md).
///
/// Per-scan occupancy maps (with or without the voxel mean; no NDT, TSDF or decay rate) walk
/// their rays to the voxel in the survey instead: their misses only set bits that commute
/// (ScanBits), so each worker marks its own planes (MissPlanes) and lists no span; step 4 places
/// only the sample hits, and step 5 ors the workers' planes of a region together before its
/// misses. No span list, count or hand-off: peak memory 14-26 % lower on the shared data, the
/// time about the same, as the walk moves from step 5 to step 1 (docs/benchmarks.md).
///
/// Scratch is sized at construction for `expected_batch_rays` rays of up to 6 regions each; a
/// larger batch grows it once (an allocation outside the steady state). Not thread-safe:
/// integrate() must not be called concurrently.
class ParallelIntegrator {
 public:
  /// `region_voxels`: voxels along a region's edge (the size of a miss plane).
  ParallelIntegrator(unsigned workers, std::uint32_t store_capacity, std::int32_t region_voxels,
                     std::size_t expected_batch_rays);

  unsigned workers() const noexcept { return pool_.size(); }
  /// The integrator's threads, for other work between batches (Backend::runOnHostThreads).
  WorkerPool& pool() noexcept { return pool_; }

  /// Seconds spent in each step, summed over the batches integrated so far (the backend's
  /// statistics: what limits the speed-up, measured where it runs).
  struct StepSeconds {
    double survey = 0;
    double serial = 0;  // create and order
    double resolve = 0;
    double apply = 0;
    double apply_busy = 0;  // every worker's apply time, summed
  };
  const StepSeconds& stepSeconds() const noexcept { return steps_seconds_; }

  /// @param caches one region cache per worker (reset for this batch)
  /// @param stats one counter set per worker
  Expected<void, IntegrateError> integrate(const IntegrationContext& ctx,
                                           std::span<const PreparedRay> rays,
                                           std::span<RegionSlotCache> caches,
                                           std::span<WorkerStats> stats) noexcept;

 private:
  /// One region piece of a ray, recorded by the survey (its slot is looked up in the resolve
  /// step, once the batch's regions exist). What can be derived is left out, because the lists
  /// are written and read once per span: whether the span holds the walk's start or end (the
  /// ray's first or last span) and its voxel box (the region's first voxel less the walk's
  /// start voxel). 16 bytes, not 32, as RegionStep: per ray on 2 threads the survey and resolve
  /// steps took 10-15 % less time and peak memory fell 3-6 % (docs/benchmarks.md).
  struct SpanRecord {
    /// RegionStore::packCoord in the survey; the region's slot from the resolve step on
    /// (RegionStore::kNoSlot: outside the batch, skipped)
    std::uint64_t region;
    float t0;
    float t1;
  };
  static constexpr std::uint32_t kFirst = 1u;
  static constexpr std::uint32_t kLast = 2u;

  /// Per ray: where its spans are (in the survey worker's list), its walk constants and its
  /// sample cell.
  struct RayRecord {
    rm_line_walk_ray walk;
    std::uint32_t first_span;
    std::uint32_t span_count;
    std::uint64_t sample_key;
    std::uint32_t sample_slot;
    std::uint32_t sample_index;
    bool sample_is_start;
  };

  /// Fixed-capacity table: region key -> estimated work (RegionKeySet, a work sum per bucket),
  /// behind a small direct-mapped write-back front (most spans of neighbouring rays fall in a few
  /// regions, so most additions stay in a few kilobytes).
  class WorkTable {
   public:
    explicit WorkTable(std::size_t max_regions);
    /// @brief Adds work to a region; false when the table would exceed the store's capacity.
    bool add(std::uint64_t key, double work) noexcept;
    /// @brief Moves the front's entries into the table; call before forEach().
    bool flush() noexcept;
    template <class Fn>
    void forEach(Fn&& fn) const {
      for (std::size_t b : keys_.usedBuckets()) {
        fn(keys_.keyAt(b), work_[b]);
      }
    }
    void clear() noexcept;

   private:
    static constexpr std::uint64_t kEmpty = RegionKeySet::kNoKey;
    static constexpr std::size_t kFrontEntries = 256;  // directMappedIndex() range
    bool addToTable(std::uint64_t key, double work) noexcept;
    std::array<std::uint64_t, kFrontEntries> front_keys_{};
    std::array<double, kFrontEntries> front_work_{};
    RegionKeySet keys_;
    std::vector<double> work_;  // per bucket of keys_
  };

  /// One step of the apply phase in its region's part of the step list: a span of a ray
  /// (kFirst | kLast) or the ray's sample hit (kHit). The span's voxel box comes from the region
  /// and the ray in the apply step (RayRegionWalk::boxLo), as for SpanRecord.
  struct RegionStep {
    std::uint32_t ray;
    std::uint32_t flags;
    float t0;
    float t1;
  };
  static_assert(sizeof(RegionStep) == 16 && sizeof(SpanRecord) == 16);
  static constexpr std::uint32_t kHit = 4u;

  /// Everything one worker writes in the survey and the resolve steps, on cache lines of its
  /// own.
  struct alignas(64) WorkerScratch {
    WorkerScratch(std::size_t max_regions, std::size_t plane_words)
        : table(max_regions), planes(max_regions, plane_words) {}
    WorkTable table;
    platform::PageArray<SpanRecord> spans;  // survey: this worker's ray range, in ray order
    MissPlanes planes;           // survey, per-scan occupancy: the misses of this worker's rays
    bool overflow = false;       // survey: the work table is full
    bool out_of_memory = false;  // survey: the span list or the miss planes could not grow
    double apply_seconds = 0;    // apply: this worker's time in the current batch
  };

  /// One region of the batch in the apply step: its slot and its parts of the flat lists.
  struct RegionWork {
    std::uint32_t slot;
    std::uint32_t steps_begin;
    std::uint32_t steps_end;
    std::uint32_t hits_begin;  // rays whose sample hit is here (per scan: before the misses;
    std::uint32_t hits_end;    // NDT: after them)
  };

  /// The rays of block `block` of a batch of `count`: blocks_ contiguous ranges, in ray order.
  std::pair<std::size_t, std::size_t> rangeOf(unsigned block, std::size_t count) const noexcept;
  /// The next block of the current step, or kNoBlock when all are taken.
  unsigned takeBlock() noexcept;
  void releaseSlots() noexcept;
  /// True when the batch's misses are walked in the survey (MissPlanes; see the class comment).
  static bool walksInSurvey(const IntegrationContext& ctx) noexcept;
  /// Gives up a batch before its apply step: the regions it created get their clear values.
  void abandonBatch(VoxelMap& map) noexcept;

  // The steps of integrate(), each run by every worker (pool_.run) or serially.
  /// What a worker's survey counts, written to its statistics once.
  struct SurveyTally {
    std::size_t span_count = 0;
    std::uint64_t voxels_visited = 0;
    std::uint64_t outside_window = 0;
  };
  /// Step 1, one ray: its spans (or, walking in the survey, its misses) and the work per region.
  /// @return false when the worker's table, list or planes cannot take more (scratch says which)
  bool surveyRay(const IntegrationContext& ctx, const PreparedRay& ray, RayRecord& record,
                 WorkerScratch& scratch, bool walk_in_survey, SurveyTally& tally) noexcept;
  void surveyWorker(unsigned w, const IntegrationContext& ctx, std::span<const PreparedRay> rays,
                    WorkerStats& stats, bool walk_in_survey) noexcept;
  /// Step 2 (serial): the surveyed regions acquired in the map, their work summed.
  Expected<void, IntegrateError> createRegions(VoxelMap& map) noexcept;
  /// Step 3: order_ = the batch's regions, most work first.
  void orderRegions() noexcept;
  /// Step 4a: slots into the ray records; steps and hits counted per block and region.
  void countWorker(const IntegrationContext& ctx, std::span<const PreparedRay> rays,
                   RegionSlotCache& cache, WorkerStats& stats, bool hit_lists) noexcept;
  /// Step 4b: each region's ranges in the flat lists; the cursors become places.
  /// @return the steps and hits in all
  std::pair<std::uint32_t, std::uint32_t> placeRegions() noexcept;
  /// Step 4c: each block's steps and hits written at their places.
  void placeWorker(const IntegrationContext& ctx, std::size_t ray_count, bool hit_lists) noexcept;
  /// Step 5: regions taken one at a time; returns nothing, counts into `stats`.
  void applyWorker(unsigned w, const IntegrationContext& ctx, std::span<const PreparedRay> rays,
                   WorkerStats& stats, bool walk_in_survey) noexcept;
  /// Step 5, one region: its hits, steps, survey misses and NDT hits. @return voxels visited
  std::uint64_t applyRegion(const RegionWork& region, const IntegrationContext& ctx,
                            std::span<const PreparedRay> rays, bool walk_in_survey) noexcept;
  /// Counts of block `b`'s steps (or hits) per slot, then its next place in the flat list.
  std::uint32_t& stepCursor(unsigned b, std::uint32_t slot) noexcept {
    return step_cursors_[static_cast<std::size_t>(b) * slots_ + slot];
  }
  std::uint32_t& hitCursor(unsigned b, std::uint32_t slot) noexcept {
    return hit_cursors_[static_cast<std::size_t>(b) * slots_ + slot];
  }
  /// Blocks of rays per worker in the survey and resolve steps: enough that a worker whose rays
  /// cost more (longer rays, more regions, pages faulted in) does not hold up the step. With one
  /// range per worker, the first worker's survey of the Ouster data took 1.6 times the second's
  /// (a warm-up pass and a timed pass together); with blocks, 2 threads gained 1-4 %
  /// (docs/benchmarks.md).
  static constexpr unsigned kBlocksPerWorker = 4;
  static constexpr unsigned kMaxBlocks = 64;  // bounds the cursor rows (blocks x store slots)
  static constexpr unsigned kNoBlock = ~0u;

  WorkerPool pool_;
  std::uint32_t slots_;                  // the store's capacity
  unsigned blocks_ = 1;                  // blocks of rays per batch
  std::vector<unsigned> block_worker_;   // per block: the worker whose span list holds its spans
  std::vector<WorkerScratch> scratch_;   // one per worker
  platform::PageArray<RayRecord> rays_;  // per ray of the batch, written by the survey
  std::vector<std::uint8_t> in_batch_;   // per slot: a region of this batch
  std::vector<std::uint8_t> created_;    // per slot: created in this batch, not cleared yet
  std::vector<double> slot_work_;        // per slot
  std::vector<std::uint32_t> touched_;   // slots of this batch
  std::vector<std::pair<double, std::uint32_t>> order_;
  /// Per block a row of one counter per slot (a block is counted and placed by one worker at a
  /// time; rows of their own keep two workers off each other's cache lines).
  std::vector<std::uint32_t> step_cursors_;
  std::vector<std::uint32_t> hit_cursors_;
  std::vector<RegionWork> regions_;  // step 3's order
  /// Written before they are read, page-backed (platform::PageArray): pages become resident
  /// only as batches use them, 2 MiB at a time where the OS gives huge pages (a zeroed list
  /// sized for the largest batch cost a per-scan run 16-31 MB of peak memory it never used, and
  /// faulting the lists in 4 KiB at a time cost a fresh scan more than its survey).
  platform::PageArray<RegionStep> steps_;    // every region's steps, grouped by region
  platform::PageArray<std::uint32_t> hits_;  // every region's hit rays, grouped by region
  /// The next entry of regions_ to apply; on a cache line of its own.
  alignas(64) std::atomic<std::size_t> next_region_{0};
  /// The next block of rays of the survey, count or place step; on a cache line of its own.
  alignas(64) std::atomic<std::size_t> next_block_{0};
  StepSeconds steps_seconds_;
};

}  // namespace raymap::detail
