// SPDX-License-Identifier: BSD-3-Clause
// CUDA build of the NDT-OM / NDT-TM kernels: the entry points of
// kernels/device/integrate_ndt_kernels.h (the OpenCL program compiles the same header) and their
// host launcher. Compiled with --fmad=false: the host walks the same spans in IEEE float without
// fused multiply-add, and a contracted a * b + c could move a region crossing.
#include "kernels/cuda/ndt_launch.h"
#include "kernels/device/integrate_ndt_kernels.h"

namespace raymap::cuda {

cudaError_t launchNdtKernel(NdtKernelId kernel, std::uint32_t mode, cudaStream_t stream,
                            unsigned block_threads, const NdtKernelBuffers& b,
                            const rm_integrate_params& params,
                            const rm_ndt_params& ndt_params) noexcept {
  if (params.item_count == 0 || block_threads == 0) {
    return cudaSuccess;
  }
  const unsigned blocks = (params.item_count + block_threads - 1) / block_threads;
  switch (kernel) {
    case NdtKernelId::kIntegrateSpans:
      switch (mode) {
#define RM_LAUNCH_MODE_(bits)                                                                \
  case (bits):                                                                               \
    rm_ndt_integrate_spans<(bits)>                                                           \
        <<<blocks, block_threads, 0, stream>>>(b.rays, b.spans, b.occupancy, b.ndt, b.means, \
                                               reinterpret_cast<std::uint32_t*>(b.hit_miss), \
                                               b.traversal, params, ndt_params, b.counters); \
    break;
        RM_NDT_PROGRAM_MODES(RM_LAUNCH_MODE_)
#undef RM_LAUNCH_MODE_
        default:
          return cudaErrorInvalidValue;  // no kernel for this mode (rm_map_mode_has_kernels)
      }
      break;
    case NdtKernelId::kApplyHitGroups:
      rm_ndt_apply_hit_groups<<<blocks, block_threads, 0, stream>>>(
          b.rays, b.groups, b.hit_rays, b.occupancy, b.ndt, b.hit_miss, b.intensity, b.means,
          params, ndt_params, b.counters);
      break;
  }
  return cudaGetLastError();
}

}  // namespace raymap::cuda
