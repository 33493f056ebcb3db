/* SPDX-License-Identifier: BSD-3-Clause */
/* OpenCL entry points of the occupancy integration: thin wrappers over
 * kernels/device/integrate_occupancy.h (the CUDA entry points wrap the same functions).
 * Built with -cl-std=CL1.2; the host defines RM_HAVE_INT64_ATOMICS when the device has
 * cl_khr_int64_base_atomics. */

/* The host walks the same spans in IEEE float without fused multiply-add; contracting a * b + c
 * here could move a region crossing by one rounding step. */
#pragma OPENCL FP_CONTRACT OFF

#include "kernels/device/integrate_occupancy.h"

RM_KERNEL void rm_tag_hit_groups(const RM_GLOBAL rm_hit_group* groups,
                                 RM_ATOMIC_GLOBAL rm_u32* occupancy, RM_GLOBAL rm_u32* scratch,
                                 rm_integrate_params params) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    rm_tag_hit_group(id, groups, occupancy, scratch, params);
  }
}

RM_KERNEL void rm_integrate_spans(const RM_GLOBAL rm_prepared_ray* rays,
                                  const RM_GLOBAL rm_span_record* spans,
                                  const RM_GLOBAL rm_hit_group* groups,
                                  const RM_GLOBAL rm_u32* hit_rays,
                                  RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                  RM_ATOMIC_GLOBAL rm_u32* marks, RM_ATOMIC_GLOBAL rm_u32* scratch,
                                  rm_integrate_params params,
                                  RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    rm_integrate_span(id, rays, spans, groups, hit_rays, occupancy, marks, scratch, params,
                      counters);
  }
}

RM_KERNEL void rm_apply_hit_groups(const RM_GLOBAL rm_prepared_ray* rays,
                                   const RM_GLOBAL rm_hit_group* groups,
                                   const RM_GLOBAL rm_u32* hit_rays,
                                   RM_ATOMIC_GLOBAL rm_u32* occupancy,
                                   RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* marks,
                                   const RM_GLOBAL rm_u32* scratch, rm_integrate_params params,
                                   RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    rm_apply_hit_group(id, rays, groups, hit_rays, occupancy, means, marks, scratch, params,
                       counters);
  }
}
