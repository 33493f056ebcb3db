/* SPDX-License-Identifier: BSD-3-Clause */
/* Walking the voxels of one span of a ray (its piece inside one region) as linear indices into
 * that region, leaving out the ray's sample voxel. Shared by the CPU integrators and the device
 * kernels, so that every backend visits exactly the same voxels for the same span.
 *
 * A span is what the coarse region walk (src/map/ray_region_walk.hpp) produces: the ray parameter
 * range [t0, t1] inside the region, the region's voxel box relative to the walk's start voxel, and
 * whether the span holds the walk's first and/or last voxel. The sample voxel (where the walk ends,
 * or starts for a reverse walk) is never visited here: each backend applies its hit rule to it
 * separately, and rays without a hit leave it out entirely (see ray.h). */
#ifndef RAYMAP_KERNELS_COMMON_SPAN_WALK_H
#define RAYMAP_KERNELS_COMMON_SPAN_WALK_H

#include "line_walk.h"
#include "portable.h"

#define RM_SPAN_FIRST 1u /* the span holds the walk's start voxel */
#define RM_SPAN_LAST 2u  /* the span holds the walk's end voxel */

/* Iterator state: the line walk plus the current voxel's index inside the region. */
typedef struct rm_span_walk {
  rm_line_walk walk;
  rm_i32 index;  /* x + n * (y + n * z) of the current voxel, region-local */
  rm_i32 step_x; /* index change of one step along each axis */
  rm_i32 step_y;
  rm_i32 step_z;
} rm_span_walk;

/* Index change of the step rm_line_walk_step just took (selects instead of an array, so GPU
 * compilers keep it in registers). */
RAYMAP_FN rm_i32 rm_span_walk_delta(const rm_span_walk* s, rm_i32 axis) {
  return axis == 0 ? s->step_x : (axis == 1 ? s->step_y : s->step_z);
}

/* The current voxel relative to the walk's start voxel. */
RAYMAP_FN rm_vec3i rm_span_walk_voxel(const rm_span_walk* s) {
  return rm_vec3i_make(s->walk.x, s->walk.y, s->walk.z);
}

/* Moves to the next voxel of the span and returns its index. Precondition: a voxel remains. */
RAYMAP_FN rm_u32 rm_span_walk_advance(rm_span_walk* s) {
  s->index += rm_span_walk_delta(s, rm_line_walk_step(&s->walk));
  return RM_U32(s->index);
}

/* Starts the walk of one span; returns how many voxels it visits (0 when the span holds only the
 * sample voxel). After a non-zero return, s->index is the first voxel to visit; each further one
 * comes from rm_span_walk_advance. box_lo: the region's minimum voxel relative to the walk's start
 * voxel; n: voxels per region edge; span_flags: RM_SPAN_*; sample_is_start: the walk starts on the
 * sample voxel (reverse walk). */
RAYMAP_FN rm_i32 rm_span_walk_init(rm_span_walk* s, const rm_line_walk_ray* ray, float t0, float t1,
                                   rm_vec3i box_lo, rm_i32 n, rm_u32 span_flags,
                                   int sample_is_start) {
  rm_vec3i box_hi = rm_vec3i_make(box_lo.x + n - 1, box_lo.y + n - 1, box_lo.z + n - 1);
  int first = (span_flags & RM_SPAN_FIRST) != 0u;
  int last = (span_flags & RM_SPAN_LAST) != 0u;
  rm_i32 steps;
  rm_line_walk_init_span(&s->walk, ray, t0, t1, box_lo, box_hi, first, last);
  s->index = (s->walk.x - box_lo.x) + n * ((s->walk.y - box_lo.y) + n * (s->walk.z - box_lo.z));
  s->step_x = s->walk.step_x;
  s->step_y = s->walk.step_y * n;
  s->step_z = s->walk.step_z * n * n;
  /* The span's voxels are its first voxel plus one per step; drop the sample voxel at whichever
   * end holds it. */
  steps = s->walk.steps_left;
  if (first && sample_is_start) {
    if (steps == 0) {
      return 0;
    }
    (void)rm_span_walk_advance(s);
    steps -= 1;
  }
  if (last && !sample_is_start) {
    if (steps == 0) {
      return 0;
    }
    steps -= 1;
  }
  return steps + 1;
}

#endif /* RAYMAP_KERNELS_COMMON_SPAN_WALK_H */
