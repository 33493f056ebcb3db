// SPDX-License-Identifier: BSD-3-Clause
// The CPU backend: a single-threaded reference and a multi-threaded path over the same code.
#pragma once

#include <cstddef>
#include <memory>

#include "raymap/error.hpp"

#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief Options of the CPU backend.
struct CpuBackendOptions {
  static constexpr unsigned kMaxThreads = 64;
  /// Worker threads: 1 = the single-threaded reference, 0 = one per available core.
  unsigned threads = 1;
  /// Rays per integrate() call the multi-threaded scratch is sized for (larger batches grow it);
  /// 0: the backend's preferredBatchRays(), the batch a caller gets when it leaves the size to it.
  std::size_t expected_batch_rays = 0;
};

/// @brief Creates a CPU backend integrating into `map` (which must outlive it).
///
/// Both paths split every ray into its per-region spans (RayRegionWalk) and walk each span's voxels
/// with the shared line walk. The single-threaded path (src/map/cpu_serial.hpp) does this ray by
/// ray. The multi-threaded path (src/map/cpu_parallel.hpp) records every ray's spans once, gives
/// each region of the batch to one worker, and lets every worker update only the spans in its own
/// regions, in ray order. No voxel is ever written by two threads and no atomics are needed;
/// because each voxel sees its updates in ray order, the map is bit-identical to the
/// single-threaded one for any thread count.
///
/// Thread-safety: integrate() must not be called concurrently; the map must not be touched by
/// others during a call. Store full: the single-threaded path stops at the first region it cannot
/// create (the batch is partly integrated); the multi-threaded path fails before any update.
Result<std::unique_ptr<Backend>> createCpuBackend(VoxelMap& map, const CpuBackendOptions& options);

}  // namespace raymap
