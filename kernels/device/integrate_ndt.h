/* SPDX-License-Identifier: BSD-3-Clause */
/* NDT-OM / NDT-TM integration on a device: the bodies of the kernels, written once for OpenCL
 * and CUDA over the update rules of kernels/common/ndt.h.
 *
 * Layout as for occupancy (integrate_occupancy.h): each layer is one device buffer cut into cache
 * slots of voxels_per_region voxels, a voxel is at slot * voxels_per_region + index; the host cuts
 * the rays into span records and groups the batch's samples per voxel (rm_hit_group, rays in ray
 * order, one group per distinct sample voxel).
 *
 * Batch semantics (ndt.h): all misses of the batch first, against the Gaussians as they were at
 * the start of the batch, then the hits voxel by voxel in ray order. Two launches give exactly
 * that, with no tagging pass:
 *  1. rm_ndt_integrate_span, one work-item per span record: the NDT miss of every voxel the span
 *     crosses. The Gaussians are read-only in this launch; the occupancy word takes the miss with
 *     a compare-and-swap retried at most RM_CAS_RETRY_LIMIT times (one still failing is given up
 *     and counted in RM_COUNTER_DROPPED), and NDT-TM adds the pass to the voxel's miss count with
 *     an atomic add. Misses are additions of log-odds with a lower clamp, so their order changes
 *     the result only by rounding and at the clamp.
 *  2. rm_ndt_apply_hit_group, one work-item per hit group: loads the voxel's occupancy, Gaussian,
 *     counts, intensity and mean once, folds its samples in ray order with rm_ndt_hit (and
 *     rm_mean_fold) and writes them once. A covariance cannot be folded with single-word atomics,
 *     and the fold is sequential in ray order anyway; grouping per voxel on the host means every
 *     work-item has work (no idle work-item per duplicate sample, unlike one thread per ray).
 *
 * Decay-rate maps (RM_MODE_TRAVERSAL): launch 1 also adds each span's metres of path to the
 * traversal layer (traversal.h), as the occupancy kernel does. */
#ifndef RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_H
#define RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_H

#if defined(__OPENCL_C_VERSION__) && !defined(RM_MAP_MODE)
#error "build the NDT program with -DRM_MAP_MODE=<bits> (kernels/common/map_mode.h)"
#endif

#include "../common/batch.h"
#include "../common/line_walk.h"
#include "../common/map_mode.h"
#include "../common/ndt.h"
#include "../common/occupancy.h"
#include "../common/ray.h"
#include "../common/span_walk.h"
#include "../common/voxel_mean.h"
#include "counters.h"
#include "device.h"
#include "traversal.h"

/* The part of a voxel's Gaussian the miss rule reads. Only the count is loaded at first: a voxel
 * that is unobserved or holds fewer than sample_threshold samples takes a plain miss, which does
 * not read the rest (rm_ndt_miss), and most voxels a ray crosses are free space. */
typedef struct rm_ndt_miss_source {
  rm_ndt_voxel gaussian;
  int loaded; /* gaussian holds the whole voxel, not only its count */
} rm_ndt_miss_source;

/* Applies the NDT miss of a ray (origin, sample: voxel frame of voxel i) to occupancy word i,
 * whose last seen bits are `old`, with bounded compare-and-swap. *is_miss: rm_ndt_miss's verdict
 * for the value that was written. Returns 0 when the update was given up. */
RM_DEVICE_FN int rm_ndt_miss_atomic(RM_ATOMIC_GLOBAL rm_u32* word, rm_u32 old,
                                    const RM_GLOBAL rm_ndt_voxel* ndt, rm_ndt_miss_source* source,
                                    rm_vec3f origin, rm_vec3f sample, int has_sample,
                                    rm_occupancy_params occ, rm_ndt_params p, int* is_miss) {
  int attempt;
  for (attempt = 0; attempt < RM_CAS_RETRY_LIMIT; ++attempt) {
    float value = rm_as_float(old);
    float updated;
    rm_u32 seen;
    if (!source->loaded && rm_occupancy_observed(value) &&
        rm_ndt_shapes_misses(source->gaussian.count, p)) {
      source->gaussian = *ndt;
      source->loaded = 1;
    }
    updated = rm_ndt_miss(value, &source->gaussian, origin, sample, has_sample, occ, p, is_miss);
    if (updated == value) {
      return 1;
    }
    seen = rm_voxel_cas_u32(word, old, rm_as_u32(updated));
    if (seen == old) {
      return 1;
    }
    old = seen;
  }
  return 0;
}

