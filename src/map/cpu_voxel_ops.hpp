// SPDX-License-Identifier: BSD-3-Clause
// What the CPU integrators share: walking the voxels of one ray span inside one region, applying
// the shared update rules (kernels/common) to them, and finding regions quickly.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "raymap/assert.hpp"

#include "kernels/common/decay.h"
#include "kernels/common/key_math.h"
#include "kernels/common/line_walk.h"
#include "kernels/common/ndt.h"
#include "kernels/common/occupancy.h"
#include "kernels/common/ray.h"
#include "kernels/common/span_walk.h"
#include "kernels/common/tsdf.h"
#include "kernels/common/voxel_mean.h"
#include "platform/write_intent.hpp"
#include "src/map/ray_region_walk.hpp"
#include "src/map/region_slot_cache.hpp"
#include "src/map/scan_bits.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::detail {

/// @brief A span's walk as rm_span_walk_init left it (no step taken), with its voxel count and
/// the span's RM_SPAN_* flags; a value, so a copy walks the span again.
struct SpanWalk {
  rm_span_walk walk;
  std::int32_t count = 0;  ///< voxels to visit (the ray's sample voxel left out)
  std::uint32_t flags = 0;
  int reverse = 0;  ///< the walk starts on the sample voxel
};

/// @brief Starts the walk of `span` of a ray with walk constants `ray`. @rt allocates: no.
inline SpanWalk startSpanWalk(const rm_line_walk_ray& ray, bool sample_is_start,
                              const RaySpan& span, std::int32_t region_voxels) noexcept {
  SpanWalk s;
  s.flags = (span.first ? RM_SPAN_FIRST : 0u) | (span.last ? RM_SPAN_LAST : 0u);
  s.reverse = sample_is_start ? 1 : 0;
  s.count = rm_span_walk_init(&s.walk, &ray, span.t0, span.t1, span.box_lo, region_voxels, s.flags,
                              s.reverse);
  return s;
}

/// @brief Calls visit(index) for each voxel of a started span walk (index inside the span's
/// region), or visit(index, voxel) with the voxel relative to the walk's start voxel.
template <class Visit>
inline void visitSpanWalk(SpanWalk s, Visit&& visit) noexcept {
  if (s.count == 0) {
    return;
  }
  if constexpr (std::is_invocable_v<Visit, std::uint32_t, rm_vec3i>) {
    visit(static_cast<std::uint32_t>(s.walk.index), rm_span_walk_voxel(&s.walk));
    for (std::int32_t k = 1; k < s.count; ++k) {
      const std::uint32_t index = rm_span_walk_advance(&s.walk);
      visit(index, rm_span_walk_voxel(&s.walk));
    }
  } else {
    visit(static_cast<std::uint32_t>(s.walk.index));
    for (std::int32_t k = 1; k < s.count; ++k) {
      visit(rm_span_walk_advance(&s.walk));
    }
  }
}

/// @brief Calls visit(index) for each voxel of `span` (index inside the span's region), or
/// visit(index, voxel) with the voxel relative to the walk's start voxel, leaving out
/// the ray's sample voxel, which the caller updates by its own rule. `ray` holds the ray's walk
/// constants; sample_is_start says whether the sample voxel is where the walk starts (reverse).
/// Returns the voxels visited. @rt allocates: no.
template <class Visit>
inline std::uint32_t walkSpan(const rm_line_walk_ray& ray, bool sample_is_start,
                              const RaySpan& span, std::int32_t region_voxels,
                              Visit&& visit) noexcept {
  const SpanWalk s = startSpanWalk(ray, sample_is_start, span, region_voxels);
  visitSpanWalk(s, std::forward<Visit>(visit));
  return static_cast<std::uint32_t>(s.count);
}

/// @brief Adds the metres of ray path inside each voxel of a started span walk of `span`, and
/// inside the voxel the walk leaves out when this span holds it, to `traversal`
/// (kernels/common/decay.h). @rt allocates: no.
inline void addSpanWalkPath(SpanWalk s, const rm_line_walk_ray& ray, const RaySpan& span,
                            std::int32_t region_voxels, float* traversal,
                            float ray_metres) noexcept {
  if ((s.flags & (s.reverse != 0 ? RM_SPAN_FIRST : RM_SPAN_LAST)) != 0u) {
    traversal[rm_decay_left_out_index(&ray, s.reverse, span.box_lo, region_voxels)] +=
        rm_decay_left_out_metres(&s.walk, s.flags, s.reverse, ray_metres);
  }
  if (s.count == 0) {
    return;
  }
  // Each voxel's metres are added once the walk has stepped past it (decay.h,
  // rm_decay_stepped_voxel_metres); the span's last voxel from its own exit.
  auto index = static_cast<std::uint32_t>(s.walk.index);
  for (std::int32_t k = 1; k < s.count; ++k) {
    const float t_left_enter = rm_line_walk_t_enter(&s.walk.walk);
    const std::uint32_t next = rm_span_walk_advance(&s.walk);
    traversal[index] += rm_decay_stepped_voxel_metres(t_left_enter, &s.walk.walk, ray_metres);
    index = next;
  }
  traversal[index] += rm_decay_voxel_metres(&s.walk.walk, ray_metres);
}

