/* SPDX-License-Identifier: BSD-3-Clause */
/* Ray preparation, written once: a world-frame ray (origin and sample in metres, double) becomes
 * the two exact voxel keys the walk starts and ends at, after the range limits, the TSDF
 * extension behind the sample and the clip to a rolling window. raymap::RayPreparer runs it on the
 * host (and adds segmentation), the device planner's rm_prepare kernel (kernels/device/prepare.h)
 * on the device, so both give the same prepared rays and count the same rejections.
 *
 * Double precision: OpenCL C needs cl_khr_fp64 (kernels/opencl/prepare.cl enables it; a device
 * without it prepares on the host). Every operation is written in the order the host has always
 * evaluated it, and no compiler may contract a * b + c here: the OpenCL program sets FP_CONTRACT
 * OFF, nvcc compiles with --fmad=false. */
#ifndef RAYMAP_KERNELS_COMMON_RAY_PREPARE_H
#define RAYMAP_KERNELS_COMMON_RAY_PREPARE_H

#include "portable.h"
#include "ray.h"
#include "tsdf.h"

#if defined(__OPENCL_C_VERSION__) || defined(__CUDACC__)
#define RM_FLOORD(x) floor(x)
#define RM_SQRTD(x) sqrt(x)
#define RM_ISFINITED(x) isfinite(x)
#elif defined(__cplusplus)
#include <cmath>
#define RM_FLOORD(x) std::floor(x)
#define RM_SQRTD(x) std::sqrt(x)
#define RM_ISFINITED(x) std::isfinite(x)
#else
#include <math.h>
#define RM_FLOORD(x) floor(x)
#define RM_SQRTD(x) sqrt(x)
#define RM_ISFINITED(x) isfinite(x)
#endif

/* Rays longer than this many voxels are rejected: the walk runs in float relative to its start
 * voxel, and 2^22 voxels (419 km at 0.1 m) keeps positions exact to better than 1e-3 voxel. */
#define RM_PREPARE_MAX_RAY_VOXELS 4194304.0

/* A position or direction in metres, double precision. */
typedef struct rm_vec3d {
  double x;
  double y;
  double z;
} rm_vec3d;

/* A world-frame ray as the host's raymap::Ray lays it out (src/map/ray.hpp asserts the layout), so
 * a batch of rays goes to the device as it is. */
typedef struct rm_raw_ray {
  rm_vec3d origin; /* sensor position, metres */
  rm_vec3d sample; /* return or no-return end point, metres */
  double time_s;   /* not used by the preparation */
  float intensity;
  rm_u32 flags;   /* RM_RAW_RAY_* */
  rm_u32 scan_lo; /* the ray's scan, not used by the preparation */
  rm_u32 scan_hi;
} rm_raw_ray;
#define RM_RAW_RAY_NO_RETURN 1u /* raymap::kRayNoReturn: clears along the ray, no hit */

/* What the preparation of one map and ray filter needs; doubles first, so C++, CUDA and OpenCL C
 * lay it out alike. */
typedef struct rm_prepare_params {
  double inv_resolution; /* voxels per metre */
  double min_range_m;    /* shorter rays are rejected */
  double max_range_m;    /* 0: none; longer rays are clipped to it */
  double max_length_m;   /* 0: none; longer rays are outliers, rejected before any clipping */
  double truncation_m;   /* TSDF maps: how far a ray goes on behind its sample */
  double max_voxel;      /* a floored voxel coordinate v is in range when -max < v < max */
  rm_vec3d window_lo;    /* rolling maps: the window grown by half a voxel, metres */
  rm_vec3d window_hi;
  rm_u32 tsdf;      /* 1: TSDF map */
  rm_u32 rolling;   /* 1: clip to [window_lo, window_hi] */
  rm_u32 walk_flag; /* RM_RAY_REVERSE or 0 */
  rm_u32 unused;
} rm_prepare_params;

/* Outcome of preparing one ray: the reason it was rejected (low bits) or ACCEPTED, and whether it
 * was clipped or had no return. */
