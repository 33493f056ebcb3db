/* SPDX-License-Identifier: BSD-3-Clause */
/* Occupancy (+ voxel mean, + per-scan marks) integration on a device: the bodies of the two
 * kernels, written once for OpenCL and CUDA over the shared rules in kernels/common.
 *
 * Layout. Each layer is one device buffer cut into cache slots of voxels_per_region voxels; a
 * voxel is at slot * voxels_per_region + index.
 *
 * Per-ray semantics: each span work-item applies misses to its voxels and, if its span holds the
 * ray's sample, the hit after them, as the CPU does ray by ray. Updates of different rays race on
 * the same voxel: they are applied with a 32-bit compare-and-swap, retried at most
 * RM_CAS_RETRY_LIMIT times; an update still failing then is dropped and counted
 * (RM_COUNTER_DROPPED), never lost silently. An update that would not change the value (a voxel
 * already at its clamp: most of free space) writes nothing. The order of different rays' updates
 * of one voxel is the device's, so where clamping makes the order matter values can differ from
 * the CPU reference (the tests bound how often). rm_apply_hit_group then folds voxel means.
 *
 * Per-scan semantics: rm_apply_hit_group runs first, then rm_integrate_span, as on the CPU. The
 * scan mark decides a single writer per voxel (atomic_max on the monotone mark), so occupancy is
 * updated with plain stores and the result equals the CPU reference exactly.
 *
 * Voxel means: one work-item per voxel folds all of the batch's samples of that voxel in ray order
 * (the host groups them), so means match the CPU reference bit for bit and need no atomics. */
#ifndef RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H
#define RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H

#include "../common/batch.h"
#include "../common/line_walk.h"
#include "../common/occupancy.h"
#include "../common/ray.h"
#include "../common/scan_mark.h"
#include "../common/span_walk.h"
#include "../common/voxel_mean.h"
#include "device.h"

/* Compare-and-swap attempts per miss before the update is given up (and counted). */
#define RM_CAS_RETRY_LIMIT 64

#if defined(RM_HAVE_INT64_ATOMICS)
typedef rm_u64 rm_counter;
RM_DEVICE_FN void rm_count(RM_ATOMIC_GLOBAL rm_counter* counters, rm_u32 which, rm_u32 amount) {
  (void)rm_atomic_add_u64(counters + which, (rm_u64)amount);
}
#else
/* 32-bit counters: the host sizes batches so that no bucket can wrap within one batch. */
typedef rm_u32 rm_counter;
RM_DEVICE_FN void rm_count(RM_ATOMIC_GLOBAL rm_counter* counters, rm_u32 which, rm_u32 amount) {
  (void)rm_atomic_add_u32(counters + which, amount);
}
#endif

/* Applies a miss (hit = 0) or a hit (hit = 1) to one occupancy word with bounded
 * compare-and-swap. Returns 0 when the update was given up. */
RM_DEVICE_FN int rm_occupancy_update_atomic(RM_ATOMIC_GLOBAL rm_u32* word, int hit,
                                            rm_occupancy_params p) {
  rm_u32 old = rm_load_u32(word);
  int attempt;
  for (attempt = 0; attempt < RM_CAS_RETRY_LIMIT; ++attempt) {
    float value = rm_as_float(old);
    float updated = hit ? rm_occupancy_hit(value, p) : rm_occupancy_miss(value, p);
    rm_u32 seen;
    if (updated == value) {
      return 1;
    }
    seen = rm_atomic_cas_u32(word, old, rm_as_u32(updated));
    if (seen == old) {
      return 1;
    }
    old = seen;
  }
  return 0;
}

/* Work-item `id`: walks span `id`, applies the semantics' miss rule to its voxels and, per ray,
 * the hit to a sample voxel the span holds. */
RM_DEVICE_FN void rm_integrate_span(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                    const RM_GLOBAL rm_span_record* spans,
                                    RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                    RM_ATOMIC_GLOBAL rm_u32* marks, rm_integrate_params p,
                                    RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_span_record span = spans[id];
  rm_prepared_ray ray = rays[span.ray];
  rm_ray_walk_frame frame = rm_ray_walk_frame_make(ray);
  rm_line_walk_ray walk_ray = rm_line_walk_ray_make(frame.start, frame.end, frame.end_voxel);
  rm_span_walk walk;
  rm_u32 base = span.slot * p.voxels_per_region;
  rm_u32 dropped = 0u;
  rm_i32 count = rm_span_walk_init(&walk, &walk_ray, span.t0, span.t1, span.box_lo, p.region_voxels,
                                   span.flags, frame.sample_is_start);
  rm_i32 k;
  rm_u32 miss_mark = rm_scan_mark_miss(p.sequence);
  for (k = 0; k < count; ++k) {
    rm_u32 i = base + (k == 0 ? RM_U32(walk.index) : rm_span_walk_advance(&walk));
    if (p.per_scan != 0u) {
      /* The first miss of this scan wins the mark and is the only writer of the voxel. */
      if (rm_load_u32(marks + i) < miss_mark &&
          rm_atomic_max_u32(marks + i, miss_mark) < miss_mark) {
        occupancy[i] = rm_as_u32(rm_occupancy_miss(rm_as_float(occupancy[i]), p.occupancy));
      }
    } else if (!rm_occupancy_update_atomic(occupancy + i, 0, p.occupancy)) {
      dropped += 1u;
    }
  }
  if (span.sample != RM_SPAN_NO_SAMPLE) {
    if (!rm_occupancy_update_atomic(occupancy + base + span.sample, 1, p.occupancy)) {
      dropped += 1u;
    }
    count += 1;
  }
  if (count > 0) {
    rm_count(counters, id % RM_COUNTER_BUCKETS, RM_U32(count));
  }
  if (dropped != 0u) {
    rm_count(counters, RM_COUNTER_DROPPED, dropped);
  }
}

/* Work-item `id`: folds every sample of hit group `id` into its voxel's mean, in ray order, and
 * with per-scan semantics applies the scan's hit. The only work-item writing this voxel during
 * the launch. */
RM_DEVICE_FN void rm_apply_hit_group(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                     const RM_GLOBAL rm_hit_group* groups,
                                     const RM_GLOBAL rm_u32* hit_rays,
                                     RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                     RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* marks,
                                     rm_integrate_params p, RM_ATOMIC_GLOBAL rm_counter* counters) {
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
  if (p.per_scan != 0u) {
    if (rm_scan_needs_hit(marks[i], p.sequence)) {
      occupancy[i] = rm_as_u32(rm_occupancy_hit(rm_as_float(occupancy[i]), p.occupancy));
      marks[i] = rm_scan_mark_hit(p.sequence);
    }
    rm_count(counters, id % RM_COUNTER_BUCKETS, group.count);
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_H */
