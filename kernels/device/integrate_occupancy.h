/* SPDX-License-Identifier: BSD-3-Clause */
/* Occupancy (+ voxel mean, + per-scan marks) integration on a device: the bodies of the kernels,
 * written once for OpenCL and CUDA over the shared rules in kernels/common.
 *
 * Layout. Each layer is one device buffer cut into cache slots of voxels_per_region voxels; a
 * voxel is at slot * voxels_per_region + index. The host groups the batch's samples per voxel
 * (rm_hit_group, rays in ray order) and cuts the rays into span records (one per region piece).
 *
 * Per-ray semantics, three launches, and the result equals the CPU reference bit for bit:
 *  1. rm_tag_hit_group: each voxel that samples fell in saves its value in the batch scratch and
 *     is replaced by a tag (a NaN carrying the group number). Only these voxels see both hits and
 *     misses in the batch, so only their updates depend on order.
 *  2. rm_integrate_span: misses along each span. An untagged voxel takes its miss with a 32-bit
 *     compare-and-swap, retried at most RM_CAS_RETRY_LIMIT times (an update still failing is
 *     dropped and counted in RM_COUNTER_DROPPED, never lost silently; one that would not change the
 *     value, a voxel at the lower clamp, writes nothing). Misses are all the same addition with a
 *     lower clamp, so their order does not matter. A miss to a tagged voxel is not applied but
 *     counted in the run of misses between the two of the group's hits that surround its ray
 *     (found by binary search in the group's sorted ray list).
 *  3. rm_apply_hit_group: replays each tagged voxel's updates in ray order from the saved value:
 *     run 0 of misses, hit 1, run 1, ..., hit n, run n; and folds the voxel means.
 *
 * Per-scan semantics, as on the CPU: rm_apply_hit_group first (the scan's hit, once per voxel),
 * then rm_integrate_span, where atomic_max on the monotone scan mark elects one writer per voxel
 * and scan for the miss (a plain store). The result equals the CPU reference exactly.
 *
 * Voxel means: one work-item per voxel folds all of the batch's samples of that voxel in ray
 * order, so means match the CPU reference bit for bit and need no atomics.
 *
 * Decay-rate maps (RM_MODE_TRAVERSAL): rm_integrate_span also adds each span's metres of path to
 * the traversal layer (traversal.h), in either semantics, with float atomics; the sums equal the
 * CPU's up to rounding (the order of the adds differs).
 *
 * TSDF maps (RM_MODE_TSDF): no occupancy layer and no hits; rm_integrate_span fuses each ray into
 * the TSDF layer of the voxels of its spans (tsdf.h), and that is the whole batch.
 *
 * Decay-rate-only maps (RM_MODE_TRAVERSAL alone; per-ray semantics): no occupancy
 * and so no tags; rm_integrate_span adds the path lengths, then rm_apply_hit_group folds the
 * voxel means (their counts are the samples). */
#ifndef RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H
#define RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H

#include "../common/batch.h"
#include "../common/line_walk.h"
#include "../common/map_mode.h"
#include "../common/occupancy.h"
#include "../common/ray.h"
#include "../common/scan_mark.h"
#include "../common/span_walk.h"
#include "../common/voxel_mean.h"
#include "counters.h"
#include "device.h"
#include "traversal.h"
#include "tsdf.h"

#if defined(__OPENCL_C_VERSION__) && !defined(RM_MAP_MODE)
#error "build the occupancy program with -DRM_MAP_MODE=<bits> (kernels/common/map_mode.h)"
#endif

/* A tagged occupancy word: a quiet NaN whose low 22 bits hold the hit group (occupancy values
 * are never NaN: rays are validated, and +inf marks "unobserved"). */
#define RM_TAG_BITS 0x7FC00000u
#define RM_TAG_GROUP_MASK (RM_TAG_MAX_GROUPS - 1u)

RM_DEVICE_FN int rm_is_tag(rm_u32 word) { return (word & RM_TAG_BITS) == RM_TAG_BITS; }

/* Where group g's runs of misses start in the scratch buffer: after the saved values (one per
 * group), count + 1 runs per group. */
RM_DEVICE_FN rm_u32 rm_runs_offset(rm_hit_group group, rm_u32 g, rm_integrate_params p) {
  return p.group_count + group.first + g;
}

