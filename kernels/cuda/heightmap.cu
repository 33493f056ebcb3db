// SPDX-License-Identifier: BSD-3-Clause
// CUDA height-map kernels (kernels/device/heightmap_kernels.h, shared with OpenCL) and their host
// launchers (kernels/cuda/heightmap_launch.h).
#include "kernels/cuda/heightmap_launch.h"
#include "kernels/device/heightmap_kernels.h"

namespace raymap::cuda {

cudaError_t launchHeightmapMasks(cudaStream_t stream, unsigned block_threads,
                                 const HeightmapKernelBuffers& b, const rm_heightmap_params& params,
                                 std::uint32_t region_count) noexcept {
  const auto plane = static_cast<unsigned>(params.region_voxels * params.region_voxels);
  const unsigned items = region_count * plane;
  if (items == 0) {
    return cudaSuccess;
  }
  const unsigned blocks = (items + block_threads - 1) / block_threads;
  rm_heightmap_masks<<<blocks, block_threads, 0, stream>>>(params, b.region_slots, b.occupancy,
                                                           b.masks, region_count);
  return cudaGetLastError();
}

cudaError_t launchHeightmapPlanar(cudaStream_t stream, unsigned block_threads,
                                  const HeightmapKernelBuffers& b,
                                  const rm_heightmap_params& params) noexcept {
  const auto items = static_cast<unsigned>(params.cells_x) * static_cast<unsigned>(params.cells_y);
  if (items == 0) {
    return cudaSuccess;
  }
  const unsigned blocks = (items + block_threads - 1) / block_threads;
  rm_heightmap_planar<<<blocks, block_threads, 0, stream>>>(
      params, b.table, b.region_slots, b.masks, b.mean, b.ndt, b.elevation, b.clearance, b.kind,
      b.samples, b.reference, b.normal_x, b.normal_y, b.normal_z);
  return cudaGetLastError();
}

cudaError_t launchHeightmapFillRing(cudaStream_t stream, unsigned block_threads,
                                    const HeightmapKernelBuffers& b,
                                    const rm_heightmap_params& params, int ring) noexcept {
  const unsigned items = rm_hm_ring_size(ring);
  const unsigned blocks = (items + block_threads - 1) / block_threads;
  rm_heightmap_fill_ring<<<blocks, block_threads, 0, stream>>>(
      params, b.table, b.region_slots, b.masks, b.mean, b.ndt, b.elevation, b.clearance, b.kind,
      b.samples, b.reference, b.normal_x, b.normal_y, b.normal_z, ring);
  return cudaGetLastError();
}

}  // namespace raymap::cuda
