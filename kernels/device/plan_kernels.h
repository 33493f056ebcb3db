/* SPDX-License-Identifier: BSD-3-Clause */
/* The entry points of the device planner (plan.h) and of its scans and sorts (scan.h), written once
 * for OpenCL C 1.2 and CUDA: kernels/opencl/plan.cl and kernels/cuda/plan.cu are this header and
 * nothing more (plus, in CUDA, the host launcher). Every entry point takes the launch arguments
 * and RM_PLAN_BUFFERS generic word buffers, read as the types each names below, so the host binds
 * them all one way (src/device/staging/device_planner.hpp says which buffer goes where). They run
 * in work-groups of RM_PLAN_GROUP; the host rounds work-items up to whole groups, so each checks
 * its index. */
#ifndef RAYMAP_KERNELS_DEVICE_PLAN_KERNELS_H
#define RAYMAP_KERNELS_DEVICE_PLAN_KERNELS_H

#include "plan.h"
#include "scan.h"

/* b0 status */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_begin(RM_PLAN_PARAMS) {
  rm_plan_begin_status(rm_global_id(), b0);
}

/* b0 rays, b1 counts (n + 1), b2 regions crossed */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_count(RM_PLAN_PARAMS) {
  rm_plan_count_ray(rm_global_id(), args, (const RM_GLOBAL rm_prepared_ray*)b0, b1, b2);
}

/* b0 offsets, b1 regions crossed, b2 status */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_cut(RM_PLAN_PARAMS) {
  rm_plan_cut_ray(rm_global_id(), args, b0, b1, (RM_ATOMIC_GLOBAL rm_u32*)b2);
}

/* b0 rays, b1 counts (unused), b2 offsets, b3 spans, b4 region table, b5 hit keys, b6 hit rays,
 * b7 status */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_emit(RM_PLAN_PARAMS) {
  rm_plan_emit_ray(rm_global_id(), args, (const RM_GLOBAL rm_prepared_ray*)b0, b2,
                   (RM_GLOBAL rm_span_record*)b3, (RM_ATOMIC_GLOBAL rm_u32*)b4, b5, b6,
                   (RM_ATOMIC_GLOBAL rm_u32*)b7);
}

/* b0 in, b1 out (may be b0), b2 tile sums; args.n elements */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_scan_tiles(RM_PLAN_PARAMS) {
  RM_LOCAL_ARRAY(rm_u32, partial, RM_PLAN_GROUP);
  rm_scan_tile(args.n, b0, b1, b2, partial);
}

/* b0 out, b1 scanned tile sums; args.n elements */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_scan_add(RM_PLAN_PARAMS) {
  rm_scan_add_tile(args.n, b0, b1);
}

/* b0 keys, b1 histogram; args.n, args.shift, args.tiles */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_radix_histogram(RM_PLAN_PARAMS) {
  RM_LOCAL_ARRAY(rm_u32, counts, RM_RADIX_BUCKETS);
  rm_radix_histogram_tile(args.n, args.shift, args.tiles, b0, b1, counts);
}

/* b0 keys in, b1 values in, b2 scanned histogram, b3 keys out, b4 values out */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_radix_scatter(RM_PLAN_PARAMS) {
  RM_LOCAL_ARRAY(rm_u32, flat, RM_RADIX_BUCKETS * RM_PLAN_GROUP);
  RM_LOCAL_ARRAY(rm_u32, partial, RM_PLAN_GROUP);
  rm_radix_scatter_tile(args.n, args.shift, args.tiles, b0, b1, b2, b3, b4, flat, partial);
}

/* b0 sorted hit keys, b1 heads (n + 1) */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_group_heads(RM_PLAN_PARAMS) {
  rm_plan_group_head(rm_global_id(), args.n, b0, b1);
}

/* b0 sorted hit keys, b1 sorted rays, b2 heads, b3 group index, b4 groups, b5 hit-ray list */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_group_build(RM_PLAN_PARAMS) {
  rm_plan_group_build_item(rm_global_id(), args, b0, b1, b2, b3, (RM_GLOBAL rm_hit_group*)b4, b5);
}

/* b0 region table, b1 spans, b2 region records, b3 status */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_compact(RM_PLAN_PARAMS) {
  rm_plan_compact_entry(rm_global_id(), args, b0, (const RM_GLOBAL rm_span_record*)b1,
                        (RM_GLOBAL rm_plan_region*)b2, (RM_ATOMIC_GLOBAL rm_u32*)b3);
}

/* b0 offsets, b1 group index, b2 status */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_finish(RM_PLAN_PARAMS) {
  rm_plan_finish_status(rm_global_id(), args, b0, b1, b2);
}

/* b0 region records, b1 resolutions, b2 entry map */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_resolve_regions(RM_PLAN_PARAMS) {
  rm_plan_resolve_region(rm_global_id(), args, (const RM_GLOBAL rm_plan_region*)b0,
                         (const RM_GLOBAL rm_plan_resolution*)b1, b2);
}

/* b0 spans, b1 entry map, b2 rank keys, b3 span indices; args.shift 1: with ranks */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_resolve_spans(RM_PLAN_PARAMS) {
  rm_plan_resolve_span(rm_global_id(), args, args.shift != 0u, (RM_GLOBAL rm_span_record*)b0, b1,
                       b2, b3);
}

/* b0 groups, b1 entry map */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_resolve_groups(RM_PLAN_PARAMS) {
  rm_plan_resolve_group(rm_global_id(), args, (RM_GLOBAL rm_hit_group*)b0, b1);
}

/* b0 spans, b1 order, b2 region spans */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_gather_spans(RM_PLAN_PARAMS) {
  rm_plan_gather_span(rm_global_id(), args, (const RM_GLOBAL rm_span_record*)b0, b1,
                      (RM_GLOBAL rm_span_record*)b2);
}

/* b0 region records, b1 region table; args.n records */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_clear_regions(RM_PLAN_PARAMS) {
  rm_u32 k = rm_global_id();
  if (k < args.n) {
    rm_plan_clear_entry(((const RM_GLOBAL rm_plan_region*)b0)[k].entry, args.table_mask + 1u, b1);
  }
}

/* b0 region table; every entry */
RM_GROUP_KERNEL(RM_PLAN_GROUP) void rm_plan_clear_table(RM_PLAN_PARAMS) {
  rm_u32 e = rm_global_id();
  if (e <= args.table_mask) {
    rm_plan_clear_entry(e, args.table_mask + 1u, b0);
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_PLAN_KERNELS_H */