/// @brief The whole update of a decay-rate-only map's span: its path (addSpanWalkPath). Returns
/// the voxels visited. @rt allocates: no.
inline std::uint32_t addSpanPath(const rm_line_walk_ray& ray, bool sample_is_start,
                                 const RaySpan& span, std::int32_t region_voxels, float* traversal,
                                 float ray_metres) noexcept {
  const SpanWalk s = startSpanWalk(ray, sample_is_start, span, region_voxels);
  addSpanWalkPath(s, ray, span, region_voxels, traversal, ray_metres);
  return static_cast<std::uint32_t>(s.count);
}

/// @brief walkSpan() for decay-rate maps: also adds the metres of ray path inside each visited
/// voxel, and inside the voxel the walk leaves out (the sample or end voxel, when this span holds
/// it), to `traversal` (kernels/common/decay.h). @rt allocates: no.
template <class Visit>
inline std::uint32_t walkSpanAddingPath(const rm_line_walk_ray& ray, bool sample_is_start,
                                        const RaySpan& span, std::int32_t region_voxels,
                                        float* traversal, float ray_metres,
                                        Visit&& visit) noexcept {
  // The traversal walks a copy of the span first, the misses walk it again: two tight loops,
  // each with one array to miss in, ran 1.35 times as fast as one loop updating both (one
  // thread, Ouster scans).
  const SpanWalk s = startSpanWalk(ray, sample_is_start, span, region_voxels);
  addSpanWalkPath(s, ray, span, region_voxels, traversal, ray_metres);
  visitSpanWalk(s, std::forward<Visit>(visit));
  return static_cast<std::uint32_t>(s.count);
}

/// Per-ray miss: every crossing lowers the occupancy.
struct PerRayMiss {
  float* occupancy;
  rm_occupancy_params params;
  void operator()(std::uint32_t i) const noexcept {
    occupancy[i] = rm_occupancy_miss(occupancy[i], params);
  }
};

/// Per-scan miss: marks the voxel crossed in this scan; applyScanMisses() lowers the occupancy
/// of each marked voxel once at the end of the batch, unless the scan hit it (occupied wins).
struct PerScanMiss {
  std::uint64_t* misses;  ///< ScanBits::missPlane of the region
  void operator()(std::uint32_t i) const noexcept { ScanBits::mark(misses, i); }
};

/// @brief Walks one span of a TSDF map's ray and fuses the ray into each voxel
/// (kernels/common/tsdf.h): free-space voxels (rm_tsdf_is_free) at +tau without computing their
/// distance, the others at their signed distance. Returns the voxels visited. @rt allocates: no.
inline std::uint32_t tsdfSpan(const rm_line_walk_ray& ray, bool sample_is_start,
                              const RaySpan& span, std::int32_t region_voxels, rm_tsdf_voxel* tsdf,
                              float tsdf_end_m, const rm_tsdf_params& params) noexcept {
  SpanWalk s = startSpanWalk(ray, sample_is_start, span, region_voxels);
  rm_span_walk& walk = s.walk;
  const std::int32_t count = s.count;
  const int reverse = s.reverse;
  const rm_tsdf_ray r = rm_tsdf_ray_make(&ray, reverse, tsdf_end_m);
  const float bound = rm_tsdf_free_bound(&r, params);
  // Two loops over chunks of the span: the walk (indices and distances, a prefetch of each
  // voxel's line), then the updates. A TSDF update is long enough that one loop doing both kept
  // few of the span's cache misses in flight; this ran 1.2 times as fast (one thread, Ouster
  // scans: 0.60 -> 0.72 of occupancy). The same split made occupancy slower (0.93 times: its
  // miss is short and the processor already overlaps it), so its walk stays one loop.
  constexpr std::int32_t kChunk = 64;
  std::uint32_t indices[kChunk];
  float sdfs[kChunk];
  for (std::int32_t done = 0; done < count; done += kChunk) {
    const std::int32_t n = std::min(kChunk, count - done);
    for (std::int32_t k = 0; k < n; ++k) {
      indices[k] =
          done + k == 0 ? static_cast<std::uint32_t>(walk.index) : rm_span_walk_advance(&walk);
      __builtin_prefetch(&tsdf[indices[k]], 1);
      sdfs[k] = rm_tsdf_is_free(rm_line_walk_t_enter(&walk.walk), bound, reverse) != 0
                    ? params.truncation
                    : rm_tsdf_sdf(&r, rm_span_walk_voxel(&walk), params.resolution);
    }
    for (std::int32_t k = 0; k < n; ++k) {
      rm_tsdf_update(&tsdf[indices[k]], sdfs[k], params);
    }
  }
  return static_cast<std::uint32_t>(count);
}

