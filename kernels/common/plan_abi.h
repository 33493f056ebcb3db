/* SPDX-License-Identifier: BSD-3-Clause */
/* What the host and the device planner's kernels (kernels/device/plan.h) share: the launch
 * arguments, the batch's region records the host reads back, the status words, the relative
 * region keys and the list of kernels. Every member is a 4-byte scalar, so C++, CUDA and OpenCL C
 * lay the structs out identically (static_asserts on the host).
 *
 * The device plans a batch in two phases around one read-back (docs/architecture.md, "Planning on
 * the device"): the plan phase walks every ray's regions, writes its span records, lists the
 * batch's distinct regions in a hash table and groups its samples per voxel; the host reads back
 * the distinct regions (a few hundred for a lidar scan of 65,536 rays), gives each one a device
 * slot exactly as the host planner would, and the resolve phase writes the slots into the spans
 * and hit groups. */
#ifndef RAYMAP_KERNELS_COMMON_PLAN_ABI_H
#define RAYMAP_KERNELS_COMMON_PLAN_ABI_H

#include "portable.h"

/* Work-items per work-group of every planning kernel, and elements each one takes in a scan or
 * sort tile. OpenCL builds the program with -DRM_PLAN_GROUP=<size that the device allows>. */
#ifndef RM_PLAN_GROUP
#define RM_PLAN_GROUP 256u
#endif
#define RM_PLAN_ITEMS 4u
#define RM_PLAN_TILE (RM_PLAN_GROUP * RM_PLAN_ITEMS)
/* Radix sort: bits per pass and buckets. */
#define RM_RADIX_BITS 4u
#define RM_RADIX_BUCKETS 16u

/* "Nothing": an empty table entry, a ray without a hit key, no cut. */
#define RM_PLAN_NONE 0xFFFFFFFFu

/* Status words of one plan, written by the plan kernels and read back by the host. */
#define RM_PLAN_STATUS_CUT_RAY 0u /* first ray that might not fit max_spans, else NONE */
#define RM_PLAN_STATUS_OUTSIDE 1u /* spans of the planned rays outside the rolling window */
#define RM_PLAN_STATUS_FAULT 2u   /* RM_PLAN_FAULT_* bits: the host plans the batch itself */
#define RM_PLAN_STATUS_REGIONS 3u /* distinct regions of the planned rays */
#define RM_PLAN_STATUS_SPANS 4u   /* span records of the planned rays */
#define RM_PLAN_STATUS_GROUPS 5u  /* hit groups (voxels with samples) */
#define RM_PLAN_STATUS_HITS 6u    /* samples */
/* Rays of the plan the device's preparation (kernels/device/prepare.h) accepted and rejected, by
 * reason; rays from the cut on are not counted. Zero for host-prepared rays. */
#define RM_PLAN_STATUS_ACCEPTED 8u
#define RM_PLAN_STATUS_INVALID 9u
#define RM_PLAN_STATUS_TOO_SHORT 10u
#define RM_PLAN_STATUS_OUT_OF_BOUNDS 11u
#define RM_PLAN_STATUS_OUTSIDE_WINDOW 12u
#define RM_PLAN_STATUS_CLIPPED 13u   /* accepted, clipped */
#define RM_PLAN_STATUS_NO_RETURN 14u /* accepted, without a return */
#define RM_PLAN_STATUS_WORDS 16u

#define RM_PLAN_FAULT_KEY_RANGE 1u  /* a region too far from the batch's key origin */
#define RM_PLAN_FAULT_TABLE_FULL 2u /* more distinct regions than the region table holds */

/* Relative region keys: a region as 11 + 11 + 10 bits of offset from the batch's key origin
 * (the first ray's origin region), +-1024 regions across and +-511 up and down (3.3 km and 1.6 km
 * with 3.2 m regions); a batch reaching further is planned on the host. All ones is NONE. */
#define RM_PLAN_KEY_XY_BIAS 1024
#define RM_PLAN_KEY_Z_BIAS 512

/* The relative key of `region`, or RM_PLAN_NONE when it is out of reach of `origin`. */
RAYMAP_FN rm_u32 rm_plan_region_key(rm_vec3i region, rm_vec3i origin) {
  rm_i32 x = region.x - origin.x + RM_PLAN_KEY_XY_BIAS;
  rm_i32 y = region.y - origin.y + RM_PLAN_KEY_XY_BIAS;
  rm_i32 z = region.z - origin.z + RM_PLAN_KEY_Z_BIAS;
  if (x < 0 || x > 2047 || y < 0 || y > 2047 || z < 0 || z > 1022) {
    return RM_PLAN_NONE;
  }
  return RM_U32(x) | (RM_U32(y) << 11) | (RM_U32(z) << 22);
}

