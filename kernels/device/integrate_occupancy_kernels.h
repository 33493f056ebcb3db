/* SPDX-License-Identifier: BSD-3-Clause */
/* The entry points of the occupancy integration, written once for OpenCL C 1.2 and CUDA through
 * the qualifiers of device.h: kernels/opencl/integrate_occupancy.cl and
 * kernels/cuda/integrate_occupancy.cu are this header and nothing more (plus, in CUDA, the host
 * launchers). One work-item per hit group (tag, apply) or per span record (integrate); the host
 * rounds the work-item count up to whole work-groups, so each entry point checks its index.
 * Layers a map lacks (scan marks per ray, the traversal layer without decay rates, occupancy and
 * TSDF layers each in the other's maps) are bound to a small placeholder and never touched
 * (the map mode's bits). The span and hit kernels are made for one map mode (RM_MAP_MODE,
 * kernels/common/map_mode.h: a -D of the OpenCL build, a template parameter in CUDA); tagging is
 * the same in every mode. */
#ifndef RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_KERNELS_H
#define RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_KERNELS_H

#include "integrate_occupancy.h"
#include "span_runs.h"

RM_KERNEL void rm_tag_hit_groups(const RM_GLOBAL rm_hit_group* groups,
                                 RM_ATOMIC_GLOBAL rm_u32* occupancy, RM_GLOBAL rm_u32* scratch,
                                 rm_integrate_params params) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    rm_tag_hit_group(id, groups, occupancy, scratch, params);
  }
}

#if defined(RM_REGION_OWNED)
/* Span work per region (kernels/device/device.h): rm_integrate_spans' parameters, then the
 * batch's runs and the run cursor. Each work-item takes the next region's run of spans
 * (params.item_count runs, longest first) until none is left, and walks it in ray order as its
 * voxels' only writer. A few work-items per device thread: runs differ in length by orders of
 * magnitude, and taking them as workers come free balances what a static split would not. */
RM_MODE_KERNEL void rm_integrate_region_spans(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_span_record* spans,
    const RM_GLOBAL rm_hit_group* groups, const RM_GLOBAL rm_u32* hit_rays,
    RM_ATOMIC_GLOBAL rm_u32* occupancy, RM_ATOMIC_GLOBAL rm_u32* marks,
    RM_ATOMIC_GLOBAL rm_u32* scratch, RM_ATOMIC_GLOBAL rm_u32* traversal,
    RM_ATOMIC_GLOBAL rm_u32* tsdf, rm_integrate_params params,
    RM_ATOMIC_GLOBAL rm_counter* counters, const RM_GLOBAL rm_span_run* runs,
    RM_ATOMIC_GLOBAL rm_u32* next_run) {
  rm_run_cursor cursor = rm_run_cursor_make();
  rm_u32 id;
  while (rm_next_owned_span(&cursor, runs, next_run, params.item_count, &id)) {
    RM_MODE_CALL(rm_integrate_span)
    (id, rays, spans, groups, hit_rays, occupancy, marks, scratch, traversal, tsdf, params,
     counters);
  }
}
#else
RM_MODE_KERNEL void rm_integrate_spans(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_span_record* spans,
    const RM_GLOBAL rm_hit_group* groups, const RM_GLOBAL rm_u32* hit_rays,
    RM_ATOMIC_GLOBAL rm_u32* occupancy, RM_ATOMIC_GLOBAL rm_u32* marks,
    RM_ATOMIC_GLOBAL rm_u32* scratch, RM_ATOMIC_GLOBAL rm_u32* traversal,
    RM_ATOMIC_GLOBAL rm_u32* tsdf, rm_integrate_params params,
    RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    RM_MODE_CALL(rm_integrate_span)
    (id, rays, spans, groups, hit_rays, occupancy, marks, scratch, traversal, tsdf, params,
     counters);
  }
}
#endif

RM_MODE_KERNEL void rm_apply_hit_groups(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_hit_group* groups,
    const RM_GLOBAL rm_u32* hit_rays, RM_ATOMIC_GLOBAL rm_u32* occupancy,
    RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* marks, const RM_GLOBAL rm_u32* scratch,
    rm_integrate_params params, RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    RM_MODE_CALL(rm_apply_hit_group)
    (id, rays, groups, hit_rays, occupancy, means, marks, scratch, params, counters);
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_INTEGRATE_OCCUPANCY_KERNELS_H */