#define RM_PREPARE_ACCEPTED 0u
#define RM_PREPARE_INVALID 1u        /* NaN or infinite coordinates */
#define RM_PREPARE_TOO_SHORT 2u      /* shorter than min range */
#define RM_PREPARE_OUT_OF_BOUNDS 3u  /* beyond the map's key range, or too long */
#define RM_PREPARE_OUTSIDE_WINDOW 4u /* entirely outside the rolling window */
#define RM_PREPARE_REJECTED_MASK 7u
#define RM_PREPARE_CLIPPED 8u    /* shortened to max range or the window */
#define RM_PREPARE_NO_RETURN 16u /* flagged no-return */

/* The ray as the walk takes it, when accepted. */
typedef struct rm_prepared_ends {
  rm_vec3d origin; /* after clipping, metres */
  rm_vec3d sample;
  rm_vec3i origin_voxel;
  rm_vec3f origin_local; /* inside origin_voxel, voxel units */
  rm_vec3i sample_voxel;
  rm_vec3f sample_local;
  double kept_m;    /* |sample - origin| after clipping */
  double end_sdf_m; /* TSDF: signed distance at the sample end (RM_TSDF_FREE: free space only) */
  rm_u32 end_flag;  /* RM_RAY_END_HIT or 0 */
} rm_prepared_ends;

RAYMAP_FN rm_vec3d rm_vec3d_make(double x, double y, double z) {
  rm_vec3d v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}
RAYMAP_FN rm_vec3d rm_vec3d_add(rm_vec3d a, rm_vec3d b) {
  return rm_vec3d_make(a.x + b.x, a.y + b.y, a.z + b.z);
}
RAYMAP_FN rm_vec3d rm_vec3d_sub(rm_vec3d a, rm_vec3d b) {
  return rm_vec3d_make(a.x - b.x, a.y - b.y, a.z - b.z);
}
RAYMAP_FN rm_vec3d rm_vec3d_scale(rm_vec3d a, double s) {
  return rm_vec3d_make(a.x * s, a.y * s, a.z * s);
}
RAYMAP_FN double rm_vec3d_norm(rm_vec3d a) { return RM_SQRTD(a.x * a.x + a.y * a.y + a.z * a.z); }
RAYMAP_FN int rm_vec3d_finite(rm_vec3d a) {
  return RM_ISFINITED(a.x) && RM_ISFINITED(a.y) && RM_ISFINITED(a.z);
}
RAYMAP_FN double rm_vec3d_axis(rm_vec3d a, int axis) {
  return axis == 0 ? a.x : (axis == 1 ? a.y : a.z);
}

/* The voxel holding `p` (metres) and `p` inside it (voxel units in [0, 1]); 0 when a coordinate
 * is out of the map's key range. */
RAYMAP_FN int rm_prepare_key(const rm_prepare_params* params, rm_vec3d p, rm_vec3i* voxel,
                             rm_vec3f* inside) {
  double sx = p.x * params->inv_resolution;
  double sy = p.y * params->inv_resolution;
  double sz = p.z * params->inv_resolution;
  double fx = RM_FLOORD(sx);
  double fy = RM_FLOORD(sy);
  double fz = RM_FLOORD(sz);
  double limit = params->max_voxel;
  if (!(fx > -limit && fx < limit) || !(fy > -limit && fy < limit) ||
      !(fz > -limit && fz < limit)) {
    return 0;
  }
  *voxel = rm_vec3i_make(RM_I32(fx), RM_I32(fy), RM_I32(fz));
  *inside = rm_vec3f_make(RM_F32(sx - fx), RM_F32(sy - fy), RM_F32(sz - fz));
  return 1;
}

/* Clips the segment a + t (b - a), t in [0, 1], to the box [lo, hi]. Returns 0 when the segment
 * misses the box; otherwise [*t0, *t1] is the part inside. */
