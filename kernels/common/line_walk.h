/* SPDX-License-Identifier: BSD-3-Clause */
/* Exact voxel traversal of a line segment (Amanatides & Woo), written once for the CPU, CUDA and
 * OpenCL.
 *
 * Frame and units. Positions are in voxel units (metres / resolution) relative to the minimum
 * corner of the walk's start voxel, so the start point lies in [0,1]^3 and voxel faces are at
 * integers. Keeping coordinates local lets the walk run in float for maps thousands of metres
 * across: only the host computes global keys (in double).
 *
 * Termination and endpoints come from integers, not from float comparisons. The caller supplies
 * the integer offset of the end voxel (computed on the host from exact keys); the walk takes
 * exactly |dx| + |dy| + |dz| steps, each to a face-adjacent voxel, and an axis whose steps are used
 * up is never stepped again. Floats only choose the ORDER of the steps. So the walk ends on the end
 * voxel and terminates for every input: rays starting or ending on faces, edges or corners,
 * axis-aligned rays, zero-length rays (no step), rays whose float direction rounds to zero on an
 * axis (that axis is stepped first, at t = 0), and rays of any length (the next crossing on an axis
 * is recomputed as first + steps * inverse-extent each time, never accumulated, so rounding does
 * not grow along a 1 km ray).
 *
 * The ray parameter t runs from 0 at the start point to 1 at the end point. A walk may cover only
 * a span [t0, t1] of the ray clamped to a box of voxels (one region of the map): that is how the
 * integrators split a ray into per-region pieces. */
#ifndef RAYMAP_KERNELS_COMMON_LINE_WALK_H
#define RAYMAP_KERNELS_COMMON_LINE_WALK_H

#include "portable.h"

/* Direction extents below this (voxel units) are treated as zero: the axis can still be stepped
 * if the integer keys demand it, but at t = t0. */
#define RM_WALK_MIN_EXTENT 1.0e-30f

/* Walk state. Value type; one per ray (segment) in flight. */
typedef struct rm_line_walk {
  rm_i32 x; /* current voxel, relative to the start voxel of the whole ray */
  rm_i32 y;
  rm_i32 z;
  rm_i32 step_x; /* -1, 0 or +1 */
  rm_i32 step_y;
  rm_i32 step_z;
  rm_i32 left_x; /* steps still to take on each axis */
  rm_i32 left_y;
  rm_i32 left_z;
  rm_i32 steps_left; /* left_x + left_y + left_z */
  float next_x;      /* t of the next face crossing; RM_INF once the axis is used up */
  float next_y;
  float next_z;
  float first_x; /* t of the first face crossing on each axis */
  float first_y;
  float first_z;
  float taken_x; /* steps taken on each axis, as float (exact below 2^24) */
  float taken_y;
  float taken_z;
  float inv_x; /* 1 / |extent| on each axis, 0 for a degenerate extent */
  float inv_y;
  float inv_z;
  float t_enter; /* t at which the walk entered the current voxel (read rm_line_walk_t_enter) */
  float t_end;   /* t at which the walk ends (t1) */
} rm_line_walk;

/* The per-ray constants of a walk, computed once and shared by every span of the ray. */
typedef struct rm_line_walk_ray {
  rm_vec3f start;     /* start point, voxel units relative to the start voxel's minimum corner */
  rm_vec3f extent;    /* end - start */
  rm_vec3f inv;       /* 1 / |extent| per axis, 0 for a degenerate extent */
  rm_vec3i end_voxel; /* exact offset of the end voxel from the start voxel */
} rm_line_walk_ray;

RAYMAP_FN float rm_line_walk_inverse_extent(float extent) {
  float abs_extent = RM_FABSF(extent);
  return (abs_extent > RM_WALK_MIN_EXTENT) ? 1.0f / abs_extent : 0.0f;
}

/* Precondition: every component of end_voxel is below 2^24 in magnitude (the host rejects longer
 * rays), so step counts stay exact in float. */
RAYMAP_FN rm_line_walk_ray rm_line_walk_ray_make(rm_vec3f start, rm_vec3f end, rm_vec3i end_voxel) {
  rm_line_walk_ray r;
  r.start = start;
  r.extent = rm_vec3f_make(end.x - start.x, end.y - start.y, end.z - start.z);
  r.inv = rm_vec3f_make(rm_line_walk_inverse_extent(r.extent.x),
                        rm_line_walk_inverse_extent(r.extent.y),
                        rm_line_walk_inverse_extent(r.extent.z));
  r.end_voxel = end_voxel;
  return r;
}

