/* SPDX-License-Identifier: BSD-3-Clause */
/* The entry points of the device's ray preparation (prepare.h), with the planning kernels'
 * signature (plan_kernels.h: the launch arguments and RM_PLAN_BUFFERS generic word buffers), so the
 * device planner launches them as two more planning kernels. OpenCL builds them into a program of
 * their own, kernels/opencl/prepare.cl, which needs cl_khr_fp64; CUDA into kernels/cuda/plan.cu. */
#ifndef RAYMAP_KERNELS_DEVICE_PREPARE_KERNELS_H
#define RAYMAP_KERNELS_DEVICE_PREPARE_KERNELS_H

#include "prepare.h"

/* b0 raw rays, b1 preparation parameters, b2 prepared rays, b3 outcomes; args.n rays */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_prepare(RM_PLAN_PARAMS) {
  rm_prepare_item(rm_global_id(), args.n, (const RM_GLOBAL rm_raw_ray*)b0,
                  (const RM_GLOBAL rm_prepare_params*)b1, (RM_GLOBAL rm_prepared_ray*)b2, b3);
}

/* b0 outcomes, b1 status; args.n rays */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_prepare_count(RM_PLAN_PARAMS) {
  RM_LOCAL_ARRAY(rm_u32, sums, RM_PREPARE_SUMS);
  rm_prepare_count_item(rm_global_id(), args.n, b0, (RM_ATOMIC_GLOBAL rm_u32*)b1, sums);
}

/* b0 points, b1 pose samples, b2 segments, b3 raw rays; args.n points */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_deskew(RM_PLAN_PARAMS) {
  rm_deskew_item(rm_global_id(), args.n, (const RM_GLOBAL rm_scan_point*)b0,
                 (const RM_GLOBAL rm_pose_sample*)b1, (const RM_GLOBAL rm_deskew_segment*)b2,
                 (RM_GLOBAL rm_raw_ray*)b3);
}

#endif /* RAYMAP_KERNELS_DEVICE_PREPARE_KERNELS_H */