RAYMAP_FN int rm_prepare_clip(rm_vec3d a, rm_vec3d b, rm_vec3d lo, rm_vec3d hi, double* t0,
                              double* t1) {
  double enter = 0.0;
  double exit = 1.0;
  int axis;
  for (axis = 0; axis < 3; ++axis) {
    double aa = rm_vec3d_axis(a, axis);
    double d = rm_vec3d_axis(b, axis) - aa;
    double ta;
    double tb;
    if (d == 0.0) {
      if (aa < rm_vec3d_axis(lo, axis) || aa > rm_vec3d_axis(hi, axis)) {
        return 0;
      }
      continue;
    }
    ta = (rm_vec3d_axis(lo, axis) - aa) / d;
    tb = (rm_vec3d_axis(hi, axis) - aa) / d;
    if (ta > tb) {
      double swap = ta;
      ta = tb;
      tb = swap;
    }
    enter = enter < ta ? ta : enter;
    exit = tb < exit ? tb : exit;
    if (enter > exit) {
      return 0;
    }
  }
  *t0 = enter;
  *t1 = exit;
  return 1;
}

/* Prepares the ray from `origin` to `sample` (metres); `no_return`: the sample is not a return.
 * Returns the outcome (RM_PREPARE_*); `out` is written when the ray is accepted. A ray with a
 * return gets RM_RAY_END_HIT; a clipped or no-return one does not (it clears the voxels before its
 * end voxel). TSDF maps walk a ray with a return on by the truncation distance and give no hit. */
RAYMAP_FN rm_u32 rm_prepare_ray(const rm_prepare_params* params, rm_vec3d origin, rm_vec3d sample,
                                int no_return, rm_prepared_ends* out) {
  double length;
  double end_sdf = RM_F64(RM_TSDF_FREE);
  rm_u32 end_flag = no_return ? 0u : RM_RAY_END_HIT;
  rm_u32 outcome = no_return ? RM_PREPARE_NO_RETURN : 0u;
  if (!rm_vec3d_finite(origin) || !rm_vec3d_finite(sample)) {
    return RM_PREPARE_INVALID;
  }
  length = rm_vec3d_norm(rm_vec3d_sub(sample, origin));
  if (length < params->min_range_m) {
    return RM_PREPARE_TOO_SHORT;
  }
  if (params->max_length_m > 0.0 && length > params->max_length_m) {
    return RM_PREPARE_OUT_OF_BOUNDS; /* an outlier return (tens of km): not a measurement */
  }
  if (params->max_range_m > 0.0 && length > params->max_range_m) {
    sample = rm_vec3d_add(
        origin, rm_vec3d_scale(rm_vec3d_sub(sample, origin), params->max_range_m / length));
    end_flag = 0u;
    outcome |= RM_PREPARE_CLIPPED;
  }
  if (params->tsdf != 0u && end_flag != 0u) {
    if (length > 0.0) {
      sample = rm_vec3d_add(
          sample, rm_vec3d_scale(rm_vec3d_sub(sample, origin), params->truncation_m / length));
      end_sdf = -params->truncation_m;
    } else {
      end_sdf = 0.0;
    }
    end_flag = 0u;
  }
  if (params->rolling != 0u) {
    double t0 = 0.0;
    double t1 = 1.0;
    rm_vec3d d;
    if (!rm_prepare_clip(origin, sample, params->window_lo, params->window_hi, &t0, &t1)) {
      return RM_PREPARE_OUTSIDE_WINDOW;
    }
    d = rm_vec3d_sub(sample, origin);
    if (t1 < 1.0) {
      end_sdf += (1.0 - t1) * rm_vec3d_norm(d);
      sample = rm_vec3d_add(origin, rm_vec3d_scale(d, t1));
      end_flag = 0u;
      outcome |= RM_PREPARE_CLIPPED;
    }
    if (t0 > 0.0) {
      origin = rm_vec3d_add(origin, rm_vec3d_scale(d, t0));
      outcome |= RM_PREPARE_CLIPPED;
    }
  }
  out->kept_m = rm_vec3d_norm(rm_vec3d_sub(sample, origin));
  if (out->kept_m * params->inv_resolution > RM_PREPARE_MAX_RAY_VOXELS ||
      !rm_prepare_key(params, origin, &out->origin_voxel, &out->origin_local) ||
      !rm_prepare_key(params, sample, &out->sample_voxel, &out->sample_local)) {
    return RM_PREPARE_OUT_OF_BOUNDS;
  }
  out->origin = origin;
  out->sample = sample;
  out->end_sdf_m = end_sdf;
  out->end_flag = end_flag;
  return outcome;
}

#endif /* RAYMAP_KERNELS_COMMON_RAY_PREPARE_H */