/* Number of the group's hit rays that come before `ray` (the rays are sorted). */
RM_DEVICE_FN rm_u32 rm_hits_before(const RM_GLOBAL rm_u32* hit_rays, rm_hit_group group,
                                   rm_u32 ray) {
  rm_u32 lo = 0u;
  rm_u32 hi = group.count;
  while (lo < hi) {
    rm_u32 mid = lo + (hi - lo) / 2u;
    if (hit_rays[group.first + mid] < ray) {
      lo = mid + 1u;
    } else {
      hi = mid;
    }
  }
  return lo;
}

/* Per-ray semantics, launch 1. Work-item `id`: saves the value of hit group `id`'s voxel and tags
 * it. */
RM_DEVICE_FN void rm_tag_hit_group(rm_u32 id, const RM_GLOBAL rm_hit_group* groups,
                                   RM_ATOMIC_GLOBAL rm_u32* occupancy, RM_GLOBAL rm_u32* scratch,
                                   rm_integrate_params p) {
  rm_hit_group group = groups[id];
  rm_u32 i = group.slot * p.voxels_per_region + group.index;
  scratch[id] = occupancy[i];
  occupancy[i] = RM_TAG_BITS | id;
}

/* Per-ray misses along a span (the mode's rule): an untagged voxel takes the miss by
 * compare-and-swap; a tagged one (samples in this batch) has the miss counted in its place among
 * the group's hits. Returns the updates given up. */
RM_DEVICE_FN rm_u32 rm_ray_miss_span(rm_span_walk walk, rm_i32 count, rm_u32 base, rm_u32 ray,
                                     const RM_GLOBAL rm_hit_group* groups,
                                     const RM_GLOBAL rm_u32* hit_rays,
                                     RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                     RM_ATOMIC_GLOBAL rm_u32* scratch, rm_integrate_params p) {
  rm_u32 dropped = 0u;
  rm_i32 k;
  for (k = 0; k < count; ++k) {
    rm_u32 i = base + (k == 0 ? RM_U32(walk.index) : rm_span_walk_advance(&walk));
    rm_u32 word = rm_load_u32(occupancy + i);
    if (rm_is_tag(word)) {
      rm_u32 g = word & RM_TAG_GROUP_MASK;
      rm_hit_group group = groups[g];
      rm_u32 run = rm_runs_offset(group, g, p) + rm_hits_before(hit_rays, group, ray);
      (void)rm_voxel_add_u32(scratch + run, 1u);
    } else if (!rm_occupancy_miss_atomic(occupancy + i, word, p.occupancy)) {
      dropped += 1u;
    }
  }
  return dropped;
}

/* Per-scan misses along a span (the mode's rule): the first miss of this scan wins the voxel's
 * mark and is its only writer (a voxel the scan hit already holds the hit mark). */
RM_DEVICE_FN void rm_scan_miss_span(rm_span_walk walk, rm_i32 count, rm_u32 base,
                                    RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                    RM_ATOMIC_GLOBAL rm_u32* marks, rm_integrate_params p) {
  rm_u32 miss_mark = rm_scan_mark_miss(p.sequence);
  rm_i32 k;
  for (k = 0; k < count; ++k) {
    rm_u32 i = base + (k == 0 ? RM_U32(walk.index) : rm_span_walk_advance(&walk));
    if (rm_load_u32(marks + i) < miss_mark && rm_voxel_max_u32(marks + i, miss_mark) < miss_mark) {
      occupancy[i] = rm_as_u32(rm_occupancy_miss(rm_as_float(occupancy[i]), p.occupancy));
    }
  }
}

/* Work-item `id`: walks span `id` and applies the map mode's rules to its voxels (RM_MAP_MODE,
 * kernels/common/map_mode.h; each `if` below is a constant of the kernel's mode): TSDF maps fuse
 * the ray into `tsdf` (distance, weight float pairs as bits) and nothing else; decay-rate maps
 * add the span's path to `traversal` (float metres as bits); occupancy maps apply their
 * semantics' miss. Layers the mode lacks are placeholders and never touched. */
