// SPDX-License-Identifier: BSD-3-Clause
// Host launchers of the CUDA height-map kernels (kernels/cuda/heightmap.cu), callable from host
// C++ built by the ordinary compiler. Device pointers and the kernel ABI struct of
// kernels/common/heightmap.h cross this boundary, nothing else.
#pragma once
#include <cstdint>

#include <cuda_runtime_api.h>

#include "kernels/common/heightmap.h"

namespace raymap::cuda {

/// Device buffers of one height-map generation (device pointers).
struct HeightmapKernelBuffers {
  const std::uint32_t* table = nullptr;         ///< region table: region index or RM_HM_NO_REGION
  const std::uint32_t* region_slots = nullptr;  ///< slot of each region in the uploaded layers
  const float* occupancy = nullptr;             ///< occupancy layer of the uploaded regions
  rm_hm_mask* masks = nullptr;                  ///< column masks (built by launchHeightmapMasks)
  const rm_voxel_mean* mean = nullptr;          ///< mean layer (read only with RM_HM_FLAG_MEAN)
  const rm_ndt_voxel* ndt = nullptr;            ///< NDT layer (read only with RM_HM_FLAG_NORMALS)
  float* elevation = nullptr;
  float* clearance = nullptr;
  std::uint32_t* kind = nullptr;
  std::uint32_t* samples = nullptr;
  float* reference = nullptr;
  float* normal_x = nullptr;  ///< written only with RM_HM_FLAG_NORMALS
  float* normal_y = nullptr;
  float* normal_z = nullptr;
};

/// @brief Enqueues building the column masks of `region_count` uploaded regions.
cudaError_t launchHeightmapMasks(cudaStream_t stream, unsigned block_threads,
                                 const HeightmapKernelBuffers& buffers,
                                 const rm_heightmap_params& params,
                                 std::uint32_t region_count) noexcept;

/// @brief Enqueues planar mode (one thread per cell). Real-time: allocates nothing, does not wait.
cudaError_t launchHeightmapPlanar(cudaStream_t stream, unsigned block_threads,
                                  const HeightmapKernelBuffers& buffers,
                                  const rm_heightmap_params& params) noexcept;

/// @brief Enqueues flood-fill ring `ring` (rm_hm_ring_size(ring) threads); rings must be enqueued
/// in order on one stream.
cudaError_t launchHeightmapFillRing(cudaStream_t stream, unsigned block_threads,
                                    const HeightmapKernelBuffers& buffers,
                                    const rm_heightmap_params& params, int ring) noexcept;

}  // namespace raymap::cuda
