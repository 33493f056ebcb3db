/* SPDX-License-Identifier: BSD-3-Clause */
/* The surface normal of an NDT voxel's Gaussian (ndt.h), shared by the CPU height-map generator,
 * OpenCL and CUDA: the eigenvector of the smallest eigenvalue of P = S S^T, pointing up.
 *
 * Method: one-sided (Hestenes) Jacobi on A = S^T. Rotating the columns of A until they are
 * orthogonal, A V = B, makes V^T P V = B^T B diagonal: the columns of V are the eigenvectors of P
 * and the squared column norms of B its eigenvalues. Working on the factor rather than on P keeps
 * the small eigenvalue accurate (P squares the factor's condition number, and float has little to
 * spare), needs no special case for a singular factor (a planar voxel has an exactly zero
 * eigenvalue) and no cubic roots. A 3x3 converges in 3 to 5 sweeps; at most RM_NDT_NORMAL_SWEEPS.
 *
 * Frame and units: the voxel's axes are the map's (world) axes, so the normal is a unit vector in
 * the world frame; eigenvalues are in voxel units squared (ndt.h).
 *
 * Orientation: the normal points up, n.z >= 0. On a vertical surface (n.z == 0 exactly) the first
 * non-zero of n.x, n.y is made positive, so the result is unique.
 *
 * Validity (else all three components are NaN), with l0 <= l1 <= l2 the eigenvalues:
 *  - count >= min_samples (the map's NDT sample threshold, 4 by default: fewer samples do not
 *    span a plane robustly);
 *  - spread: l1 >= RM_NDT_NORMAL_MIN_SPREAD * l2 and l1 > 0. Samples along a line (one scan line
 *    through a voxel) or at one point leave the normal's direction around the line undetermined;
 *  - flatness: l0 <= RM_NDT_NORMAL_MAX_THICKNESS * l1. An isotropic cloud (vegetation, noise larger
 *    than the voxel's extent) has no preferred axis; the eigenvector's error grows as 1/(l1 - l0).
 */
#ifndef RAYMAP_KERNELS_COMMON_NDT_NORMAL_H
#define RAYMAP_KERNELS_COMMON_NDT_NORMAL_H

#include "ndt.h"
#include "portable.h"

#define RM_NDT_NORMAL_SWEEPS 8
/* Columns count as orthogonal when |cos| of their angle is below this (float carries ~7 digits). */
#define RM_NDT_NORMAL_ORTHOGONAL 1e-6f
/* l1 / l2 at least this: the in-plane sigmas differ by at most a factor of ~2.2. */
#define RM_NDT_NORMAL_MIN_SPREAD 0.2f
/* l0 / l1 at most this: the sigma across the plane is at most half the smaller one along it. */
#define RM_NDT_NORMAL_MAX_THICKNESS 0.25f

/* Eigen-decomposition of P = S S^T from the packed factor s (ndt.h): value[k] is the eigenvalue of
 * the unit eigenvector vector[k] (voxel units squared), in no particular order. */
RAYMAP_FN void rm_ndt_eigen(const float* s, float* value, rm_vec3f* vector) {
  /* a[c][r]: column c of A = S^T is row c of S. v[c][r]: column c of V, from the identity. */
  float a[3][3];
  float v[3][3];
  int c;
  int r;
  int sweep;
  for (c = 0; c < 3; ++c) {
    for (r = 0; r < 3; ++r) {
      a[c][r] = 0.0f;
      v[c][r] = c == r ? 1.0f : 0.0f;
    }
  }
  a[0][0] = s[0];
  a[1][0] = s[1];
  a[1][1] = s[2];
  a[2][0] = s[3];
  a[2][1] = s[4];
  a[2][2] = s[5];
  for (sweep = 0; sweep < RM_NDT_NORMAL_SWEEPS; ++sweep) {
    int rotated = 0;
    int pair;
    for (pair = 0; pair < 3; ++pair) {
      const int p = pair == 2 ? 1 : 0;
      const int q = pair == 0 ? 1 : 2;
      float alpha = 0.0f;
      float beta = 0.0f;
      float gamma = 0.0f;
      for (r = 0; r < 3; ++r) {
        alpha += a[p][r] * a[p][r];
        beta += a[q][r] * a[q][r];
        gamma += a[p][r] * a[q][r];
      }
      if (gamma == 0.0f || RM_FABSF(gamma) <= RM_NDT_NORMAL_ORTHOGONAL * RM_SQRTF(alpha * beta)) {
        continue;
      }
      {
        /* The rotation that zeroes the columns' dot product (the smaller of the two angles). An
         * overflowing zeta gives t = 0: no rotation, never NaN. */
        const float zeta = (beta - alpha) / (2.0f * gamma);
        const float t =
            (zeta >= 0.0f ? 1.0f : -1.0f) / (RM_FABSF(zeta) + RM_SQRTF(1.0f + zeta * zeta));
        const float cs = 1.0f / RM_SQRTF(1.0f + t * t);
        const float sn = cs * t;
        for (r = 0; r < 3; ++r) {
          const float ap = a[p][r];
          const float aq = a[q][r];
          const float vp = v[p][r];
          const float vq = v[q][r];
          a[p][r] = cs * ap - sn * aq;
          a[q][r] = sn * ap + cs * aq;
          v[p][r] = cs * vp - sn * vq;
          v[q][r] = sn * vp + cs * vq;
        }
        rotated = 1;
      }
    }
    if (!rotated) {
      break;
    }
  }
  for (c = 0; c < 3; ++c) {
    /* V drifts from orthonormal only by rounding; renormalise each column. */
    const float length = RM_SQRTF(v[c][0] * v[c][0] + v[c][1] * v[c][1] + v[c][2] * v[c][2]);
    value[c] = a[c][0] * a[c][0] + a[c][1] * a[c][1] + a[c][2] * a[c][2];
    vector[c].x = v[c][0] / length;
    vector[c].y = v[c][1] / length;
    vector[c].z = v[c][2] / length;
  }
}

/* The upward unit normal of a voxel's Gaussian (packed factor s, `count` samples), world frame;
 * NaN in all three components when the validity rule above fails. */
RAYMAP_FN rm_vec3f rm_ndt_normal(const float* s, rm_u32 count, rm_u32 min_samples) {
  float value[3];
  rm_vec3f vector[3];
  rm_vec3f n;
  int lo = 0;
  int hi = 0;
  int k;
  n.x = RM_F32(NAN);
  n.y = n.x;
  n.z = n.x;
  if (count < min_samples || count == 0u) {
    return n;
  }
  rm_ndt_eigen(s, value, vector);
  for (k = 1; k < 3; ++k) {
    lo = value[k] < value[lo] ? k : lo;
    hi = value[k] >= value[hi] ? k : hi;
  }
  if (lo == hi) {
    return n; /* no order: NaN in the factor */
  }
  {
    const float l0 = value[lo];
    const float l1 = value[3 - lo - hi];
    const float l2 = value[hi];
    if (!(l1 > 0.0f && l1 >= RM_NDT_NORMAL_MIN_SPREAD * l2 &&
          l0 <= RM_NDT_NORMAL_MAX_THICKNESS * l1)) {
      return n;
    }
  }
  n = vector[lo];
  if (n.z < 0.0f || (n.z == 0.0f && (n.x < 0.0f || (n.x == 0.0f && n.y < 0.0f)))) {
    n.x = -n.x;
    n.y = -n.y;
    n.z = -n.z;
  }
  return n;
}

#endif /* RAYMAP_KERNELS_COMMON_NDT_NORMAL_H */
