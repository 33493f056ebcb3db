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

/* A hit adds p.hit and clamps from above, a miss adds p.miss and clamps from below: values stay in
 * [clamp_min, clamp_max] from the first update on, so the other bound cannot be crossed. */
RAYMAP_FN float rm_occupancy_hit(float value, rm_occupancy_params p) {
  float base = rm_occupancy_observed(value) ? value : 0.0f;
  return RM_FMINF(base + p.hit, p.clamp_max);
}

RAYMAP_FN float rm_occupancy_miss(float value, rm_occupancy_params p) {
  float base = rm_occupancy_observed(value) ? value : 0.0f;
  return RM_FMAXF(base + p.miss, p.clamp_min);
}

#endif /* RAYMAP_KERNELS_COMMON_OCCUPANCY_H */