/// @brief Pointers to one region's layers (null for absent layers).
struct RegionLayers {
  float* occupancy = nullptr;
  rm_voxel_mean* mean = nullptr;
  std::uint64_t* scan_bits = nullptr;    ///< per-scan semantics: ScanBits::bitsFor the region
  std::uint64_t* scan_misses = nullptr;  ///< per-scan semantics: its ScanBits::missPlane
  rm_ndt_voxel* ndt = nullptr;
  rm_ndt_hit_miss* hit_miss = nullptr;
  rm_ndt_intensity* intensity = nullptr;
  float* traversal = nullptr;  ///< decay rate: metres of ray path per voxel
  rm_tsdf_voxel* tsdf = nullptr;
};

/// NDT miss (kernels/common/ndt.h): each crossing lowers the occupancy by how squarely the ray
/// meets the voxel's Gaussian; NDT-TM also counts the pass.
struct NdtMiss {
  float* occupancy;
  const rm_voxel_mean* mean;  ///< null without the mean layer (its count spares the Gaussian)
  const rm_ndt_voxel* ndt;
  rm_ndt_hit_miss* hit_miss;  ///< null for NDT-OM
  const rm_line_walk_ray* ray;
  int sample_is_start;
  int has_sample;  ///< the ray ends in a return (RM_RAY_END_HIT)
  rm_occupancy_params occupancy_params;
  rm_ndt_params params;
  /// The common case inline (free space: a plain miss from the occupancy and the mean count),
  /// the Gaussian out of line.
  [[gnu::always_inline]] void operator()(std::uint32_t i, rm_vec3i voxel) const noexcept {
    const float value = occupancy[i];
    // No test of NDT-OM's lower clamp here, though a clamped voxel cannot change: in a map still
    // being built, clamped and unclamped voxels alternate along a ray and the branch is
    // mispredicted so often that skipping the mean's count cost more than loading it (one
    // thread, fresh map of the Ouster scans: 0.45 M rays/s with the test, 0.57 M without).
    if (!rm_occupancy_observed(value)) {
      occupancy[i] = rm_occupancy_miss(value, occupancy_params);
      return;  // unobserved: no sample yet
    }
    const std::uint32_t samples = mean != nullptr ? mean[i].count : ndt[i].count;
    if (samples < params.sample_threshold) {
      occupancy[i] = rm_occupancy_miss(value, occupancy_params);
      countPass(i, samples, 1);
      return;
    }
    shaped(i, voxel);
  }

 private:
  [[gnu::noinline]] void shaped(std::uint32_t i, rm_vec3i voxel) const noexcept {
    rm_vec3f origin;
    rm_vec3f sample;
    rm_ndt_ray_in_voxel(ray, sample_is_start, voxel, &origin, &sample);
    int is_miss = 0;
    occupancy[i] = rm_ndt_miss(occupancy[i], &ndt[i], origin, sample, has_sample, occupancy_params,
                               params, &is_miss);
    countPass(i, ndt[i].count, is_miss);
  }

  /// NDT-TM counts passes from a voxel's first sample on: its first hit restarts the counts
  /// (rm_ndt_hit), so passes before it would be dropped anyway.
  void countPass(std::uint32_t i, std::uint32_t samples, int is_miss) const noexcept {
    if (hit_miss != nullptr && samples > 0u) {
      rm_ndt_count_miss(&hit_miss[i], is_miss);
    }
  }
};

/// @brief Folds a ray's sample into its voxel's mean. The mean layer's pages stay the OS's zero
/// pages until a sample lands there: the first access is a write (platform/write_intent.hpp), so
/// that the update's read does not map the zero page only for its write to copy it.
inline void foldSampleIntoMean(rm_voxel_mean& m, const rm_prepared_ray& ray) noexcept {
  platform::touchForWrite(&m);
  m.packed = rm_mean_fold(m.packed, m.count, ray.sample_local);
  m.count = rm_mean_count_increment(m.count);
}