/* NDT-TM: one more pass through voxel i (passes count from a voxel's first sample on: its first
 * hit restarts the counts). The miss count is hit_miss[2 i + 1] (rm_ndt_hit_miss); it saturates
 * like rm_ndt_count_miss, though the check and the add are not one atomic step, which matters
 * only within a few counts of 2^32. */
RM_DEVICE_FN void rm_ndt_count_pass(RM_ATOMIC_GLOBAL rm_u32* hit_miss, rm_u32 i) {
  RM_ATOMIC_GLOBAL rm_u32* misses = hit_miss + i + i + 1u; /* not 2u * i: wraps past 2^31 */
  if (rm_load_u32(misses) != 0xFFFFFFFFu) {
    (void)rm_voxel_add_u32(misses, 1u);
  }
}

/* The miss of a voxel whose Gaussian shapes it (observed, >= sample_threshold samples), with
 * bounded compare-and-swap from the occupancy bits `old`. Returns 1 when it was given up. */
RM_DEVICE_COLD_FN rm_u32 rm_ndt_shaped_miss(RM_ATOMIC_GLOBAL rm_u32* word, rm_u32 old,
                                            const RM_GLOBAL rm_ndt_voxel* ndt,
                                            RM_ATOMIC_GLOBAL rm_u32* hit_miss, rm_u32 i,
                                            const rm_line_walk_ray* walk_ray, int sample_is_start,
                                            rm_vec3i voxel, int has_sample, rm_occupancy_params occ,
                                            rm_ndt_params np) {
  rm_vec3f origin;
  rm_vec3f sample;
  rm_ndt_miss_source source;
  int is_miss = 0;
  rm_ndt_ray_in_voxel(walk_ray, sample_is_start, voxel, &origin, &sample);
  source.gaussian.count = ndt->count;
  source.loaded = 0;
  if (!rm_ndt_miss_atomic(word, old, ndt, &source, origin, sample, has_sample, occ, np, &is_miss)) {
    return 1u;
  }
  if (np.traversability != 0u && is_miss) {
    rm_ndt_count_pass(hit_miss, i);
  }
  return 0u;
}

/* Launch 1. Work-item `id`: walks span `id` and applies the NDT miss to each voxel it crosses
 * (means: the voxel-mean layer, read when p.has_mean);
 * NDT-TM (p.traversability) counts the passes that are misses in hit_miss; decay-rate maps
 * (RM_MODE_TRAVERSAL) add the span's path to `traversal` (float metres as bits). */
