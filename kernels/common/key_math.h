/* SPDX-License-Identifier: BSD-3-Clause */
/* Voxel key maths shared by every backend: global voxel coordinates, their region and the linear
 * index of a voxel inside its region.
 *
 * Frames and units. A global voxel coordinate v (integer, per axis) covers world positions
 * [v * resolution, (v + 1) * resolution) metres, so voxel faces lie on multiples of the resolution,
 * as in OctoMap. A region holds N^3 voxels (N = region_voxels); region r covers global voxels
 * [r * N, r * N + N - 1] on each axis. Inside a region voxels are stored x fastest:
 * index = x + N * (y + N * z). */
#ifndef RAYMAP_KERNELS_COMMON_KEY_MATH_H
#define RAYMAP_KERNELS_COMMON_KEY_MATH_H

#include "portable.h"

/* Floor division for a positive divisor: rm_floor_div(-1, 32) == -1 (C division truncates). */
RAYMAP_FN rm_i32 rm_floor_div(rm_i32 value, rm_i32 divisor) {
  rm_i32 q = value / divisor;
  return (q * divisor > value) ? q - 1 : q;
}

/* Region coordinate of a global voxel coordinate (per axis). */
RAYMAP_FN rm_vec3i rm_region_of_voxel(rm_vec3i voxel, rm_i32 region_voxels) {
  return rm_vec3i_make(rm_floor_div(voxel.x, region_voxels), rm_floor_div(voxel.y, region_voxels),
                       rm_floor_div(voxel.z, region_voxels));
}

/* Coordinate of a voxel inside a region that holds it (no division). */
RAYMAP_FN rm_vec3i rm_local_in_region(rm_vec3i voxel, rm_vec3i region, rm_i32 region_voxels) {
  return rm_vec3i_make(voxel.x - region.x * region_voxels, voxel.y - region.y * region_voxels,
                       voxel.z - region.z * region_voxels);
}

/* Voxel coordinate inside its region, each component in [0, region_voxels). */
RAYMAP_FN rm_vec3i rm_local_of_voxel(rm_vec3i voxel, rm_i32 region_voxels) {
  return rm_local_in_region(voxel, rm_region_of_voxel(voxel, region_voxels), region_voxels);
}

/* Linear index of a region-local voxel coordinate (x fastest). */
RAYMAP_FN rm_u32 rm_local_index(rm_vec3i cell, rm_i32 region_voxels) {
  return RM_U32(cell.x + region_voxels * (cell.y + region_voxels * cell.z));
}

/* Inverse of rm_local_index: the region-local coordinate of a linear index. */
RAYMAP_FN rm_vec3i rm_local_of_index(rm_u32 index, rm_i32 region_voxels) {
  rm_i32 i = RM_I32(index);
  return rm_vec3i_make(i % region_voxels, (i / region_voxels) % region_voxels,
                       i / (region_voxels * region_voxels));
}

#endif /* RAYMAP_KERNELS_COMMON_KEY_MATH_H */
