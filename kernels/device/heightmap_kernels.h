/* SPDX-License-Identifier: BSD-3-Clause */
/* The entry points of height-map generation, written once for OpenCL C 1.2 and CUDA through the
 * qualifiers of device.h: kernels/opencl/heightmap.cl and kernels/cuda/heightmap.cu are this
 * header (plus, in CUDA, the host launchers). First one work-item per column of every uploaded
 * region builds the column masks; then one work-item per cell: planar mode runs one launch; flood
 * fill runs one launch per ring (ring k reads ring k - 1, which the in-order queue / stream has
 * completed). The column search is kernels/common/heightmap.h, the same code the CPU generator
 * runs. */
#ifndef RAYMAP_KERNELS_DEVICE_HEIGHTMAP_KERNELS_H
#define RAYMAP_KERNELS_DEVICE_HEIGHTMAP_KERNELS_H

#include "../common/heightmap.h"
#include "device.h"

RM_DEVICE_FN rm_hm_layers rm_hm_make_layers(RM_GLOBAL float* elevation, RM_GLOBAL float* clearance,
                                            RM_GLOBAL rm_u32* kind, RM_GLOBAL rm_u32* samples,
                                            RM_GLOBAL float* reference, RM_GLOBAL float* normal_x,
                                            RM_GLOBAL float* normal_y, RM_GLOBAL float* normal_z) {
  rm_hm_layers out;
  out.elevation = elevation;
  out.clearance = clearance;
  out.kind = kind;
  out.samples = samples;
  out.reference = reference;
  out.normal_x = normal_x;
  out.normal_y = normal_y;
  out.normal_z = normal_z;
  return out;
}

RM_DEVICE_FN rm_hm_sources rm_hm_make_sources(const RM_GLOBAL rm_u32* table,
                                              const RM_GLOBAL rm_u32* region_slots,
                                              const RM_GLOBAL rm_hm_mask* masks,
                                              const RM_GLOBAL rm_voxel_mean* mean,
                                              const RM_GLOBAL rm_ndt_voxel* ndt) {
  rm_hm_sources src;
  src.table = table;
  src.region_slots = region_slots;
  src.masks = masks;
  src.mean = mean;
  src.ndt = ndt;
  return src;
}

/* One work-item per column of every uploaded region: the masks the searches read. */
RM_KERNEL void rm_heightmap_masks(rm_heightmap_params params, const RM_GLOBAL rm_u32* region_slots,
                                  const RM_GLOBAL float* occupancy, RM_GLOBAL rm_hm_mask* masks,
                                  rm_u32 region_count) {
  rm_hm_mask_item(params, region_slots, occupancy, masks, region_count, rm_global_id());
}

RM_KERNEL void rm_heightmap_planar(
    rm_heightmap_params params, const RM_GLOBAL rm_u32* table, const RM_GLOBAL rm_u32* region_slots,
    const RM_GLOBAL rm_hm_mask* masks, const RM_GLOBAL rm_voxel_mean* mean,
    const RM_GLOBAL rm_ndt_voxel* ndt, RM_GLOBAL float* elevation, RM_GLOBAL float* clearance,
    RM_GLOBAL rm_u32* kind, RM_GLOBAL rm_u32* samples, RM_GLOBAL float* reference,
    RM_GLOBAL float* normal_x, RM_GLOBAL float* normal_y, RM_GLOBAL float* normal_z) {
  rm_hm_planar_item(params, rm_hm_make_sources(table, region_slots, masks, mean, ndt),
                    rm_hm_make_layers(elevation, clearance, kind, samples, reference, normal_x,
                                      normal_y, normal_z),
                    rm_global_id());
}

RM_KERNEL void rm_heightmap_fill_ring(
    rm_heightmap_params params, const RM_GLOBAL rm_u32* table, const RM_GLOBAL rm_u32* region_slots,
    const RM_GLOBAL rm_hm_mask* masks, const RM_GLOBAL rm_voxel_mean* mean,
    const RM_GLOBAL rm_ndt_voxel* ndt, RM_GLOBAL float* elevation, RM_GLOBAL float* clearance,
    RM_GLOBAL rm_u32* kind, RM_GLOBAL rm_u32* samples, RM_GLOBAL float* reference,
    RM_GLOBAL float* normal_x, RM_GLOBAL float* normal_y, RM_GLOBAL float* normal_z, rm_i32 ring) {
  rm_hm_fill_item(params, rm_hm_make_sources(table, region_slots, masks, mean, ndt),
                  rm_hm_make_layers(elevation, clearance, kind, samples, reference, normal_x,
                                    normal_y, normal_z),
                  ring, rm_global_id());
}

#endif /* RAYMAP_KERNELS_DEVICE_HEIGHTMAP_KERNELS_H */
