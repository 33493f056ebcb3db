/* SPDX-License-Identifier: BSD-3-Clause */
/* The coarse walk of a prepared ray over the regions it crosses, in walk order, written once for
 * the CPU, CUDA and OpenCL: the CPU backends and the host batch planner call it through
 * RayRegionWalk (src/map/ray_region_walk.hpp), the device planner's kernels
 * (kernels/device/plan.h) call it directly, so every planner cuts a ray into the same spans, float
 * for float.
 *
 * It is the line walk of line_walk.h in region units: a region is N voxels, so region faces are
 * voxel faces, and the walk's integer end (the end voxel's region) makes it terminate for every
 * ray. Each step yields one span: the region, the ray parameter range [t0, t1] inside it (walk
 * frame, see ray.h), the region's voxel box relative to the walk's start voxel, and whether the
 * span holds the walk's first and/or last voxel. A ray never enters a region twice (the walk is
 * monotone on every axis). */
#ifndef RAYMAP_KERNELS_COMMON_REGION_WALK_H
#define RAYMAP_KERNELS_COMMON_REGION_WALK_H

#include "key_math.h"
#include "line_walk.h"
#include "portable.h"
#include "ray.h"
#include "span_walk.h"

/* One region's piece of a ray. */
typedef struct rm_region_span {
  rm_vec3i region; /* global region coordinate */
  rm_vec3i box_lo; /* the region's minimum voxel relative to the walk's start voxel */
  float t0;        /* ray parameter where the ray enters the region (0 at the walk start) */
  float t1;        /* ray parameter where it leaves */
  rm_u32 flags;    /* RM_SPAN_FIRST | RM_SPAN_LAST (span_walk.h) */
} rm_region_span;

/* Walk state. Value type, one per ray; no allocation, bounded by the regions crossed. */
typedef struct rm_region_walk {
  rm_ray_walk_frame frame;
  rm_i32 n; /* voxels per region edge */
  rm_vec3i start_region;
  rm_vec3i start_local; /* the walk's start voxel inside start_region */
  rm_vec3i end_region;
  rm_line_walk walk; /* over regions, relative to start_region */
  int started;
  int done;
} rm_region_walk;

/* A region's first voxel relative to a walk's start voxel (global key). */
RAYMAP_FN rm_vec3i rm_region_box_lo(rm_vec3i region, rm_vec3i walk_start_voxel, rm_i32 n) {
  return rm_vec3i_make(region.x * n - walk_start_voxel.x, region.y * n - walk_start_voxel.y,
                       region.z * n - walk_start_voxel.z);
}

/* Starts the walk of `ray` over regions of n voxels per edge: every member of *w is set. */
RAYMAP_FN void rm_region_walk_init(rm_region_walk* w, rm_prepared_ray ray, rm_i32 n) {
  rm_vec3i end_global;
  float inv_n;
  rm_vec3f region_start;
  rm_vec3f region_end;
  w->frame = rm_ray_walk_frame_make(ray);
  w->n = n;
  w->start_region = rm_region_of_voxel(w->frame.start_voxel, n);
  w->start_local = rm_local_in_region(w->frame.start_voxel, w->start_region, n);
  end_global = rm_vec3i_make(w->frame.start_voxel.x + w->frame.end_voxel.x,
                             w->frame.start_voxel.y + w->frame.end_voxel.y,
                             w->frame.start_voxel.z + w->frame.end_voxel.z);
  w->end_region = rm_region_of_voxel(end_global, n);
  inv_n = 1.0f / RM_F32(n);
  region_start = rm_vec3f_make((RM_F32(w->start_local.x) + w->frame.start.x) * inv_n,
                               (RM_F32(w->start_local.y) + w->frame.start.y) * inv_n,
                               (RM_F32(w->start_local.z) + w->frame.start.z) * inv_n);
  region_end = rm_vec3f_make((RM_F32(w->start_local.x) + w->frame.end.x) * inv_n,
                             (RM_F32(w->start_local.y) + w->frame.end.y) * inv_n,
                             (RM_F32(w->start_local.z) + w->frame.end.z) * inv_n);
  rm_line_walk_init(
      &w->walk, region_start, region_end,
      rm_vec3i_make(w->end_region.x - w->start_region.x, w->end_region.y - w->start_region.y,
                    w->end_region.z - w->start_region.z));
  w->started = 0;
  w->done = 0;
}

/* rm_region_walk_init as a value (host C++ initialises members with it). */
RAYMAP_FN rm_region_walk rm_region_walk_make(rm_prepared_ray ray, rm_i32 n) {
  rm_region_walk w;
  rm_region_walk_init(&w, ray, n);
  return w;
}

/* Regions the walk visits, in the window or not: one per step of the region walk, and the
 * first. */
RAYMAP_FN rm_u32 rm_region_walk_regions(const rm_region_walk* w) {
  return RM_U32(rm_abs_i32(w->end_region.x - w->start_region.x) +
                rm_abs_i32(w->end_region.y - w->start_region.y) +
                rm_abs_i32(w->end_region.z - w->start_region.z)) +
         1u;
}

/* Writes the next span into *span; returns 0 when every region has been visited. */
RAYMAP_FN int rm_region_walk_next(rm_region_walk* w, rm_region_span* span) {
  if (w->done) {
    return 0;
  }
  if (w->started && rm_line_walk_next(&w->walk) < 0) {
    w->done = 1;
    return 0;
  }
  span->flags = (w->started ? 0u : RM_SPAN_FIRST) | (w->walk.steps_left == 0 ? RM_SPAN_LAST : 0u);
  w->started = 1;
  span->region = rm_vec3i_make(w->start_region.x + w->walk.x, w->start_region.y + w->walk.y,
                               w->start_region.z + w->walk.z);
  span->t0 = rm_line_walk_t_enter(&w->walk);
  span->t1 = rm_line_walk_t_exit(&w->walk);
  span->box_lo = rm_region_box_lo(span->region, w->frame.start_voxel, w->n);
  return 1;
}

/* The span flag of the span that holds the ray's sample voxel: the walk's last voxel, or its
 * first for a reverse walk (ray.h). */
RAYMAP_FN rm_u32 rm_region_walk_sample_flag(const rm_region_walk* w) {
  return w->frame.sample_is_start ? RM_SPAN_FIRST : RM_SPAN_LAST;
}

/* Region and in-region index of the ray's sample voxel (the walk's end voxel, or its start voxel
 * for a reverse walk), without a division. */
RAYMAP_FN rm_u32 rm_region_walk_sample_cell(const rm_region_walk* w, rm_vec3i* region) {
  rm_vec3i cell;
  if (w->frame.sample_is_start) {
    *region = w->start_region;
    return rm_local_index(w->start_local, w->n);
  }
  cell = rm_vec3i_make(
      w->start_local.x + w->frame.end_voxel.x - (w->end_region.x - w->start_region.x) * w->n,
      w->start_local.y + w->frame.end_voxel.y - (w->end_region.y - w->start_region.y) * w->n,
      w->start_local.z + w->frame.end_voxel.z - (w->end_region.z - w->start_region.z) * w->n);
  *region = w->end_region;
  return rm_local_index(cell, w->n);
}

#endif /* RAYMAP_KERNELS_COMMON_REGION_WALK_H */