/* Inverse of rm_plan_region_key. */
RAYMAP_FN rm_vec3i rm_plan_key_region(rm_u32 key, rm_vec3i origin) {
  return rm_vec3i_make(RM_I32(key & 2047u) - RM_PLAN_KEY_XY_BIAS + origin.x,
                       RM_I32((key >> 11) & 2047u) - RM_PLAN_KEY_XY_BIAS + origin.y,
                       RM_I32(key >> 22) - RM_PLAN_KEY_Z_BIAS + origin.z);
}

/* One distinct region of a planned batch, as the host reads it back. */
typedef struct rm_plan_region {
  rm_u32 key;        /* relative region key */
  rm_u32 entry;      /* its entry in the batch's region table */
  rm_u32 first_span; /* index of its first span record: the batch's order of first appearance */
  rm_u32 first_ray;  /* the ray of that span */
  rm_u32 spans;      /* span records in the region */
  rm_u32 hits;       /* samples that fell in it */
} rm_plan_region;

/* What the host decided for one region, in the order the regions were read back. */
typedef struct rm_plan_resolution {
  rm_u32 slot; /* device slot */
  rm_u32 rank; /* its run's place in the launch (span work per region), else 0 */
} rm_plan_resolution;

/* Launch arguments of every planning kernel; each kernel reads the members it names. */
typedef struct rm_plan_args {
  rm_u32 n;             /* elements (rays, spans, regions, table entries) of the launch */
  rm_u32 shift;         /* radix sort: the pass's lowest key bit */
  rm_u32 tiles;         /* scan and radix sort: tiles of the launch (RM_PLAN_TILE elements each) */
  rm_i32 region_voxels; /* voxels per region edge */
  rm_u32 voxels_per_region;
  rm_u32 max_spans;   /* span records the batch may hold */
  rm_u32 table_mask;  /* region table entries - 1 (a power of two) */
  rm_u32 table_shift; /* 32 - log2(entries): the hash's shift */
  rm_u32 region_cap;  /* region records the read-back buffer holds */
  rm_u32 rolling;     /* 1: regions outside [window_lo, window_hi] are skipped and counted */
  rm_vec3i window_lo; /* rolling window, region coordinates (inclusive) */
  rm_vec3i window_hi;
  rm_vec3i key_origin; /* the region relative keys are taken from */
} rm_plan_args;

/* Buffers a planning kernel takes (after its arguments): always this many, as generic words that
 * each kernel reads as its types, so the host binds every kernel the same way. */
#define RM_PLAN_BUFFERS 8
/* The parameter list of every planning entry point (kernels/device/plan_kernels.h,
 * prepare_kernels.h; RM_GLOBAL comes from kernels/device/device.h). */
#define RM_PLAN_PARAMS                                                                        \
  rm_plan_args args, RM_GLOBAL rm_u32 *b0, RM_GLOBAL rm_u32 *b1, RM_GLOBAL rm_u32 *b2,        \
      RM_GLOBAL rm_u32 *b3, RM_GLOBAL rm_u32 *b4, RM_GLOBAL rm_u32 *b5, RM_GLOBAL rm_u32 *b6, \
      RM_GLOBAL rm_u32 *b7

/* The planning kernels, in no particular order: X(name) for each; the entry point is
 * rm_plan_<name> (kernels/device/plan_kernels.h). */
#define RM_PLAN_KERNELS(X) \
  X(begin)                 \
  X(count)                 \
  X(cut)                   \
  X(emit)                  \
  X(scan_tiles)            \
  X(scan_add)              \
  X(radix_histogram)       \
  X(radix_scatter)         \
  X(group_heads)           \
  X(group_build)           \
  X(compact)               \
  X(finish)                \
  X(resolve_regions)       \
  X(resolve_spans)         \
  X(resolve_groups)        \
  X(gather_spans)          \
  X(clear_regions)         \
  X(clear_table)

/* The ray preparation kernels (kernels/device/prepare_kernels.h): double precision, so OpenCL
 * builds them as a program of their own (kernels/opencl/prepare.cl) where the device has
 * cl_khr_fp64; gpu::PlanKernel numbers them after RM_PLAN_KERNELS. */
#define RM_PREPARE_KERNELS(X) \
  X(prepare)                  \
  X(prepare_count)            \
  X(deskew)

#endif /* RAYMAP_KERNELS_COMMON_PLAN_ABI_H */
