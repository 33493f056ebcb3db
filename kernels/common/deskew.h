/* SPDX-License-Identifier: BSD-3-Clause */
/* Deskewing, written once: a point of a scan (sensor frame, with its own time) becomes the
 * world-frame ray from the sensor's pose at that time, the base's pose interpolated between the
 * samples that bracket the time and composed with the sensor's extrinsic (kernels/common/pose.h).
 * The host (raymap::RayBatcher's conversion of points it cannot hand to a device) and the device
 * (the rm_plan_deskew kernel, kernels/device/prepare.h) run the same functions on the same
 * samples, so they make the same rays; and they make the rays pipeline::PointDeskewer makes from
 * a PoseHistory holding those samples (tests/unit/pipeline/test_deskew_tables.cpp).
 *
 * A batch carries its points, a table of base pose samples and a table of segments: the points
 * converted in one step of one scan, with their sensor's extrinsic and the samples that covered
 * them then (a later pose can change what a time interpolates to, so each step keeps its own).
 * Double precision: OpenCL C needs cl_khr_fp64. */
#ifndef RAYMAP_KERNELS_COMMON_DESKEW_H
#define RAYMAP_KERNELS_COMMON_DESKEW_H

#include "pose.h"

#if defined(__OPENCL_C_VERSION__)
typedef long rm_i64;
#else
typedef int64_t rm_i64;
#endif

/* Pose samples and segments one batch of points may carry. */
#define RM_DESKEW_MAX_POSE_SAMPLES 4096u
#define RM_DESKEW_MAX_SEGMENTS 1024u

/* One point of a scan: sensor frame, with its absolute time. */
typedef struct rm_scan_point {
  float x; /* sensor frame, metres */
  float y;
  float z;
  float intensity;
  rm_u32 flags;   /* RM_RAW_RAY_NO_RETURN: a free-space-only point */
  rm_u32 segment; /* its entry in the batch's segment table */
  rm_i64 time_ns; /* the scan's stamp plus the point's offset, ns */
} rm_scan_point;

/* The base's pose in the world frame at a time (ns, the pose source's clock). */
typedef struct rm_pose_sample {
  rm_i64 time_ns;
  rm_i64 unused;
  rm_pose pose;
} rm_pose_sample;

/* Points converted together: their sensor's pose in the base frame, and the pose samples (at
 * increasing times, at least one) that cover their times. */
typedef struct rm_deskew_segment {
  rm_pose extrinsic;
  rm_u32 first_pose; /* in the batch's pose sample table */
  rm_u32 poses;
} rm_deskew_segment;

/* The base pose at time t from samples[0 .. n), n >= 1, as pipeline::PoseHistory::lookup gives
 * it for samples that cover t: the last sample's pose from its time on, otherwise interpolated
 * between the two samples that bracket t. (A t before the first sample, which a covering table
 * never has, gets the first pose.) */
RAYMAP_FN rm_pose rm_deskew_base_pose(const RAYMAP_GLOBAL rm_pose_sample* samples, rm_u32 n,
                                      rm_i64 t) {
  rm_u32 lo = 0u;
  rm_u32 hi = n - 1u;
  rm_i64 t0;
  rm_i64 t1;
  if (t >= samples[hi].time_ns) {
    return samples[hi].pose;
  }
  if (t < samples[0].time_ns) {
    return samples[0].pose;
  }
  /* samples[lo].time_ns <= t < samples[hi].time_ns */
  while (hi - lo > 1u) {
    rm_u32 mid = lo + (hi - lo) / 2u;
    if (samples[mid].time_ns <= t) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  t0 = samples[lo].time_ns;
  t1 = samples[hi].time_ns;
  return rm_pose_interpolate(samples[lo].pose, samples[hi].pose, RM_F64(t - t0) / RM_F64(t1 - t0));
}

/* The world-frame ray of point `p` of segment `segment`: from the sensor's position at the
 * point's time to the point. */
RAYMAP_FN void rm_deskew_point(rm_scan_point p, const RAYMAP_GLOBAL rm_pose_sample* samples,
                               rm_deskew_segment segment, rm_vec3d* origin, rm_vec3d* sample) {
  rm_pose base = rm_deskew_base_pose(samples + segment.first_pose, segment.poses, p.time_ns);
  rm_pose sensor = rm_pose_compose(base, segment.extrinsic);
  *origin = sensor.position;
  *sample = rm_pose_apply(sensor, rm_vec3d_make(RM_F64(p.x), RM_F64(p.y), RM_F64(p.z)));
}

#endif /* RAYMAP_KERNELS_COMMON_DESKEW_H */
