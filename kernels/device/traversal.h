/* SPDX-License-Identifier: BSD-3-Clause */
/* Decay-rate maps on a device: what a span adds to the traversal layer (metres of ray path per
 * voxel), by the rules of kernels/common/decay.h, exactly what the CPU's walkSpanAddingPath
 * (src/map/cpu_voxel_ops.hpp) adds for the same span. Shared by the occupancy and NDT span
 * kernels, whose modes with RM_MODE_TRAVERSAL (kernels/common/map_mode.h) call
 * rm_traversal_add_span once a span; the kernels of the other modes do not contain it.
 *
 * Every ray adds its path, whatever the semantics: per-scan marks elect one occupancy writer per
 * voxel and scan, but path length is physical and every ray's counts. Adds of many work-items to
 * one voxel (the sensor's, crossed by every ray of a scan) are atomic (plain adds in ray order
 * with span work per region, RM_REGION_OWNED in device.h); their order changes the
 * sums by float rounding only, and so does OpenCL's sqrt in rm_decay_ray_metres (3 ulp in
 * OpenCL 1.2, not correctly rounded as on the host). An add given up under contention (OpenCL's
 * bounded compare-and-swap, counters.h) is counted in RM_COUNTER_DROPPED by the caller. */
#ifndef RAYMAP_KERNELS_DEVICE_TRAVERSAL_H
#define RAYMAP_KERNELS_DEVICE_TRAVERSAL_H

#include "../common/batch.h"
#include "../common/decay.h"
#include "../common/line_walk.h"
#include "../common/span_walk.h"
#include "counters.h"
#include "device.h"

/* The voxel the span walk leaves out (the sample voxel, or the end voxel of a ray without a
 * return): when span `span` holds it (RM_SPAN_LAST for a forward walk, RM_SPAN_FIRST for a
 * reverse one), adds the part of the ray inside it. `s` as rm_span_walk_init left it; `base`:
 * the span's region in the layer (slot * voxels_per_region). Returns the adds given up (0 or 1). */
RM_DEVICE_FN rm_u32 rm_traversal_add_left_out(RM_ATOMIC_GLOBAL rm_u32* traversal, rm_u32 base,
                                              const rm_span_walk* s, const rm_line_walk_ray* ray,
                                              rm_span_record span, int sample_is_start,
                                              rm_i32 region_voxels, float ray_metres) {
  rm_u32 holder = sample_is_start ? RM_SPAN_FIRST : RM_SPAN_LAST;
  rm_u32 i;
  if ((span.flags & holder) == 0u) {
    return 0u;
  }
  i = base + rm_decay_left_out_index(ray, sample_is_start, span.box_lo, region_voxels);
  return rm_float_add_atomic(traversal + i,
                             rm_decay_left_out_metres(s, span.flags, sample_is_start, ray_metres))
             ? 0u
             : 1u;
}

/* Adds the metres of the ray inside the walk's current voxel, layer index i. Returns the adds
 * given up (0 or 1). */
RM_DEVICE_FN rm_u32 rm_traversal_add_voxel(RM_ATOMIC_GLOBAL rm_u32* traversal, rm_u32 i,
                                           const rm_span_walk* s, float ray_metres) {
  return rm_float_add_atomic(traversal + i, rm_decay_voxel_metres(&s->walk, ray_metres)) ? 0u : 1u;
}

/* Everything span `span` adds to the traversal layer: the left-out voxel's part when the span
 * holds it, and each of its `count` voxels' metres. Walks its own copy of `s` (as
 * rm_span_walk_init left it), so the caller's miss loop stays as it is for maps without the layer
 * (one uniform branch a span, none a voxel). Returns the adds given up. */
RM_DEVICE_FN rm_u32 rm_traversal_add_span(RM_ATOMIC_GLOBAL rm_u32* traversal, rm_u32 base,
                                          rm_span_walk s, rm_i32 count, const rm_line_walk_ray* ray,
                                          rm_span_record span, int sample_is_start,
                                          rm_i32 region_voxels, float resolution) {
  float ray_metres = rm_decay_ray_metres(ray, resolution);
  rm_u32 dropped = rm_traversal_add_left_out(traversal, base, &s, ray, span, sample_is_start,
                                             region_voxels, ray_metres);
  rm_u32 i = base + RM_U32(s.index);
  rm_i32 k;
  if (count == 0) {
    return dropped;
  }
  /* Each voxel once the walk has stepped past it (rm_decay_stepped_voxel_metres), the span's
   * last one from its own exit: the CPU's addSpanPath, float for float. */
  for (k = 1; k < count; ++k) {
    float t_left_enter = rm_line_walk_t_enter(&s.walk);
    rm_u32 next = base + rm_span_walk_advance(&s);
    dropped += rm_float_add_atomic(traversal + i,
                                   rm_decay_stepped_voxel_metres(t_left_enter, &s.walk, ray_metres))
                   ? 0u
                   : 1u;
    i = next;
  }
  dropped += rm_traversal_add_voxel(traversal, i, &s, ray_metres);
  return dropped;
}

#endif /* RAYMAP_KERNELS_DEVICE_TRAVERSAL_H */
