/* SPDX-License-Identifier: BSD-3-Clause */
/* A map's mode as the device kernels see it: the features that change what a span's walk does
 * at each voxel, one bit each. The host turns a map's layers and semantics into these bits
 * (rm_map_mode_bits) and runs the kernels made for exactly that mode: OpenCL builds its program
 * with -DRM_MAP_MODE=<bits>, CUDA instantiates each kernel once per mode of the lists below and
 * launches the one for the map's bits. A kernel so carries no branch, argument use or register
 * for a mode it is not: the per-mode rules sit in one span kernel (kernels/device), and
 * RM_MAP_MODE_HAS folds each of their `if`s to a constant.
 *
 * What is not a mode bit: layer presence that only the per-voxel hit kernels read once per hit
 * group (the voxel mean), and NDT-TM's counts (rm_ndt_params.traversability): both stay launch
 * parameters.
 *
 * Adding a map mode: a bit here if its span update differs from every existing one, its entry in
 * the lists below, its rule in the span kernel under `RM_MAP_MODE_HAS(bit)`, and the host's
 * rm_map_mode_bits input (docs/architecture.md, "Adding a map mode"). */
#ifndef RAYMAP_KERNELS_COMMON_MAP_MODE_H
#define RAYMAP_KERNELS_COMMON_MAP_MODE_H

#include "portable.h"

#define RM_MODE_OCCUPANCY 1u /* log-odds occupancy: misses lower it, hits raise it */
#define RM_MODE_PER_SCAN 2u  /* occupancy once per voxel and scan, occupied wins (scan marks) */
#define RM_MODE_TRAVERSAL 4u /* decay rates: each span adds its metres of path per voxel */
#define RM_MODE_TSDF 8u      /* a truncated signed distance field, the only layer rays update */
#define RM_MODE_NDT 16u      /* NDT-OM/TM: misses shaped by each voxel's Gaussian (NDT program) */

/* The modes the occupancy program (integrate_occupancy.h) has kernels for, as X(bits) entries:
 * occupancy per ray and per scan, each with or without decay rates; decay rates alone; TSDF. */
#define RM_OCCUPANCY_PROGRAM_MODES(X)                         \
  X(RM_MODE_OCCUPANCY)                                        \
  X(RM_MODE_OCCUPANCY | RM_MODE_PER_SCAN)                     \
  X(RM_MODE_OCCUPANCY | RM_MODE_TRAVERSAL)                    \
  X(RM_MODE_OCCUPANCY | RM_MODE_PER_SCAN | RM_MODE_TRAVERSAL) \
  X(RM_MODE_TRAVERSAL)                                        \
  X(RM_MODE_TSDF)

/* The modes the NDT program (integrate_ndt.h) has kernels for: NDT-OM/TM with or without decay
 * rates (NDT is per-ray only). */
#define RM_NDT_PROGRAM_MODES(X)      \
  X(RM_MODE_NDT | RM_MODE_OCCUPANCY) \
  X(RM_MODE_NDT | RM_MODE_OCCUPANCY | RM_MODE_TRAVERSAL)

/* The mode bits of a map: which of its layers rays update and how (per_scan, has_* as in
 * rm_integrate_params; ndt: an NDT-OM or NDT-TM map). */
RAYMAP_FN rm_u32 rm_map_mode_bits(rm_u32 has_occupancy, rm_u32 per_scan, rm_u32 has_traversal,
                                  rm_u32 has_tsdf, rm_u32 ndt) {
  rm_u32 bits = 0u;
  bits |= has_occupancy != 0u ? RM_MODE_OCCUPANCY : 0u;
  bits |= per_scan != 0u ? RM_MODE_PER_SCAN : 0u;
  bits |= has_traversal != 0u ? RM_MODE_TRAVERSAL : 0u;
  bits |= has_tsdf != 0u ? RM_MODE_TSDF : 0u;
  bits |= ndt != 0u ? RM_MODE_NDT : 0u;
  return bits;
}

#define RM_MAP_MODE_IS_(bits) || mode == (bits)

/* 1 when a device program has kernels for mode `mode` (one of the lists above). */
RAYMAP_FN int rm_map_mode_has_kernels(rm_u32 mode) {
  return 0 RM_OCCUPANCY_PROGRAM_MODES(RM_MAP_MODE_IS_) RM_NDT_PROGRAM_MODES(RM_MAP_MODE_IS_);
}

#undef RM_MAP_MODE_IS_

/* Inside a kernel made for one mode (RM_MAP_MODE: a -D of the OpenCL build, a template parameter
 * in CUDA): whether that mode has `bit`, a constant the compiler folds. */
#define RM_MAP_MODE_HAS(bit) ((RM_MAP_MODE & (bit)) != 0u)

#endif /* RAYMAP_KERNELS_COMMON_MAP_MODE_H */
