/* SPDX-License-Identifier: BSD-3-Clause */
/* Per-scan semantics: each voxel is updated at most once per scan, and occupied wins (OctoMap's
 * insertPointCloud). The device backends elect the one update with these marks; the CPU backend
 * keeps the same rule with one bit per voxel and batch instead (src/map/scan_bits.hpp: no atomics
 * there, and a 32-bit mark beside every occupancy value cost it memory).
 *
 * A scratch layer keeps one 32-bit mark per voxel: (scan_sequence << 1) | hit. Scan sequences start
 * at 1 and only grow, so marks from earlier scans compare lower than any mark of the current scan
 * and no clearing is needed between scans (marks are monotone, which also suits atomic_max on
 * devices). A scan first applies its hits (marking them), then walks its rays and applies a miss to
 * each voxel not yet marked in this scan. */
#ifndef RAYMAP_KERNELS_COMMON_SCAN_MARK_H
#define RAYMAP_KERNELS_COMMON_SCAN_MARK_H

#include "portable.h"

/* Largest usable scan sequence; the map resets all marks and restarts at 1 beyond it. */
#define RM_SCAN_SEQUENCE_MAX 0x7FFFFFFFu

RAYMAP_FN rm_u32 rm_scan_mark_hit(rm_u32 sequence) { return (sequence << 1) | 1u; }

RAYMAP_FN rm_u32 rm_scan_mark_miss(rm_u32 sequence) { return sequence << 1; }

/* True when the voxel has had no hit yet in this scan. */
RAYMAP_FN int rm_scan_needs_hit(rm_u32 mark, rm_u32 sequence) {
  return mark < rm_scan_mark_hit(sequence);
}

/* True when the voxel has had neither a hit nor a miss in this scan. */
RAYMAP_FN int rm_scan_needs_miss(rm_u32 mark, rm_u32 sequence) {
  return mark < rm_scan_mark_miss(sequence);
}

#endif /* RAYMAP_KERNELS_COMMON_SCAN_MARK_H */
