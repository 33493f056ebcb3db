/* SPDX-License-Identifier: BSD-3-Clause */
/* Truncated signed distance field (TSDF, Voxblox-style projective distances): the update of one
 * voxel by one ray, written once for the CPU, OpenCL and CUDA.
 *
 * Layer: per voxel a float distance (metres, positive in front of the surface, on the sensor's
 * side) and a float weight (0: no ray has updated the voxel; clear value all zero bits).
 *
 * Distance. For a voxel whose centre c projects onto the ray from origin o towards the surface
 * point z, the signed distance is the distance along the ray from that projection to z:
 *     sdf = |z - o| - (c - o).(z - o) / |z - o|     (Voxblox's and OHM's definition)
 * so it is the projective distance, which equals the Euclidean distance to a surface only when
 * the ray meets it square on (it is larger at grazing angles; its zero, the surface, is exact).
 *
 * The walk. Unlike OHM, which walks only from the sensor to the sample, the host extends every
 * ray with a return by the truncation distance tau behind the sample (src/map/ray_preparer), so
 * the voxels just behind the surface get their negative distances too. A prepared ray carries
 * the signed distance at its walk end (tsdf_end_m): -tau for an extended ray, the distance still
 * to go for an inner piece of a segmented one, and RM_TSDF_FREE for rays clipped at max range or
 * without a return, which update free space only (+tau everywhere). The voxel the walk leaves out
 * (the end voxel, at -tau) is not updated, as no voxel more than tau behind the surface is.
 *
 * Weight and fusion. Each ray adds weight 1 (constant; Voxblox's default for lidar is 1/z^2 for
 * depth z, OHM's is 1); with a drop-off distance eps > 0, the weight behind the surface falls
 * linearly from 1 at sdf = -eps to 0 at sdf = -tau (Voxblox's drop-off). Then
 *     W' = W + w, D' = (D W + clamp(sdf, -tau, tau) w) / W', W' = min(W', max_weight).
 * Unlike Voxblox and OHM, each ray's distance is truncated before it is averaged (as in
 * KinectFusion): they fuse the raw distance and clamp the result, so one ray passing metres in
 * front of a voxel moves a well-observed surface voxel to +tau at once. */
#ifndef RAYMAP_KERNELS_COMMON_TSDF_H
#define RAYMAP_KERNELS_COMMON_TSDF_H

#include "line_walk.h"
#include "portable.h"

/* tsdf_end_m of a ray that updates free space only: far enough in front of any surface that every
 * voxel it crosses is truncated to +tau. */
#define RM_TSDF_FREE 1.0e30f

/* Fusion below this total weight leaves a voxel unchanged (all of its weight dropped off). */
#define RM_TSDF_MIN_WEIGHT 1.0e-5f

typedef struct rm_tsdf_voxel {
  float distance; /* metres, truncated to [-tau, tau]; positive in front of the surface */
  float weight;   /* sum of ray weights, at most max_weight; 0 = never updated */
} rm_tsdf_voxel;

typedef struct rm_tsdf_params {
  float truncation; /* tau, metres, > 0 */
  float max_weight; /* > 0 */
  float dropoff;    /* eps, metres, in [0, tau): 0 = constant weight behind the surface */
  float resolution; /* voxel edge, metres */
} rm_tsdf_params;

/* The per-ray constants of the distance: the walk's direction over its length, and where the
 * walk's surface end is. */
typedef struct rm_tsdf_ray {
  rm_vec3f start;      /* walk start point, voxel units relative to the start voxel's corner */
  rm_vec3f direction;  /* unit vector along the walk (start to end); 0 for a zero-length walk */
  float length;        /* |end - start|, voxel units */
  float end_sdf;       /* signed distance at the walk's sample end, metres (tsdf_end_m) */
  int sample_is_start; /* the walk starts at the sample end (reverse walk) */
} rm_tsdf_ray;

RAYMAP_FN rm_tsdf_ray rm_tsdf_ray_make(const rm_line_walk_ray* walk, int sample_is_start,
                                       float end_sdf) {
  rm_tsdf_ray r;
  rm_vec3f e = walk->extent;
  float length = RM_SQRTF(e.x * e.x + e.y * e.y + e.z * e.z);
  float inv = length > 0.0f ? 1.0f / length : 0.0f;
  r.start = walk->start;
  r.direction = rm_vec3f_make(e.x * inv, e.y * inv, e.z * inv);
  r.length = length;
  r.end_sdf = end_sdf;
  r.sample_is_start = sample_is_start;
  return r;
}

/* Signed distance (metres) of voxel `voxel` (relative to the walk's start voxel): the ray's
 * distance at the walk's sample end plus the distance along the ray from the voxel centre's
 * projection to that end. */