/* Sets up one axis. p0: start point of the span on this axis; inv: 1 / |extent| of the whole ray;
 * k0, k1: first and last voxel of the span on this axis; t0: ray parameter of p0. */
RAYMAP_FN void rm_line_walk_axis_init(float p0, float inv, rm_i32 k0, rm_i32 k1, float t0,
                                      rm_i32* step, rm_i32* left, float* first, float* next) {
  rm_i32 delta = k1 - k0;
  float inside = p0 - RM_F32(k0); /* position inside the first voxel, nominally in [0,1] */
  float to_face;
  *step = rm_sign_i32(delta);
  *left = rm_abs_i32(delta);
  to_face = (*step > 0) ? (1.0f - inside) : inside;
  to_face = RM_FMAXF(to_face, 0.0f);
  *first = t0 + to_face * inv;
  *next = (*left > 0) ? *first : RM_INF;
}

/* First or last voxel of a span on one axis: the exact key at the ray's ends, otherwise the voxel
 * holding the point, clamped into the box (a point on a box face belongs to the box). */
RAYMAP_FN rm_i32 rm_line_walk_span_key(float p, rm_i32 exact_key, int use_exact, rm_i32 lo,
                                       rm_i32 hi) {
  return use_exact ? exact_key : rm_clamp_i32(rm_floor_i32(p), lo, hi);
}

/* Starts a walk over the span [t0, t1] (0 <= t0 <= t1 <= 1) of a ray, restricted to the voxel box
 * [box_lo, box_hi] (inclusive, relative to the start voxel). The first span of a ray (holds_start)
 * starts on the start voxel (0,0,0) and the last (holds_end) ends on the end voxel, exactly; the
 * caller makes sure those lie in the box. Other ends are the voxel holding the point at t0 or t1,
 * clamped into the box: a ray may touch several regions at the same t (a start point on a region
 * face, a crossing through a region edge), so t alone cannot say which span holds an end. After
 * init, (x, y, z) is the first voxel. */
RAYMAP_FN void rm_line_walk_init_span(rm_line_walk* w, const rm_line_walk_ray* ray, float t0,
                                      float t1, rm_vec3i box_lo, rm_vec3i box_hi, int holds_start,
                                      int holds_end) {
  rm_vec3f p0 = ray->start;
  rm_vec3f p1 = rm_vec3f_make(ray->start.x + t1 * ray->extent.x, ray->start.y + t1 * ray->extent.y,
                              ray->start.z + t1 * ray->extent.z);
  rm_vec3i k0;
  rm_vec3i k1;
  if (holds_start) {
    t0 = 0.0f;
  } else {
    p0 = rm_vec3f_make(ray->start.x + t0 * ray->extent.x, ray->start.y + t0 * ray->extent.y,
                       ray->start.z + t0 * ray->extent.z);
  }
  k0.x = rm_line_walk_span_key(p0.x, 0, holds_start, box_lo.x, box_hi.x);
  k0.y = rm_line_walk_span_key(p0.y, 0, holds_start, box_lo.y, box_hi.y);
  k0.z = rm_line_walk_span_key(p0.z, 0, holds_start, box_lo.z, box_hi.z);
  k1.x = rm_line_walk_span_key(p1.x, ray->end_voxel.x, holds_end, box_lo.x, box_hi.x);
  k1.y = rm_line_walk_span_key(p1.y, ray->end_voxel.y, holds_end, box_lo.y, box_hi.y);
  k1.z = rm_line_walk_span_key(p1.z, ray->end_voxel.z, holds_end, box_lo.z, box_hi.z);
  rm_line_walk_axis_init(p0.x, ray->inv.x, k0.x, k1.x, t0, &w->step_x, &w->left_x, &w->first_x,
                         &w->next_x);
  rm_line_walk_axis_init(p0.y, ray->inv.y, k0.y, k1.y, t0, &w->step_y, &w->left_y, &w->first_y,
                         &w->next_y);
  rm_line_walk_axis_init(p0.z, ray->inv.z, k0.z, k1.z, t0, &w->step_z, &w->left_z, &w->first_z,
                         &w->next_z);
  w->inv_x = ray->inv.x;
  w->inv_y = ray->inv.y;
  w->inv_z = ray->inv.z;
  w->x = k0.x;
  w->y = k0.y;
  w->z = k0.z;
  w->taken_x = 0.0f;
  w->taken_y = 0.0f;
  w->taken_z = 0.0f;
  w->steps_left = w->left_x + w->left_y + w->left_z;
  w->t_enter = t0;
  w->t_end = holds_end ? 1.0f : t1;
}

