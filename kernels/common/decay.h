/* SPDX-License-Identifier: BSD-3-Clause */
/* Decay rate (Schaefer et al. 2017, OHM's "traversal" / "density" layer): how often rays that
 * pass through a voxel are reflected there, per metre of ray path inside it. Written once for the
 * CPU, OpenCL and CUDA.
 *
 * Layer: one float per voxel, the total length in metres of every ray path inside the voxel
 * (clear value 0). The sample count comes from the voxel-mean layer. The rate is
 *     lambda = samples / traversal   (reflections per metre).
 * A voxel no ray entered has neither: its rate is unknown (NaN). A voxel crossed but never hit
 * has rate 0. A voxel with samples and no length (every sample exactly on the face where its ray
 * entered) has rate +inf, as in OHM.
 *
 * Path lengths are exact to the walk: each voxel the line walk visits adds
 * (t_exit - t_enter) * ray length, with the entry and exit parameters of rm_line_walk, so the
 * lengths of a ray's voxels add up to the ray's length. The voxel the span walk leaves out (the
 * sample voxel, or the end voxel of a ray without a return, clipped at max range or cut into
 * pieces) still adds the part of the ray inside it: from where the ray enters it to the sample,
 * or to the clip point. Unlike the occupancy rules, which leave a partly seen end voxel alone,
 * that part is known path, and leaving it out would bias the rate of every sample voxel (its
 * hits would count, the metres before them would not).
 *
 * Precision: float sums. An increment stops registering once a voxel's total exceeds 2^24 times
 * it (about 1.7e6 m for 0.1 m crossings); well before that, rounding is below 1e-6 of the total
 * per add and unbiased. Device backends add with atomics in any order, so their totals differ
 * from the CPU's by rounding only. */
#ifndef RAYMAP_KERNELS_COMMON_DECAY_H
#define RAYMAP_KERNELS_COMMON_DECAY_H

#include "line_walk.h"
#include "portable.h"
#include "span_walk.h"

/* Length of a walked ray in metres: |extent| (voxel units) times the voxel edge (metres). */
RAYMAP_FN float rm_decay_ray_metres(const rm_line_walk_ray* ray, float resolution) {
  rm_vec3f e = ray->extent;
  return RM_SQRTF(e.x * e.x + e.y * e.y + e.z * e.z) * resolution;
}

/* Metres of the ray inside the walk's current voxel. Never negative: rm_line_walk_t_exit is
 * never below rm_line_walk_t_enter. */
RAYMAP_FN float rm_decay_voxel_metres(const rm_line_walk* w, float ray_metres) {
  return (rm_line_walk_t_exit(w) - rm_line_walk_t_enter(w)) * ray_metres;
}

/* Metres of the ray inside the voxel the walk has just stepped out of, entered at `t_left_enter`
 * (its rm_line_walk_t_enter): from there to where the walk entered the current voxel. The same
 * float as rm_decay_voxel_metres for that voxel before the step (the step enters the next voxel
 * at the least of the three crossings, which is where the voxel is left; both clamp to the span
 * end and to zero), but from values the walk keeps anyway: a loop that adds each voxel once it
 * has stepped past it does no min of three crossings and no branch per voxel, and ran 1.10 times
 * as fast as one that adds before the step (one thread, decay rates only, Ouster scans). */
RAYMAP_FN float rm_decay_stepped_voxel_metres(float t_left_enter, const rm_line_walk* w,
                                              float ray_metres) {
  return RM_FMAXF(rm_line_walk_t_enter(w) - t_left_enter, 0.0f) * ray_metres;
}

/* Ray parameter at which a forward walk enters its last voxel, from the state right after
 * rm_line_walk_init_span (no step taken yet): the last crossing on each axis that has steps is
 * first + (steps - 1) * inv, the expression rm_line_walk_step evaluates for it, and the walk
 * takes crossings in increasing order, so the last voxel is entered at the latest of them. */
RAYMAP_FN float rm_decay_last_voxel_t_enter(const rm_line_walk* w) {
  float t = w->t_enter;
  if (w->left_x > 0) {
    t = RM_FMAXF(t, rm_line_walk_next_crossing(1, w->first_x, RM_F32(w->left_x - 1), w->inv_x));
  }
  if (w->left_y > 0) {
    t = RM_FMAXF(t, rm_line_walk_next_crossing(1, w->first_y, RM_F32(w->left_y - 1), w->inv_y));
  }
  if (w->left_z > 0) {
    t = RM_FMAXF(t, rm_line_walk_next_crossing(1, w->first_z, RM_F32(w->left_z - 1), w->inv_z));
  }
  return RM_FMINF(t, w->t_end);
}

/* Metres of the ray inside the voxel rm_span_walk_init left out (the sample voxel, or the end
 * voxel of a ray without a return), for the span that holds it: `s` as rm_span_walk_init left it
 * (before any rm_span_walk_advance of the caller). Forward walks (sample_is_start 0) end on that
 * voxel: it runs from its entry to t = t_end. Reverse walks start on it: from t = 0 to where the
 * walk left it (init has already stepped past it), or to t_end when it is the span's only voxel.
 * Returns 0 for a span that does not hold the left-out voxel (span_flags without RM_SPAN_LAST
 * for a forward walk, without RM_SPAN_FIRST for a reverse one). */
RAYMAP_FN float rm_decay_left_out_metres(const rm_span_walk* s, rm_u32 span_flags,
                                         int sample_is_start, float ray_metres) {
  const rm_line_walk* w = &s->walk;
  if (sample_is_start) {
    int moved = w->x != 0 || w->y != 0 || w->z != 0;
    if ((span_flags & RM_SPAN_FIRST) == 0u) {
      return 0.0f;
    }
    return (moved ? rm_line_walk_t_enter(w) : w->t_end) * ray_metres;
  }
  if ((span_flags & RM_SPAN_LAST) == 0u) {
    return 0.0f;
  }
  return (w->t_end - rm_decay_last_voxel_t_enter(w)) * ray_metres;
}

/* Index, inside the span's region, of the voxel rm_span_walk_init left out: the walk's end voxel
 * (forward) or its start voxel (0,0,0) (reverse), relative to the region's minimum voxel box_lo.
 * Meaningful only when rm_decay_left_out_metres says the span holds it. */
RAYMAP_FN rm_u32 rm_decay_left_out_index(const rm_line_walk_ray* ray, int sample_is_start,
                                         rm_vec3i box_lo, rm_i32 n) {
  rm_vec3i v = sample_is_start ? rm_vec3i_make(0, 0, 0) : ray->end_voxel;
  return RM_U32((v.x - box_lo.x) + n * ((v.y - box_lo.y) + n * (v.z - box_lo.z)));
}

/* Reflections per metre from a voxel's sample count and traversal (metres): NaN when no ray
 * entered it, +inf for samples without length, else samples / traversal. */
RAYMAP_FN float rm_decay_rate(rm_u32 samples, float traversal) {
  if (traversal > 0.0f) {
    return RM_F32(samples) / traversal;
  }
  return samples > 0u ? RM_INF : RM_NAN;
}

#endif /* RAYMAP_KERNELS_COMMON_DECAY_H */