RM_MODE_FN void rm_ndt_integrate_span(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                      const RM_GLOBAL rm_span_record* spans,
                                      RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                      const RM_GLOBAL rm_ndt_voxel* ndt,
                                      const RM_GLOBAL rm_voxel_mean* means,
                                      RM_ATOMIC_GLOBAL rm_u32* hit_miss,
                                      RM_ATOMIC_GLOBAL rm_u32* traversal, rm_integrate_params p,
                                      rm_ndt_params np, RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_span_record span = spans[id];
  rm_prepared_ray ray = rays[span.ray];
  rm_ray_walk_frame frame = rm_ray_walk_frame_make(ray);
  rm_line_walk_ray walk_ray = rm_line_walk_ray_make(frame.start, frame.end, frame.end_voxel);
  rm_span_walk walk;
  rm_u32 base = span.slot * p.voxels_per_region;
  rm_u32 dropped = 0u;
  int has_sample = (ray.flags & RM_RAY_END_HIT) != 0u;
  rm_i32 count = rm_span_walk_init(&walk, &walk_ray, span.t0, span.t1, span.box_lo, p.region_voxels,
                                   span.flags, frame.sample_is_start);
  rm_i32 k;
  if (RM_MAP_MODE_HAS(RM_MODE_TRAVERSAL)) {
    dropped += rm_traversal_add_span(traversal, base, walk, count, &walk_ray, span,
                                     frame.sample_is_start, p.region_voxels, p.resolution);
  }
  for (k = 0; k < count; ++k) {
    rm_u32 i = base + (k == 0 ? RM_U32(walk.index) : rm_span_walk_advance(&walk));
    rm_u32 old = rm_load_u32(occupancy + i);
    float value = rm_as_float(old);
    rm_u32 samples;
    /* Free space first, inline and without the Gaussian (as on the CPU): an unobserved voxel
     * has none, and one with fewer samples than the threshold takes a plain miss. The Gaussians
     * do not change during this launch, so the choice holds on a retry. */
    if (!rm_occupancy_observed(value)) {
      dropped += rm_occupancy_miss_atomic(occupancy + i, old, p.occupancy) ? 0u : 1u;
      continue;
    }
    /* NDT-OM at the lower clamp: no miss changes the voxel, so no sample count is read; most
     * free space of a steady map is there. (On the CPU this test cost more than it saved.) */
    if (rm_ndt_miss_is_noop(value, p.occupancy, np)) {
      continue;
    }
    /* The voxel mean's count (8 bytes a voxel) rather than the Gaussian's (40): fewer cache
     * lines. It is never below the Gaussian's (a reinitialisation restarts only the Gaussian),
     * so a voxel it puts below the threshold is below it, and rm_ndt_shaped_miss checks the
     * Gaussian's own count for the others. */
    samples = p.has_mean != 0u ? means[i].count : ndt[i].count;
    if (samples < np.sample_threshold) {
      if (!rm_occupancy_miss_atomic(occupancy + i, old, p.occupancy)) {
        dropped += 1u;
      } else if (np.traversability != 0u && samples > 0u) {
        rm_ndt_count_pass(hit_miss, i);
      }
      continue;
    }
    dropped += rm_ndt_shaped_miss(occupancy + i, old, ndt + i, hit_miss, i, &walk_ray,
                                  frame.sample_is_start, rm_span_walk_voxel(&walk), has_sample,
                                  p.occupancy, np);
  }
  if (count > 0) {
    rm_count(counters, id % RM_COUNTER_BUCKETS, RM_U32(count));
  }
  if (dropped != 0u) {
    rm_count(counters, RM_COUNTER_DROPPED, dropped);
  }
}

/* Launch 2. Work-item `id`: applies hit group `id` to its voxel, the only work-item touching it
 * during the launch: occupancy, Gaussian, NDT-TM counts and intensity, and the voxel mean
 * (p.has_mean), each loaded and stored once, the samples folded in ray order. */
RM_DEVICE_FN void rm_ndt_apply_hit_group(rm_u32 id, const RM_GLOBAL rm_prepared_ray* rays,
                                         const RM_GLOBAL rm_hit_group* groups,
                                         const RM_GLOBAL rm_u32* hit_rays,
                                         RM_GLOBAL rm_u32* occupancy, RM_GLOBAL rm_ndt_voxel* ndt,
                                         RM_GLOBAL rm_ndt_hit_miss* hit_miss,
                                         RM_GLOBAL rm_ndt_intensity* intensity,
                                         RM_GLOBAL rm_voxel_mean* means, rm_integrate_params p,
                                         rm_ndt_params np, RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_hit_group group = groups[id];
  rm_u32 i = group.slot * p.voxels_per_region + group.index;
  int traversability = np.traversability != 0u;
  float value = rm_as_float(occupancy[i]);
  rm_ndt_voxel gaussian = ndt[i];
  rm_ndt_hit_miss counts;
  rm_ndt_intensity stats;
  rm_voxel_mean mean;
  rm_u32 k;
  counts.hit = 0u;
  counts.miss = 0u;
  stats.mean = 0.0f;
  stats.variance = 0.0f;
  mean.packed = 0u;
  mean.count = 0u;
  if (traversability) {
    counts = hit_miss[i];
    stats = intensity[i];
  }
  if (p.has_mean != 0u) {
    mean = means[i];
  }
  for (k = 0u; k < group.count; ++k) {
    rm_prepared_ray ray = rays[hit_rays[group.first + k]];
    rm_ndt_hit(&value, &gaussian, traversability ? &counts : 0, traversability ? &stats : 0,
               rm_ndt_origin_at_sample(ray), ray.sample_local, ray.intensity, p.occupancy, np);
    mean.packed = rm_mean_fold(mean.packed, mean.count, ray.sample_local);
    mean.count = rm_mean_count_increment(mean.count);
  }
  occupancy[i] = rm_as_u32(value);
  ndt[i] = gaussian;
  if (traversability) {
    hit_miss[i] = counts;
    intensity[i] = stats;
  }
  if (p.has_mean != 0u) {
    means[i] = mean;
  }
  rm_count(counters, id % RM_COUNTER_BUCKETS, group.count);
}

#endif /* RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_H */
