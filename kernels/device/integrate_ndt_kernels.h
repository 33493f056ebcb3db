/* SPDX-License-Identifier: BSD-3-Clause */
/* The entry points of the NDT-OM / NDT-TM integration, written once for OpenCL C 1.2 and CUDA
 * through the qualifiers of device.h: kernels/opencl/integrate_ndt.cl and
 * kernels/cuda/integrate_ndt.cu are this header and nothing more (plus, in CUDA, the host
 * launcher). One work-item per span record (misses), then one per hit group (hits); the host
 * rounds the work-item count up to whole work-groups, so each entry point checks its index.
 * Layers a map lacks (NDT-TM's hit_miss and intensity in NDT-OM, the mean, the traversal layer)
 * are bound to a small placeholder and never touched (ndt_params.traversability, params.has_mean,
 * the map mode's RM_MODE_TRAVERSAL). The span kernel is made for one map mode (RM_MAP_MODE,
 * kernels/common/map_mode.h: a -D of the OpenCL build, a template parameter in CUDA). */
#ifndef RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_KERNELS_H
#define RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_KERNELS_H

#include "integrate_ndt.h"
#include "span_runs.h"

#if defined(RM_REGION_OWNED)
/* Span work per region: as rm_integrate_region_spans (integrate_occupancy_kernels.h),
 * rm_ndt_integrate_spans' parameters, then the batch's runs and the run cursor; each work-item
 * takes the next region's run of spans until none is left. */
RM_MODE_KERNEL void rm_ndt_integrate_region_spans(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_span_record* spans,
    RM_ATOMIC_GLOBAL rm_u32* occupancy, const RM_GLOBAL rm_ndt_voxel* ndt,
    const RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* hit_miss,
    RM_ATOMIC_GLOBAL rm_u32* traversal, rm_integrate_params params, rm_ndt_params ndt_params,
    RM_ATOMIC_GLOBAL rm_counter* counters, const RM_GLOBAL rm_span_run* runs,
    RM_ATOMIC_GLOBAL rm_u32* next_run) {
  rm_run_cursor cursor = rm_run_cursor_make();
  rm_u32 id;
  while (rm_next_owned_span(&cursor, runs, next_run, params.item_count, &id)) {
    RM_MODE_CALL(rm_ndt_integrate_span)
    (id, rays, spans, occupancy, ndt, means, hit_miss, traversal, params, ndt_params, counters);
  }
}
#else
RM_MODE_KERNEL void rm_ndt_integrate_spans(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_span_record* spans,
    RM_ATOMIC_GLOBAL rm_u32* occupancy, const RM_GLOBAL rm_ndt_voxel* ndt,
    const RM_GLOBAL rm_voxel_mean* means, RM_ATOMIC_GLOBAL rm_u32* hit_miss,
    RM_ATOMIC_GLOBAL rm_u32* traversal, rm_integrate_params params, rm_ndt_params ndt_params,
    RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    RM_MODE_CALL(rm_ndt_integrate_span)
    (id, rays, spans, occupancy, ndt, means, hit_miss, traversal, params, ndt_params, counters);
  }
}
#endif

RM_KERNEL void rm_ndt_apply_hit_groups(
    const RM_GLOBAL rm_prepared_ray* rays, const RM_GLOBAL rm_hit_group* groups,
    const RM_GLOBAL rm_u32* hit_rays, RM_GLOBAL rm_u32* occupancy, RM_GLOBAL rm_ndt_voxel* ndt,
    RM_GLOBAL rm_ndt_hit_miss* hit_miss, RM_GLOBAL rm_ndt_intensity* intensity,
    RM_GLOBAL rm_voxel_mean* means, rm_integrate_params params, rm_ndt_params ndt_params,
    RM_ATOMIC_GLOBAL rm_counter* counters) {
  rm_u32 id = rm_global_id();
  if (id < params.item_count) {
    rm_ndt_apply_hit_group(id, rays, groups, hit_rays, occupancy, ndt, hit_miss, intensity, means,
                           params, ndt_params, counters);
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_INTEGRATE_NDT_KERNELS_H */