/// @brief Applies a ray's hit to its sample voxel (index `i` of region `layers`). Per-scan hits
/// change the occupancy in a separate pass (applyScanHit); here they only feed the mean.
/// @pre ray.flags has RM_RAY_END_HIT.
inline void applySampleHit(const rm_prepared_ray& ray, const RegionLayers& layers, std::uint32_t i,
                           bool per_scan, const rm_occupancy_params& params) noexcept {
  if (!per_scan && layers.occupancy != nullptr) {  // decay-rate-only maps: the mean alone
    layers.occupancy[i] = rm_occupancy_hit(layers.occupancy[i], params);
  }
  if (layers.mean != nullptr) {
    foldSampleIntoMean(layers.mean[i], ray);
  }
}

/// @brief NDT hit of a ray's sample (kernels/common/ndt.h): occupancy, Gaussian, NDT-TM counts
/// and intensity, and the voxel mean.
/// @pre ray.flags has RM_RAY_END_HIT.
inline void applyNdtHit(const rm_prepared_ray& ray, const RegionLayers& layers, std::uint32_t i,
                        const rm_occupancy_params& params, const rm_ndt_params& ndt) noexcept {
  // The sample layers' pages may still be zero pages (foldSampleIntoMean).
  platform::touchForWrite(&layers.ndt[i]);
  if (layers.hit_miss != nullptr) {
    platform::touchForWrite(&layers.hit_miss[i]);
  }
  if (layers.intensity != nullptr) {
    platform::touchForWrite(&layers.intensity[i]);
  }
  rm_ndt_hit(&layers.occupancy[i], &layers.ndt[i],
             layers.hit_miss != nullptr ? &layers.hit_miss[i] : nullptr,
             layers.intensity != nullptr ? &layers.intensity[i] : nullptr,
             rm_ndt_origin_at_sample(ray), ray.sample_local, ray.intensity, params, ndt);
  if (layers.mean != nullptr) {
    foldSampleIntoMean(layers.mean[i], ray);
  }
}

/// @brief Per-scan hit pass: the first hit of a voxel in this scan raises its occupancy once.
inline void applyScanHit(const RegionLayers& layers, std::uint32_t i,
                         const rm_occupancy_params& params) noexcept {
  if (ScanBits::claim(layers.scan_bits, i) && layers.occupancy != nullptr) {
    layers.occupancy[i] = rm_occupancy_hit(layers.occupancy[i], params);
  }
}

/// @brief Per-scan miss pass of one region, after all of the batch's walks through it: every
/// voxel a ray crossed (miss plane) that the scan did not hit (hit plane) takes one miss. Word
/// by word, so the occupancy is read in index order and only where a bit is set.
inline void applyScanMisses(const RegionLayers& layers, std::size_t words,
                            const rm_occupancy_params& params) noexcept {
  if (layers.occupancy == nullptr || layers.scan_misses == nullptr) {
    return;  // not a per-scan occupancy map (MapConfig::validate allows none)
  }
  for (std::size_t w = 0; w < words; ++w) {
    std::uint64_t pending = layers.scan_misses[w] & ~layers.scan_bits[w];
    float* occupancy = layers.occupancy + (w * 64u);
    while (pending != 0u) {
      const int bit = __builtin_ctzll(pending);
      occupancy[bit] = rm_occupancy_miss(occupancy[bit], params);
      pending &= pending - 1u;
    }
  }
}

/// @brief What every integration step needs to know about the map and the batch.
struct IntegrationContext {
  VoxelMap* map = nullptr;
  std::int32_t region_voxels = 32;
  rm_occupancy_params params{};

  bool per_scan = false;
  std::uint32_t sequence = 0;  ///< scan sequence of this batch (per-scan semantics)
  /// Per-scan semantics: the batch's once-per-scan bits (ScanBits::beginBatch called with
  /// `sequence`); null per ray.
  ScanBits* scan_bits = nullptr;
  /// NDT maps: a batch's misses all come before its hits (see kernels/common/ndt.h).
  bool ndt = false;
  rm_ndt_params ndt_params{};
  float resolution = 0.1f;       ///< voxel edge, metres (decay rate: path lengths in metres)
  rm_tsdf_params tsdf_params{};  ///< TSDF maps
};

/// @brief Whether a batch of `ctx` may be cut between any two rays without changing the map:
/// per ray, no NDT (an NDT batch's hits follow all its misses; a per-scan batch is one scan).
inline bool splitsAtAnyRay(const IntegrationContext& ctx) noexcept {
  return !ctx.per_scan && !ctx.ndt;
}

