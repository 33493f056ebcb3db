/* SPDX-License-Identifier: BSD-3-Clause */
/* Occupancy update rules (log-odds), shared by the CPU reference, OpenCL and CUDA.
 *
 * A voxel's occupancy is a float log-odds value l = ln(p / (1 - p)). RM_OCC_UNOBSERVED (+inf) marks
 * a voxel no ray has touched; the first update starts from l = 0 (p = 0.5), as OctoMap does. Values
 * are clamped to [clamp_min, clamp_max] so that a voxel can change state again after many
 * consistent observations. A voxel is occupied when observed and l >= threshold, free when
 * l < threshold. */
#ifndef RAYMAP_KERNELS_COMMON_OCCUPANCY_H
#define RAYMAP_KERNELS_COMMON_OCCUPANCY_H

#include "portable.h"

#define RM_OCC_UNOBSERVED RM_INF

/* Log-odds parameters of an occupancy layer (all in log-odds, not probabilities). */
typedef struct rm_occupancy_params {
  float hit;       /* added on a hit, > 0 */
  float miss;      /* added on a miss, < 0 */
  float clamp_min; /* lower clamp */
  float clamp_max; /* upper clamp */
  float threshold; /* occupied when value >= threshold */
} rm_occupancy_params;

RAYMAP_FN int rm_occupancy_observed(float value) { return value != RM_OCC_UNOBSERVED; }

RAYMAP_FN int rm_occupancy_occupied(float value, float threshold) {
  return rm_occupancy_observed(value) && value >= threshold;
}

RAYMAP_FN int rm_occupancy_free(float value, float threshold) { return value < threshold; }

/* Adds `delta` (log-odds) to a voxel value and clamps the result. */
RAYMAP_FN float rm_occupancy_add(float value, float delta, float clamp_min, float clamp_max) {
  float base = rm_occupancy_observed(value) ? value : 0.0f;
  return RM_FMINF(RM_FMAXF(base + delta, clamp_min), clamp_max);
}

RAYMAP_FN float rm_occupancy_hit(float value, rm_occupancy_params p) {
  return rm_occupancy_add(value, p.hit, p.clamp_min, p.clamp_max);
}

RAYMAP_FN float rm_occupancy_miss(float value, rm_occupancy_params p) {
  return rm_occupancy_add(value, p.miss, p.clamp_min, p.clamp_max);
}

#endif /* RAYMAP_KERNELS_COMMON_OCCUPANCY_H */
