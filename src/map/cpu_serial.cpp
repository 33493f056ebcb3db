// SPDX-License-Identifier: BSD-3-Clause
// Single-threaded integration: the reference every other path is compared with.
#include "src/map/cpu_serial.hpp"

namespace raymap::detail {
namespace {

/// Slot of a region, created on demand (cached). kNoSlot: outside a rolling window.
Expected<std::uint32_t, IntegrateError> acquire(const IntegrationContext& ctx, VoxelMap& map,
                                                RegionSlotCache& cache, Vec3i region) noexcept {
  if (const std::uint32_t* cached = cache.find(RegionStore::packCoord(region))) {
    return *cached;
  }
  auto slot = map.acquireRegion(region);
  if (!slot && slot.error() == StoreError::kFull && map.tiered() && splitsAtAnyRay(ctx)) {
    // The batch's regions outgrew the pool: those of the rays done so far may go to the cold
    // tiers (a new epoch unpins them), so that any budget that holds one region works.
    cache.reset();
    map.beginEpoch();
    slot = map.acquireRegion(region);
  }
  if (!slot) {
    if (slot.error() == StoreError::kFull) {
      return Unexpected(IntegrateError::kStoreFull);  // not cached: a later call may succeed
    }
    if (slot.error() == StoreError::kTierFailed) {
      return Unexpected(IntegrateError::kTierFailed);
    }
    cache.remember(RegionStore::kNoSlot);
    return RegionStore::kNoSlot;
  }
  cache.remember(*slot);
  return *slot;
}

/// Calls apply(ray, layers, index) for the sample voxel of every ray with a hit, in ray order
/// (regions created on demand; samples outside a rolling window are skipped).
template <class Apply>
Expected<void, IntegrateError> forEachSampleHit(const IntegrationContext& ctx,
                                                RegionSlotCache& cache,
                                                std::span<const PreparedRay> rays,
                                                Apply&& apply) noexcept {
  for (const PreparedRay& ray : rays) {
    if ((ray.flags & RM_RAY_END_HIT) == 0u) {
      continue;
    }
    const auto [region, index] = sampleCellOf(ray, ctx.region_voxels);
    auto slot = acquire(ctx, *ctx.map, cache, region);
    if (!slot) {
      return Unexpected(slot.error());
    }
    if (*slot != RegionStore::kNoSlot) {
      apply(ray, regionLayers(ctx, *slot), index);
    }
  }
  return {};
}

Expected<void, IntegrateError> integrateRays(const IntegrationContext& ctx,
                                             std::span<const PreparedRay> rays,
                                             RegionSlotCache& cache, WorkerStats& stats) noexcept {
  VoxelMap& map = *ctx.map;
  if (ctx.per_scan) {
    // Hits first: a voxel hit anywhere in the scan takes no miss from it (occupied wins).
    auto hits = forEachSampleHit(
        ctx, cache, rays, [&](const PreparedRay&, const RegionLayers& layers, std::uint32_t index) {
          applyScanHit(layers, index, ctx.params);
        });
    if (!hits) {
      return hits;
    }
  }
  for (const PreparedRay& ray : rays) {
    RayRegionWalk walk(ray, ctx.region_voxels);
    const bool sample_is_start = walk.frame().sample_is_start != 0;
    RaySpan span;
    while (walk.next(&span)) {
      auto slot = acquire(ctx, map, cache, span.region);
      if (!slot) {
        return Unexpected(slot.error());
      }
      if (*slot == RegionStore::kNoSlot) {
        ++stats.spans_outside_window;
        continue;
      }
      stats.voxels_visited += missSpan(ctx, walk.voxelRay(), sample_is_start, ray.flags,
                                       ray.tsdf_end_m, span, regionLayers(ctx, *slot));
    }
    if ((ray.flags & RM_RAY_END_HIT) != 0u && !ctx.ndt) {
      const auto [region, index] = walk.sampleCell();
      auto slot = acquire(ctx, map, cache, region);
      if (!slot) {
        return Unexpected(slot.error());
      }
      if (*slot != RegionStore::kNoSlot) {
        applySampleHit(ray, regionLayers(ctx, *slot), index, ctx.per_scan, ctx.params);
        ++stats.voxels_visited;
      }
    }
  }
  if (ctx.ndt) {
    // NDT: the batch's hits after all its misses, in ray order (kernels/common/ndt.h).
    return forEachSampleHit(
        ctx, cache, rays,
        [&](const PreparedRay& ray, const RegionLayers& layers, std::uint32_t index) {
          applyNdtHit(ray, layers, index, ctx.params, ctx.ndt_params);
          ++stats.voxels_visited;
        });
  }
  return {};
}

}  // namespace

Expected<void, IntegrateError> integrateSerial(const IntegrationContext& ctx,
                                               std::span<const PreparedRay> rays,
                                               RegionSlotCache& cache,
                                               WorkerStats& stats) noexcept {
  Expected<void, IntegrateError> result = integrateRays(ctx, rays, cache, stats);
  if (ctx.per_scan) {
    // The scan's misses, region by region (also after a failed batch: what its walks crossed
    // takes its miss, as the rays' hits up to the failure took theirs).
    const std::size_t words = ctx.scan_bits->voxelWords();
    ctx.scan_bits->forEachSlotOfBatch(
        [&](std::uint32_t slot) { applyScanMisses(regionLayers(ctx, slot), words, ctx.params); });
  }
  return result;
}

}  // namespace raymap::detail