RAYMAP_FN float rm_tsdf_sdf(const rm_tsdf_ray* r, rm_vec3i voxel, float resolution) {
  float along = (RM_F32(voxel.x) + 0.5f - r->start.x) * r->direction.x +
                (RM_F32(voxel.y) + 0.5f - r->start.y) * r->direction.y +
                (RM_F32(voxel.z) + 0.5f - r->start.z) * r->direction.z;
  float to_end = r->sample_is_start ? along : r->length - along;
  return r->end_sdf + to_end * resolution;
}

/* Voxels whose centre may lie up to this far (voxel units) along the ray from any point of the
 * ray inside them: half the voxel's diagonal (0.87), rounded up for float rounding of the walk. */
#define RM_TSDF_FREE_MARGIN 1.0f

/* The walk parameter beyond which (forward walks: up to which) every voxel is free space: its
 * signed distance is at least tau whatever its centre's offset from the ray, so its update is
 * exactly the update at sdf = tau and its distance need not be computed. Compare the walk's entry
 * parameter of a voxel with rm_tsdf_is_free. */
RAYMAP_FN float rm_tsdf_free_bound(const rm_tsdf_ray* r, rm_tsdf_params p) {
  /* Distance along the ray (voxel units) a voxel centre must be from the sample end. */
  float need = (p.truncation - r->end_sdf) / p.resolution + RM_TSDF_FREE_MARGIN;
  if (!(r->length > 0.0f)) {
    return r->sample_is_start ? RM_INF : -RM_INF; /* nothing is known to be free */
  }
  return r->sample_is_start ? need / r->length : 1.0f - need / r->length;
}

/* True when the voxel the walk entered at parameter t_enter is free space (rm_tsdf_free_bound):
 * a forward walk ends at the sample end, so its free voxels come first; a reverse one starts
 * there, so they come last. */
RAYMAP_FN int rm_tsdf_is_free(float t_enter, float bound, int sample_is_start) {
  return sample_is_start ? t_enter >= bound : t_enter <= bound;
}

/* Weight of one ray's update at signed distance sdf (metres): 1, or Voxblox's linear drop-off
 * behind the surface when p.dropoff > 0. */
RAYMAP_FN float rm_tsdf_weight(float sdf, rm_tsdf_params p) {
  if (p.dropoff > 0.0f && sdf < -p.dropoff) {
    return RM_FMAXF((p.truncation + sdf) / (p.truncation - p.dropoff), 0.0f);
  }
  return 1.0f;
}

/* True when a ray at signed distance sdf updates the voxel at all: not more than tau behind the
 * surface (the walk reaches such voxels only by corners past its end). */
RAYMAP_FN int rm_tsdf_in_reach(float sdf, rm_tsdf_params p) { return sdf >= -p.truncation; }

/* The voxel after fusing one ray's signed distance sdf (metres) with weight w. Returns v itself
 * when the total weight is below RM_TSDF_MIN_WEIGHT. */
RAYMAP_FN rm_tsdf_voxel rm_tsdf_fuse(rm_tsdf_voxel v, float sdf, float w, rm_tsdf_params p) {
  rm_tsdf_voxel out;
  float total = v.weight + w;
  float d = RM_FMINF(RM_FMAXF(sdf, -p.truncation), p.truncation);
  if (total < RM_TSDF_MIN_WEIGHT) {
    return v;
  }
  out.weight = RM_FMINF(total, p.max_weight);
  /* A ray that agrees with the voxel leaves its average where it is, exactly: the common case of
   * free space crossed again (+tau on both sides), which then costs no division. */
  if (d == v.distance) {
    out.distance = d;
    return out;
  }
  out.distance =
      RM_FMINF(RM_FMAXF((v.distance * v.weight + d * w) / total, -p.truncation), p.truncation);
  return out;
}

/* The whole update of one voxel by one ray at signed distance sdf (CPU form; devices wrap
 * rm_tsdf_fuse in a compare-and-swap). Free space crossed again (+tau on a voxel already at
 * +tau: most voxels of most rays) only adds the ray's weight 1 and writes the weight word alone:
 * the same result as rm_tsdf_fuse, which ran 1.1 times as fast on the CPU (one thread, Ouster
 * scans; the pair is not rewritten, and none of the weight and average arithmetic runs). */
RAYMAP_FN void rm_tsdf_update(rm_tsdf_voxel* v, float sdf, rm_tsdf_params p) {
  if (sdf == p.truncation && v->distance == p.truncation) {
    v->weight = RM_FMINF(v->weight + 1.0f, p.max_weight);
    return;
  }
  if (rm_tsdf_in_reach(sdf, p)) {
    *v = rm_tsdf_fuse(*v, sdf, rm_tsdf_weight(sdf, p), p);
  }
}

#endif /* RAYMAP_KERNELS_COMMON_TSDF_H */
