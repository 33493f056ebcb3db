// SPDX-License-Identifier: BSD-3-Clause
// Host launchers of the CUDA kernels (defined in the .cu files beside this header, compiled by
// nvcc), callable from host C++ built by the ordinary compiler: the CUDA backend's .cpp files
// never need nvcc's <<<>>> syntax. Plain pointers and the device ABI structs of
// kernels/common/batch.h cross this boundary, nothing else.
#pragma once

#include <cstddef>
#include <cstdint>

#include <cuda_runtime_api.h>

#include "kernels/common/batch.h"
#include "kernels/common/ray.h"
#include "kernels/common/voxel_mean.h"

namespace raymap::cuda {

/// Device buffers of one batch and the map layers the kernels update (device pointers). Absent
/// layers (no voxel mean, per-ray semantics without scan marks, no traversal or TSDF layer, no
/// occupancy in TSDF maps) point at a
/// small placeholder.
struct OccupancyKernelBuffers {
  const rm_prepared_ray* rays = nullptr;
  const rm_span_record* spans = nullptr;
  const rm_hit_group* groups = nullptr;
  const std::uint32_t* hit_rays = nullptr;
  std::uint32_t* occupancy = nullptr;
  rm_voxel_mean* means = nullptr;
  std::uint32_t* marks = nullptr;
  std::uint32_t* scratch = nullptr;
  std::uint32_t* traversal = nullptr;      // decay rate: float metres, added as bits
  std::uint32_t* tsdf = nullptr;           // TSDF: (distance, weight) float pairs as bits
  unsigned long long* counters = nullptr;  // RM_COUNTER_COUNT 64-bit words
};

/// Which kernel to launch (the names of kernels/device/integrate_occupancy_kernels.h).
enum class OccupancyKernelId : std::uint8_t { kTagHitGroups, kIntegrateSpans, kApplyHitGroups };

/// @brief Enqueues `kernel` on `stream` over params.item_count threads in blocks of
/// `block_threads`, the kernel made for map mode `mode` (rm_map_mode_bits,
/// kernels/common/map_mode.h); returns the launch status (cudaSuccess, or why the launch was
/// refused: cudaErrorInvalidValue for a mode without kernels).
/// Real-time: allocates nothing; does not wait for the kernel.
cudaError_t launchOccupancyKernel(OccupancyKernelId kernel, std::uint32_t mode, cudaStream_t stream,
                                  unsigned block_threads, const OccupancyKernelBuffers& buffers,
                                  const rm_integrate_params& params) noexcept;

/// A voxel's clear value: up to 16 words (LayerSpec::kMaxWordsPerVoxel), passed by value.
struct FillPattern {
  std::uint32_t words[16] = {};
  unsigned count = 1;  ///< words per voxel, 1 to 16
};

/// @brief Enqueues setting `words` 32-bit words from `dst` (device memory) on to `pattern`
/// repeated; `words` is a multiple of pattern.count. Real-time: allocates nothing.
cudaError_t launchFill(cudaStream_t stream, std::uint32_t* dst, std::size_t words,
                       const FillPattern& pattern) noexcept;

}  // namespace raymap::cuda
