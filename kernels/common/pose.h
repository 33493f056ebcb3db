/* SPDX-License-Identifier: BSD-3-Clause */
/* Rigid poses in double precision, written once: applying a pose to a point, composing two poses
 * and interpolating between two (position linearly, orientation by normalised linear
 * interpolation along the shorter arc, nlerp). raymap::io::Pose's transform(), compose() and
 * interpolate() call these, so every deskewed ray, trajectory pose and TF chain is computed by
 * this one definition on every host (x86-64 and arm64 alike) and can be on a device.
 *
 * The order of every operation is the one Eigen 3.4 evaluates on x86-64 (Quaternion * Vector3 as
 * its 30-flop form; Quaternion * Quaternion as its SSE2 kernel; a Vector4's squared norm as two
 * lanes summed), so the switch from Eigen changed no result on x86-64
 * (tests/unit/io/test_pose_math.cpp compares bit for bit). No compiler may contract
 * a * b + c here: x86-64's baseline has no fused multiply-add; OpenCL programs set FP_CONTRACT
 * OFF and nvcc runs with --fmad=false. OpenCL C needs cl_khr_fp64. */
#ifndef RAYMAP_KERNELS_COMMON_POSE_H
#define RAYMAP_KERNELS_COMMON_POSE_H

#include "ray_prepare.h"

/* A unit quaternion, Hamilton convention: w + xi + yj + zk. */
typedef struct rm_quat {
  double w;
  double x;
  double y;
  double z;
} rm_quat;

/* The pose of frame b in frame a: p_a = orientation * p_b + position (metres). */
typedef struct rm_pose {
  rm_vec3d position;
  rm_quat orientation;
} rm_pose;

RAYMAP_FN rm_vec3d rm_vec3d_cross(rm_vec3d a, rm_vec3d b) {
  return rm_vec3d_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* q * v for a unit quaternion: uv = 2 (q.xyz x v); v + w uv + q.xyz x uv. */
RAYMAP_FN rm_vec3d rm_quat_rotate(rm_quat q, rm_vec3d v) {
  rm_vec3d u = rm_vec3d_make(q.x, q.y, q.z);
  rm_vec3d uv = rm_vec3d_cross(u, v);
  rm_vec3d c;
  uv = rm_vec3d_add(uv, uv);
  c = rm_vec3d_cross(u, uv);
  return rm_vec3d_make(v.x + q.w * uv.x + c.x, v.y + q.w * uv.y + c.y, v.z + q.w * uv.z + c.z);
}

/* a * b (b first, then a), grouped as Eigen's SSE2 kernel groups it. */
RAYMAP_FN rm_quat rm_quat_mul(rm_quat a, rm_quat b) {
  rm_quat r;
  r.x = (a.w * b.x + a.y * b.z) - (a.z * b.y - a.x * b.w);
  r.y = (a.w * b.y + a.y * b.w) + (a.z * b.x - a.x * b.z);
  r.z = (a.w * b.z - a.y * b.x) + (a.z * b.w + a.x * b.y);
  r.w = (a.w * b.w - a.y * b.y) - (a.z * b.z + a.x * b.x);
  return r;
}

/* The four-component dot product, summed as two lanes (x, z) and (y, w). */
RAYMAP_FN double rm_quat_dot(rm_quat a, rm_quat b) {
  return (a.x * b.x + a.z * b.z) + (a.y * b.y + a.w * b.w);
}

/* q / |q|; q unchanged when its norm is 0. */
RAYMAP_FN rm_quat rm_quat_normalised(rm_quat q) {
  double n = rm_quat_dot(q, q);
  if (n > 0.0) {
    double s = RM_SQRTD(n);
    q.w = q.w / s;
    q.x = q.x / s;
    q.y = q.y / s;
    q.z = q.z / s;
  }
  return q;
}

/* p_a of a point p_b given in frame b. */
RAYMAP_FN rm_vec3d rm_pose_apply(rm_pose a_b, rm_vec3d p_b) {
  return rm_vec3d_add(a_b.position, rm_quat_rotate(a_b.orientation, p_b));
}

/* The pose of frame c in frame a from a_b (b in a) and b_c (c in b). */
RAYMAP_FN rm_pose rm_pose_compose(rm_pose a_b, rm_pose b_c) {
  rm_pose a_c;
  a_c.position = rm_pose_apply(a_b, b_c.position);
  a_c.orientation = rm_quat_mul(a_b.orientation, b_c.orientation);
  return a_c;
}

/* The pose a fraction f in [0, 1] of the way from a to b; f == 0 gives a exactly. */
RAYMAP_FN rm_pose rm_pose_interpolate(rm_pose a, rm_pose b, double f) {
  rm_pose p;
  double g;
  double h;
  if (f == 0.0) {
    return a;
  }
  p.position = rm_vec3d_add(a.position, rm_vec3d_scale(rm_vec3d_sub(b.position, a.position), f));
  /* q and -q are one rotation: b goes onto a's hemisphere, so nlerp takes the short arc. */
  g = 1.0 - f;
  h = f * (rm_quat_dot(a.orientation, b.orientation) < 0.0 ? -1.0 : 1.0);
  p.orientation.w = g * a.orientation.w + h * b.orientation.w;
  p.orientation.x = g * a.orientation.x + h * b.orientation.x;
  p.orientation.y = g * a.orientation.y + h * b.orientation.y;
  p.orientation.z = g * a.orientation.z + h * b.orientation.z;
  p.orientation = rm_quat_normalised(p.orientation);
  return p;
}

#endif /* RAYMAP_KERNELS_COMMON_POSE_H */
