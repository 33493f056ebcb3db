/* SPDX-License-Identifier: BSD-3-Clause */
/* Voxel mean: the running mean position of the samples that fell in a voxel, packed into 32 bits,
 * plus a sample count. Shared by the CPU reference, OpenCL and CUDA.
 *
 * Frame and units: the mean is stored relative to the voxel's minimum corner in voxel units, so a
 * component u in [0,1] is u * resolution metres from the corner (independent of the resolution and
 * exact in float far from the origin). Each component is quantised to 10 bits, u = i / 1023
 * (about resolution / 1023, 0.1 mm at 0.1 m); bits 30 and 31 are unused. The packed word alone is
 * updated with a 32-bit compare-and-swap on devices; the count is a separate word. Because the
 * mean is re-quantised on every update it stops moving once (sample - mean) / (count + 1) is below
 * half a quantum: with sample noise of 5 % of a voxel it settles within a few quanta (< 0.5 mm at
 * 0.1 m) of the true mean, far below what the map can resolve.
 *
 * Unlike OHM's decoder (which tests its "set" constant instead of the pattern, so an unset mean
 * decodes to the voxel corner), the decoder here takes the count and returns the voxel centre for a
 * voxel without samples. */
#ifndef RAYMAP_KERNELS_COMMON_VOXEL_MEAN_H
#define RAYMAP_KERNELS_COMMON_VOXEL_MEAN_H

#include "portable.h"

#define RM_MEAN_BITS 10
#define RM_MEAN_LEVELS 1023u
#define RM_MEAN_MASK 0x3FFu

/* One voxel of the mean layer (8 bytes). */
typedef struct rm_voxel_mean {
  rm_u32 packed; /* x: bits 0-9, y: bits 10-19, z: bits 20-29 */
  rm_u32 count;  /* samples folded in; saturates at 2^32 - 1 */
} rm_voxel_mean;

RAYMAP_FN rm_u32 rm_mean_quantise(float u) {
  float scaled = RM_FLOORF(u * RM_F32(RM_MEAN_LEVELS) + 0.5f);
  scaled = RM_FMINF(RM_FMAXF(scaled, 0.0f), RM_F32(RM_MEAN_LEVELS));
  return RM_U32(scaled);
}

/* Packs a voxel-local position (voxel units, clamped to [0,1]). */
RAYMAP_FN rm_u32 rm_mean_encode(rm_vec3f cell) {
  return rm_mean_quantise(cell.x) | (rm_mean_quantise(cell.y) << 10) |
         (rm_mean_quantise(cell.z) << 20);
}

/* Unpacks a mean; a voxel with count 0 has no samples and decodes to its centre. */
RAYMAP_FN rm_vec3f rm_mean_decode(rm_u32 packed, rm_u32 count) {
  const float scale = 1.0f / RM_F32(RM_MEAN_LEVELS);
  if (count == 0u) {
    return rm_vec3f_make(0.5f, 0.5f, 0.5f);
  }
  return rm_vec3f_make(RM_F32(packed & RM_MEAN_MASK) * scale,
                       RM_F32((packed >> 10) & RM_MEAN_MASK) * scale,
                       RM_F32((packed >> 20) & RM_MEAN_MASK) * scale);
}

/* Folds one sample (voxel-local position) into a mean that already holds count_before samples:
 * mean' = mean + (sample - mean) / (count_before + 1). Returns the new packed word. */
RAYMAP_FN rm_u32 rm_mean_fold(rm_u32 packed, rm_u32 count_before, rm_vec3f sample) {
  rm_vec3f mean = rm_mean_decode(packed, count_before);
  /* 1/(n+1) in float: exact for n < 2^24, and the mean barely moves beyond that. */
  float weight = 1.0f / (RM_F32(count_before) + 1.0f);
  mean.x += (sample.x - mean.x) * weight;
  mean.y += (sample.y - mean.y) * weight;
  mean.z += (sample.z - mean.z) * weight;
  return rm_mean_encode(mean);
}

RAYMAP_FN rm_u32 rm_mean_count_increment(rm_u32 count) {
  return count == 0xFFFFFFFFu ? count : count + 1u;
}

#endif /* RAYMAP_KERNELS_COMMON_VOXEL_MEAN_H */