/* Starts a walk over the whole ray: from the start voxel (0,0,0) to end_voxel. */
RAYMAP_FN void rm_line_walk_init(rm_line_walk* w, rm_vec3f start, rm_vec3f end,
                                 rm_vec3i end_voxel) {
  rm_line_walk_ray ray = rm_line_walk_ray_make(start, end, end_voxel);
  rm_line_walk_init_span(w, &ray, 0.0f, 1.0f, end_voxel, end_voxel, 1, 1);
}

/* Next crossing time on an axis after `taken` steps there; RM_INF once its steps are used up.
 * No overflow: inv <= 1 / RM_WALK_MIN_EXTENT and taken < 2^24 (end voxel offsets below 2^24, a
 * precondition of init), so first + taken * inv stays far below FLT_MAX and an axis with steps
 * left always compares below an exhausted one. */
RAYMAP_FN float rm_line_walk_next_crossing(rm_i32 left, float first, float taken, float inv) {
  return (left > 0) ? first + taken * inv : RM_INF;
}

/* Advances to the next voxel and returns the axis stepped (0 = x, 1 = y, 2 = z).
 * Precondition: w->steps_left > 0. Ties step the lowest axis first, so a ray through a voxel edge
 * or corner visits one of the voxels that touch it there. The crossing times chosen never
 * decrease: each axis's crossings grow and the smallest is taken. */
RAYMAP_FN rm_i32 rm_line_walk_step(rm_line_walk* w) {
  float nx = w->next_x;
  float ny = w->next_y;
  float nz = w->next_z;
  w->steps_left -= 1;
  if (nx <= ny && nx <= nz) {
    w->t_enter = nx;
    w->x += w->step_x;
    w->left_x -= 1;
    w->taken_x += 1.0f;
    w->next_x = rm_line_walk_next_crossing(w->left_x, w->first_x, w->taken_x, w->inv_x);
    return 0;
  }
  if (ny <= nz) {
    w->t_enter = ny;
    w->y += w->step_y;
    w->left_y -= 1;
    w->taken_y += 1.0f;
    w->next_y = rm_line_walk_next_crossing(w->left_y, w->first_y, w->taken_y, w->inv_y);
    return 1;
  }
  w->t_enter = nz;
  w->z += w->step_z;
  w->left_z -= 1;
  w->taken_z += 1.0f;
  w->next_z = rm_line_walk_next_crossing(w->left_z, w->first_z, w->taken_z, w->inv_z);
  return 2;
}

/* Advances to the next voxel: the axis stepped, or -1 when the current voxel is the last one. */
RAYMAP_FN rm_i32 rm_line_walk_next(rm_line_walk* w) {
  return w->steps_left > 0 ? rm_line_walk_step(w) : -1;
}

/* Ray parameter at which the walk entered the current voxel. Crossings of an axis whose extent
 * rounds to zero happen at t0; rounding can put a last crossing past t1, hence the clamp. */
RAYMAP_FN float rm_line_walk_t_enter(const rm_line_walk* w) {
  return RM_FMINF(w->t_enter, w->t_end);
}

/* Ray parameter at which the walk leaves the current voxel (t1 for the last voxel). */
RAYMAP_FN float rm_line_walk_t_exit(const rm_line_walk* w) {
  float t;
  if (w->steps_left <= 0) {
    return w->t_end;
  }
  t = RM_FMINF(RM_FMINF(w->next_x, w->next_y), w->next_z);
  return RM_FMINF(RM_FMAXF(t, w->t_enter), w->t_end);
}

#endif /* RAYMAP_KERNELS_COMMON_LINE_WALK_H */
