/* SPDX-License-Identifier: BSD-3-Clause */
/* What the host hands a device for one batch, besides the prepared rays: span records (one
 * work-item each), hit groups (one work-item per voxel that samples fell in) and the launch
 * parameters. Host and device share these layouts: every member is a 4-byte scalar, so C++,
 * CUDA and OpenCL C lay them out identically (checked by static_asserts on the host). */
#ifndef RAYMAP_KERNELS_COMMON_BATCH_H
#define RAYMAP_KERNELS_COMMON_BATCH_H

#include "occupancy.h"
#include "portable.h"
#include "tsdf.h"

/* The piece of one ray inside one region, with the device cache slot that holds the region.
 * Spans are produced by the host's coarse region walk; the device walks their voxels with
 * rm_span_walk (span_walk.h). */
typedef struct rm_span_record {
  rm_u32 ray;      /* index of the ray in the batch */
  rm_u32 slot;     /* device cache slot of the region */
  rm_u32 flags;    /* RM_SPAN_FIRST | RM_SPAN_LAST (span_walk.h) */
  float t0;        /* ray parameter where the span starts (walk frame, see line_walk.h) */
  float t1;        /* ray parameter where it ends */
  rm_vec3i box_lo; /* the region's minimum voxel relative to the walk's start voxel */
} rm_span_record;

/* The span records of one region, when the host has grouped a batch's spans by region (span work
 * per region, kernels/device/device.h: RM_REGION_OWNED): spans[first .. first + count) all lie in
 * the region, in ray order. */
typedef struct rm_span_run {
  rm_u32 first;
  rm_u32 count;
} rm_span_run;

/* All samples of a batch that fell into one voxel: hit_rays[first .. first + count) are their ray
 * indices, in ray order, so folding them one after another gives the same voxel mean as the CPU
 * reference, bit for bit. */
typedef struct rm_hit_group {
  rm_u32 slot;  /* device cache slot of the region */
  rm_u32 index; /* voxel index inside the region */
  rm_u32 first; /* first entry in the hit-ray list */
  rm_u32 count; /* number of samples */
} rm_hit_group;

/* Launch parameters of the occupancy kernels. per_scan, has_traversal, has_tsdf and
 * has_occupancy describe the map for the host, which picks the kernels made for its mode from them
 * (map_mode.h: rm_map_mode_bits); the kernels themselves test RM_MAP_MODE, not these. */
typedef struct rm_integrate_params {
  rm_occupancy_params occupancy;
  rm_i32 region_voxels;     /* voxels per region edge */
  rm_u32 voxels_per_region; /* region_voxels^3 */
  rm_u32 item_count;        /* spans or hit groups in this launch */
  rm_u32 group_count;       /* hit groups in the batch (scratch layout, per-ray semantics) */
  rm_u32 per_scan;          /* 1: per-scan semantics (scan marks), 0: per-ray */
  rm_u32 sequence;          /* scan sequence (per-scan semantics) */
  rm_u32 has_mean;          /* 1 when the map keeps the voxel-mean layer */
  rm_u32 has_traversal;     /* 1 when the map keeps the traversal layer (decay rate, decay.h) */
  float resolution;         /* voxel edge, metres (path lengths in the traversal layer) */
  rm_u32 has_tsdf;          /* 1 for TSDF maps: spans update the TSDF layer only (tsdf.h) */
  rm_tsdf_params tsdf;      /* TSDF maps */
  rm_u32 has_occupancy;     /* 0 for maps without the occupancy layer (TSDF, decay rates only) */
} rm_integrate_params;

/* Per-ray semantics: most hit groups in one batch. The device tags a voxel with samples with its
 * group number in 22 bits (kernels/device/integrate_occupancy.h), so the host never plans more
 * rays per per-ray batch than this. */
#define RM_TAG_MAX_GROUPS 0x00400000u

/* Per-ray semantics: 32-bit words of batch scratch the device needs for a batch of `groups` hit
 * groups over `hits` samples: a saved value per group, and count + 1 runs of misses per group. */
#define RM_SCRATCH_WORDS(groups, hits) (2u * (groups) + (hits))

/* Device counters of one batch: RM_COUNTER_BUCKETS buckets of voxel visits (work-items add to
 * bucket id % RM_COUNTER_BUCKETS, so no single word is contended) and the updates given up. */
#define RM_COUNTER_BUCKETS 64u
#define RM_COUNTER_DROPPED RM_COUNTER_BUCKETS
#define RM_COUNTER_COUNT (RM_COUNTER_BUCKETS + 1u)

#endif /* RAYMAP_KERNELS_COMMON_BATCH_H */