/// @brief Pointers to the layers of the region in `slot` (and, per scan, to its bits: call from
/// the thread that owns the region in this batch).
inline RegionLayers regionLayers(const IntegrationContext& ctx, std::uint32_t slot) noexcept {
  const VoxelMap& map = *ctx.map;
  const RegionStore& store = map.store();
  RegionLayers layers;
  if (map.occupancyLayer() >= 0) {
    layers.occupancy = store.layerData<float>(slot, map.occupancyLayer());
  }
  if (map.meanLayer() >= 0) {
    layers.mean = store.layerData<rm_voxel_mean>(slot, map.meanLayer());
  }
  if (ctx.scan_bits != nullptr) {
    layers.scan_bits = ctx.scan_bits->bitsFor(slot);
    layers.scan_misses = ctx.scan_bits->missPlane(layers.scan_bits);
  }
  if (map.ndtLayer() >= 0) {
    layers.ndt = store.layerData<rm_ndt_voxel>(slot, map.ndtLayer());
  }
  if (map.hitMissLayer() >= 0) {
    layers.hit_miss = store.layerData<rm_ndt_hit_miss>(slot, map.hitMissLayer());
  }
  if (map.intensityLayer() >= 0) {
    layers.intensity = store.layerData<rm_ndt_intensity>(slot, map.intensityLayer());
  }
  if (map.traversalLayer() >= 0) {
    layers.traversal = store.layerData<float>(slot, map.traversalLayer());
  }
  if (map.tsdfLayer() >= 0) {
    layers.tsdf = store.layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
  }
  return layers;
}

/// @brief Walks one span with the semantics' miss rule (TSDF maps: the TSDF update; decay-rate-only
/// maps: the path lengths); returns
/// the voxels visited. `ray_flags`, `tsdf_end_m`: the prepared ray's RM_RAY_* flags and signed
/// distance at its end.
inline std::uint32_t missSpan(const IntegrationContext& ctx, const rm_line_walk_ray& ray,
                              bool sample_is_start, std::uint32_t ray_flags, float tsdf_end_m,
                              const RaySpan& span, const RegionLayers& layers) noexcept {
  if (layers.tsdf != nullptr) {
    return tsdfSpan(ray, sample_is_start, span, ctx.region_voxels, layers.tsdf, tsdf_end_m,
                    ctx.tsdf_params);
  }
  if (layers.occupancy == nullptr) {  // a decay-rate-only map: its path and nothing else
    return addSpanPath(ray, sample_is_start, span, ctx.region_voxels, layers.traversal,
                       rm_decay_ray_metres(&ray, ctx.resolution));
  }
  const auto walk = [&](auto&& miss) {
    if (layers.traversal != nullptr) {
      return walkSpanAddingPath(ray, sample_is_start, span, ctx.region_voxels, layers.traversal,
                                rm_decay_ray_metres(&ray, ctx.resolution), miss);
    }
    return walkSpan(ray, sample_is_start, span, ctx.region_voxels, miss);
  };
  if (ctx.ndt) {
    return walk(NdtMiss{layers.occupancy, layers.mean, layers.ndt, layers.hit_miss, &ray,
                        sample_is_start ? 1 : 0, (ray_flags & RM_RAY_END_HIT) != 0u ? 1 : 0,
                        ctx.params, ctx.ndt_params});
  }
  if (ctx.per_scan) {
    return walk(PerScanMiss{layers.scan_misses});
  }
  return walk(PerRayMiss{layers.occupancy, ctx.params});
}

/// @brief Region and in-region index of a ray's sample voxel (integer divisions; the region walk
/// has a cheaper RayRegionWalk::sampleCell()).
inline std::pair<Vec3i, std::uint32_t> sampleCellOf(const rm_prepared_ray& ray,
                                                    std::int32_t n) noexcept {
  const rm_vec3i region = rm_region_of_voxel(ray.sample_voxel, n);
  return {Vec3i{region.x, region.y, region.z},
          rm_local_index(rm_local_in_region(ray.sample_voxel, region, n), n)};
}

/// @brief Slot of an existing region by packed coordinate, or RegionStore::kNoSlot (read-only
/// lookups; several threads may look up concurrently, each with its own cache).
inline std::uint32_t findSlot(const RegionStore& store, RegionSlotCache& cache,
                              std::uint64_t key) noexcept {
  if (const std::uint32_t* cached = cache.find(key)) {
    return *cached;
  }
  const std::uint32_t slot = store.findPacked(key);
  cache.remember(slot);
  return slot;
}

/// @brief Counters of one worker during one batch.
struct WorkerStats {
  std::uint64_t voxels_visited = 0;
  std::uint64_t spans_outside_window = 0;
};

}  // namespace raymap::detail
