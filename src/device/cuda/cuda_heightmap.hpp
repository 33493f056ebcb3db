// SPDX-License-Identifier: BSD-3-Clause
// Height maps on a CUDA device: the kernels of kernels/device/heightmap_kernels.h.
#pragma once
#include <memory>

#include "raymap/error.hpp"

#include "src/heightmap/heightmap_generator.hpp"
#include "src/map/backend.hpp"

namespace raymap {

/// @brief Which device, and the launch shape.
struct CudaHeightmapOptions {
  int device = 0;                ///< CUDA device ordinal
  unsigned block_threads = 128;  ///< threads per block, a multiple of 32
};

/// @brief Creates a CUDA height-map generator. generate() uploads the occupancy (and voxel-mean)
/// layer of every map region under the box, runs one thread per column (flood fill: one launch
/// per ring, in order on one stream) and copies the layers back; it produces the same height map
/// as the CPU generator. Device buffers grow to the largest request seen and are reused.
/// Errors: no driver or device ("no CUDA driver: ..."), allocation refused.
/// Thread-safety: one thread at a time.
Result<std::unique_ptr<heightmap::HeightmapGenerator>> createCudaHeightmapGenerator(
    const CudaHeightmapOptions& options);

/// @brief Creates a CUDA height-map generator on the device and stream of `backend`, a CUDA
/// integration backend (which must outlive it), for the map that backend integrates into: its
/// kernels run on the backend's stream after the batches integrated so far and read the
/// occupancy, voxel-mean and NDT layers where integration left them (device region cache, or
/// the host pool mapped into the device), through a table of each region's slot. Only that
/// table, the plan's region table and the output layers are copied; no Backend::synchronise() is
/// needed before generate() (readsHostStore() is false). When the regions under the box do not
/// fit the device cache at once, generate() synchronises the backend and uploads them as the
/// standalone generator does. Errors: `backend` is not a CUDA backend; `block_threads` is not a
/// multiple of 32. Thread-safety: as the backend's; generate() must not run concurrently with
/// its integrate().
Result<std::unique_ptr<heightmap::HeightmapGenerator>> createCudaHeightmapGenerator(
    Backend& backend, unsigned block_threads = 128);

}  // namespace raymap
