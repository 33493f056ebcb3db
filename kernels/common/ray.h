/* SPDX-License-Identifier: BSD-3-Clause */
/* A prepared ray as every backend consumes it, and how its walk is set up.
 *
 * Rays are prepared on the host (validated, clipped, segmented; see src/map/ray_preparer.hpp) into
 * this fixed layout. Both ends are stored as an exact global voxel key (computed in double on the
 * host) plus the position inside that voxel in voxel units, so device code works in float without
 * losing precision far from the map origin. */
#ifndef RAYMAP_KERNELS_COMMON_RAY_H
#define RAYMAP_KERNELS_COMMON_RAY_H

#include "portable.h"

/* With RM_RAY_END_HIT the voxel holding the sample gets a hit; without it that voxel is left out.
 * A ray clipped at max range (or at a rolling window) or without a return is known free only up to
 * its end point, which lies inside its end voxel: like OctoMap, that partly seen voxel is not
 * updated. The inner pieces of a segmented ray leave out their end voxel too, because the next
 * piece starts in it. */
#define RM_RAY_END_HIT 1u /* a hit (occupied evidence) and a voxel-mean sample */
#define RM_RAY_REVERSE 4u /* walk from the sample back to the origin (spreads GPU contention) */
/* A place kept for a ray the device's preparation rejected (kernels/device/prepare.h): it crosses
 * no region, has no sample and is never walked. Host-prepared rays never carry it. */
#define RM_RAY_SKIP 8u

typedef struct rm_prepared_ray {
  rm_vec3i origin_voxel; /* global voxel holding the ray origin (sensor side) */
  rm_vec3f origin_local; /* origin inside origin_voxel, voxel units in [0,1] */
  rm_vec3i sample_voxel; /* global voxel holding the sample (or clip point) */
  rm_vec3f sample_local; /* sample inside sample_voxel, voxel units in [0,1] */
  rm_u32 flags;          /* RM_RAY_* */
  float intensity;       /* sensor intensity of the return, unitless as the sensor reports it */
  float tsdf_end_m;      /* TSDF maps: signed distance at the sample end, metres (tsdf.h) */
} rm_prepared_ray;

/* The endpoints of a ray's walk in the walk frame (see line_walk.h): the walk starts at the origin,
 * or at the sample for RM_RAY_REVERSE. */
typedef struct rm_ray_walk_frame {
  rm_vec3i start_voxel; /* global key of the walk's start voxel */
  rm_vec3f start;       /* start point, voxel units relative to start_voxel's minimum corner */
  rm_vec3f end;         /* end point, same frame */
  rm_vec3i end_voxel;   /* end voxel relative to start_voxel */
  int sample_is_start;  /* 1 when the walk starts on the sample voxel (reverse walk) */
} rm_ray_walk_frame;

RAYMAP_FN rm_ray_walk_frame rm_ray_walk_frame_make(rm_prepared_ray ray) {
  rm_ray_walk_frame f;
  rm_vec3i a_voxel = ray.origin_voxel;
  rm_vec3f a_local = ray.origin_local;
  rm_vec3i b_voxel = ray.sample_voxel;
  rm_vec3f b_local = ray.sample_local;
  f.sample_is_start = (ray.flags & RM_RAY_REVERSE) != 0u;
  if (f.sample_is_start) {
    a_voxel = ray.sample_voxel;
    a_local = ray.sample_local;
    b_voxel = ray.origin_voxel;
    b_local = ray.origin_local;
  }
  f.start_voxel = a_voxel;
  f.start = a_local;
  f.end_voxel = rm_vec3i_make(b_voxel.x - a_voxel.x, b_voxel.y - a_voxel.y, b_voxel.z - a_voxel.z);
  f.end = rm_vec3f_make(b_local.x + RM_F32(f.end_voxel.x), b_local.y + RM_F32(f.end_voxel.y),
                        b_local.z + RM_F32(f.end_voxel.z));
  return f;
}

#endif /* RAYMAP_KERNELS_COMMON_RAY_H */