RM_MODE_FN void rm_integrate_span(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                  const RM_GLOBAL rm_span_record* spans,
                                  const RM_GLOBAL rm_hit_group* groups,
                                  const RM_GLOBAL rm_u32* hit_rays,
                                  RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                  RM_ATOMIC_GLOBAL rm_u32* marks, RM_ATOMIC_GLOBAL rm_u32* scratch,
                                  RM_ATOMIC_GLOBAL rm_u32* traversal, RM_ATOMIC_GLOBAL rm_u32* tsdf,
                                  rm_integrate_params p, RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_span_record span = spans[id];
  rm_prepared_ray ray = rays[span.ray];
  rm_ray_walk_frame frame = rm_ray_walk_frame_make(ray);
  rm_line_walk_ray walk_ray = rm_line_walk_ray_make(frame.start, frame.end, frame.end_voxel);
  rm_span_walk walk;
  rm_u32 base = span.slot * p.voxels_per_region;
  rm_u32 dropped = 0u;
  rm_i32 count = rm_span_walk_init(&walk, &walk_ray, span.t0, span.t1, span.box_lo, p.region_voxels,
                                   span.flags, frame.sample_is_start);
  if (RM_MAP_MODE_HAS(RM_MODE_TSDF)) {
    dropped += rm_tsdf_span(tsdf, base, walk, count, &walk_ray, frame.sample_is_start,
                            ray.tsdf_end_m, p.tsdf);
  }
  if (RM_MAP_MODE_HAS(RM_MODE_TRAVERSAL)) {
    dropped += rm_traversal_add_span(traversal, base, walk, count, &walk_ray, span,
                                     frame.sample_is_start, p.region_voxels, p.resolution);
  }
  if (RM_MAP_MODE_HAS(RM_MODE_OCCUPANCY)) {
    if (RM_MAP_MODE_HAS(RM_MODE_PER_SCAN)) {
      rm_scan_miss_span(walk, count, base, occupancy, marks, p);
    } else {
      dropped +=
          rm_ray_miss_span(walk, count, base, span.ray, groups, hit_rays, occupancy, scratch, p);
    }
  }
  if (count > 0) {
    rm_count(counters, id % RM_COUNTER_BUCKETS, RM_U32(count));
  }
  if (dropped != 0u) {
    rm_count(counters, RM_COUNTER_DROPPED, dropped);
  }
}

/* Work-item `id`: applies hit group `id` to its voxel, the only work-item writing it during the
 * launch: folds the samples into the voxel mean in ray order; per ray, replays the voxel's hits
 * and the runs of misses between them from the saved value; per scan, applies the scan's hit. */
RM_MODE_FN void rm_apply_hit_group(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                   const RM_GLOBAL rm_hit_group* groups,
                                   const RM_GLOBAL rm_u32* hit_rays,
                                   RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                   RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* marks,
                                   const RM_GLOBAL rm_u32* scratch, rm_integrate_params p,
                                   RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_hit_group group = groups[id];
  rm_u32 i = group.slot * p.voxels_per_region + group.index;
  rm_u32 k;
  if (p.has_mean != 0u) {
    rm_voxel_mean mean = means[i];
    for (k = 0u; k < group.count; ++k) {
      rm_prepared_ray ray = rays[hit_rays[group.first + k]];
      mean.packed = rm_mean_fold(mean.packed, mean.count, ray.sample_local);
      mean.count = rm_mean_count_increment(mean.count);
    }
    means[i] = mean;
  }
  if (!RM_MAP_MODE_HAS(RM_MODE_OCCUPANCY)) {
    /* Decay rates only: the mean is the whole hit. */
  } else if (RM_MAP_MODE_HAS(RM_MODE_PER_SCAN)) {
    if (rm_scan_needs_hit(marks[i], p.sequence)) {
      occupancy[i] = rm_as_u32(rm_occupancy_hit(rm_as_float(occupancy[i]), p.occupancy));
      marks[i] = rm_scan_mark_hit(p.sequence);
    }
  } else {
    rm_u32 runs = rm_runs_offset(group, id, p);
    float value = rm_as_float(scratch[id]);
    rm_u32 m;
    for (k = 0u; k <= group.count; ++k) {
      for (m = scratch[runs + k]; m > 0u; --m) {
        value = rm_occupancy_miss(value, p.occupancy);
      }
      if (k < group.count) {
        value = rm_occupancy_hit(value, p.occupancy);
      }
    }
    occupancy[i] = rm_as_u32(value);
  }
  rm_count(counters, id % RM_COUNTER_BUCKETS, group.count);
}

#endif /* RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H */
