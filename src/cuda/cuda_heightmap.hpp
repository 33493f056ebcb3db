// SPDX-License-Identifier: BSD-3-Clause
// Height maps on a CUDA device: the kernels of kernels/device/heightmap_kernels.h.
#pragma once
#include <memory>

#include "src/core/error.hpp"
#include "src/heightmap/heightmap_generator.hpp"

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

}  // namespace raymap
