// SPDX-License-Identifier: BSD-3-Clause
// Host launchers of the CUDA NDT-OM / NDT-TM kernels (kernels/cuda/integrate_ndt.cu), callable
// from host C++ built by the ordinary compiler. Device pointers and the kernel ABI structs of
// kernels/common/batch.h and kernels/common/ndt.h cross this boundary, nothing else.
#pragma once

#include <cstdint>

#include <cuda_runtime_api.h>

#include "kernels/common/batch.h"
#include "kernels/common/ndt.h"
#include "kernels/common/ray.h"
#include "kernels/common/voxel_mean.h"

namespace raymap::cuda {

/// Device buffers of one batch and the map layers the NDT kernels update (device pointers).
/// Absent layers (NDT-TM's counts and intensity in an NDT-OM map, the voxel mean, the traversal
/// layer) point at a placeholder the kernels never touch.
struct NdtKernelBuffers {
  const rm_prepared_ray* rays = nullptr;
  const rm_span_record* spans = nullptr;
  const rm_hit_group* groups = nullptr;
  const std::uint32_t* hit_rays = nullptr;
  std::uint32_t* occupancy = nullptr;  ///< float log-odds, read and written as bits
  rm_ndt_voxel* ndt = nullptr;
  rm_ndt_hit_miss* hit_miss = nullptr;
  rm_ndt_intensity* intensity = nullptr;
  rm_voxel_mean* means = nullptr;
  std::uint32_t* traversal = nullptr;      ///< decay rate: float metres, added as bits
  unsigned long long* counters = nullptr;  ///< RM_COUNTER_COUNT 64-bit words
};

/// Which NDT kernel to launch (the names of kernels/device/integrate_ndt_kernels.h).
enum class NdtKernelId : std::uint8_t { kIntegrateSpans, kApplyHitGroups };

/// @brief Enqueues `kernel` on `stream` over params.item_count threads in blocks of
/// `block_threads`, the span kernel made for map mode `mode` (rm_map_mode_bits,
/// kernels/common/map_mode.h); returns the launch status (cudaErrorInvalidValue for a mode
/// without kernels). Real-time: allocates nothing; does not wait.
cudaError_t launchNdtKernel(NdtKernelId kernel, std::uint32_t mode, cudaStream_t stream,
                            unsigned block_threads, const NdtKernelBuffers& buffers,
                            const rm_integrate_params& params,
                            const rm_ndt_params& ndt_params) noexcept;

}  // namespace raymap::cuda
