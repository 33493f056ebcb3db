/* SPDX-License-Identifier: BSD-3-Clause */
/* Preparing a batch's rays on the device, before it is planned (plan.h): each world-frame ray
 * (rm_raw_ray, as the host's raymap::Ray lays it out) goes through rm_prepare_ray
 * (kernels/common/ray_prepare.h), the host's own preparation, into the batch's ray array at its
 * own index. A rejected ray keeps its place as an RM_RAY_SKIP ray, which crosses no region: the
 * plan's prefix sums then give every accepted ray's span records in ray order, as for
 * host-prepared rays, with no compaction pass. After the plan's cut, rm_prepare_count_item counts
 * the outcomes of the rays the plan covers into the status words, one local sum per work-group, so
 * the host adds exactly what the host's preparation would have counted.
 *
 * Written once for OpenCL C 1.2 with cl_khr_fp64 and CUDA. */
#ifndef RAYMAP_KERNELS_DEVICE_PREPARE_H
#define RAYMAP_KERNELS_DEVICE_PREPARE_H

#include "../common/deskew.h"
#include "../common/plan_abi.h"
#include "../common/ray.h"
#include "../common/ray_prepare.h"
#include "device.h"

/* Work-item r < n: ray r prepared into rays[r], its outcome (RM_PREPARE_*) into outcomes[r]. */
RM_DEVICE_FN void rm_prepare_item(rm_u32 r, rm_u32 n, const RM_GLOBAL rm_raw_ray* in,
                                  const RM_GLOBAL rm_prepare_params* params_in,
                                  RM_GLOBAL rm_prepared_ray* rays, RM_GLOBAL rm_u32* outcomes) {
  rm_prepare_params params;
  rm_raw_ray raw;
  rm_prepared_ends ends;
  rm_prepared_ray ray;
  rm_u32 outcome;
  if (r >= n) {
    return;
  }
  params = *params_in;
  raw = in[r];
  outcome = rm_prepare_ray(&params, raw.origin, raw.sample,
                           (raw.flags & RM_RAW_RAY_NO_RETURN) != 0u ? 1 : 0, &ends);
  if ((outcome & RM_PREPARE_REJECTED_MASK) != RM_PREPARE_ACCEPTED) {
    ray.origin_voxel = rm_vec3i_make(0, 0, 0);
    ray.origin_local = rm_vec3f_make(0.0f, 0.0f, 0.0f);
    ray.sample_voxel = ray.origin_voxel;
    ray.sample_local = ray.origin_local;
    ray.flags = RM_RAY_SKIP;
    ray.intensity = 0.0f;
    ray.tsdf_end_m = 0.0f;
  } else {
    ray.origin_voxel = ends.origin_voxel;
    ray.origin_local = ends.origin_local;
    ray.sample_voxel = ends.sample_voxel;
    ray.sample_local = ends.sample_local;
    ray.flags = ends.end_flag | params.walk_flag;
    ray.intensity = raw.intensity;
    ray.tsdf_end_m = RM_F32(ends.end_sdf_m);
  }
  rays[r] = ray;
  outcomes[r] = outcome;
}

/* Work-item r < n: point r deskewed (kernels/common/deskew.h) into the world-frame ray in[r]
 * that rm_prepare_item then prepares. */
RM_DEVICE_FN void rm_deskew_item(rm_u32 r, rm_u32 n, const RM_GLOBAL rm_scan_point* points,
                                 const RM_GLOBAL rm_pose_sample* samples,
                                 const RM_GLOBAL rm_deskew_segment* segments,
                                 RM_GLOBAL rm_raw_ray* rays) {
  rm_scan_point p;
  rm_raw_ray ray;
  if (r >= n) {
    return;
  }
  p = points[r];
  rm_deskew_point(p, samples, segments[p.segment], &ray.origin, &ray.sample);
  ray.time_s = RM_F64(p.time_ns) * 1e-9;
  ray.intensity = p.intensity;
  ray.flags = p.flags;
  ray.scan_lo = 0u;
  ray.scan_hi = 0u;
  rays[r] = ray;
}

/* Status word of each counted outcome, in the order of rm_prepare_count_item's local sums. */
#define RM_PREPARE_SUMS 7u

/* Work-item r of a work-group (every item reaches the barriers): counts the outcome of ray r when
 * the plan covers it (r < n and before the cut) into `sums` (RM_PREPARE_SUMS local words), then
 * adds the group's sums to the status words. */
RM_DEVICE_FN void rm_prepare_count_item(rm_u32 r, rm_u32 n, const RM_GLOBAL rm_u32* outcomes,
                                        RM_ATOMIC_GLOBAL rm_u32* status,
                                        volatile RM_LOCAL rm_u32* sums) {
  rm_u32 lid = rm_local_id();
  rm_u32 cut = rm_load_u32(status + RM_PLAN_STATUS_CUT_RAY);
  if (lid < RM_PREPARE_SUMS) {
    sums[lid] = 0u;
  }
  rm_group_barrier();
  if (r < n && r < cut) {
    rm_u32 outcome = outcomes[r];
    rm_u32 reason = outcome & RM_PREPARE_REJECTED_MASK;
    /* reason 0 (accepted) to 4 (outside the window) are sums 0 to 4 */
    (void)rm_local_atomic_add(sums + reason, 1u);
    if (reason == RM_PREPARE_ACCEPTED && (outcome & RM_PREPARE_CLIPPED) != 0u) {
      (void)rm_local_atomic_add(sums + 5u, 1u);
    }
    if (reason == RM_PREPARE_ACCEPTED && (outcome & RM_PREPARE_NO_RETURN) != 0u) {
      (void)rm_local_atomic_add(sums + 6u, 1u);
    }
  }
  rm_group_barrier();
  if (lid < RM_PREPARE_SUMS && sums[lid] != 0u) {
    (void)rm_atomic_add_u32(status + RM_PLAN_STATUS_ACCEPTED + lid, sums[lid]);
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_PREPARE_H */
