// SPDX-License-Identifier: BSD-3-Clause
// CUDA build of the occupancy kernels: the entry points of
// kernels/device/integrate_occupancy_kernels.h (the OpenCL program compiles the same header) and
// their host launchers. Compiled with --fmad=false: the host walks the same spans in IEEE float
// without fused multiply-add, and a contracted a * b + c could move a region crossing.
#include "kernels/cuda/launch.h"
#include "kernels/device/integrate_occupancy_kernels.h"

namespace raymap::cuda {
namespace {

// The launch of `kernel` made for map mode `kMode` (kernels/common/map_mode.h).
template <std::uint32_t kMode>
void launchFor(OccupancyKernelId kernel, cudaStream_t stream, unsigned blocks,
               unsigned block_threads, const OccupancyKernelBuffers& b,
               const rm_integrate_params& params) noexcept {
  switch (kernel) {
    case OccupancyKernelId::kTagHitGroups:
      rm_tag_hit_groups<<<blocks, block_threads, 0, stream>>>(b.groups, b.occupancy, b.scratch,
                                                              params);
      break;
    case OccupancyKernelId::kIntegrateSpans:
      rm_integrate_spans<kMode><<<blocks, block_threads, 0, stream>>>(
          b.rays, b.spans, b.groups, b.hit_rays, b.occupancy, b.marks, b.scratch, b.traversal,
          b.tsdf, params, b.counters);
      break;
    case OccupancyKernelId::kApplyHitGroups:
      rm_apply_hit_groups<kMode>
          <<<blocks, block_threads, 0, stream>>>(b.rays, b.groups, b.hit_rays, b.occupancy, b.means,
                                                 b.marks, b.scratch, params, b.counters);
      break;
  }
}

}  // namespace

cudaError_t launchOccupancyKernel(OccupancyKernelId kernel, std::uint32_t mode, cudaStream_t stream,
                                  unsigned block_threads, const OccupancyKernelBuffers& b,
                                  const rm_integrate_params& params) noexcept {
  if (params.item_count == 0 || block_threads == 0) {
    return cudaSuccess;
  }
  const unsigned blocks = (params.item_count + block_threads - 1) / block_threads;
  switch (mode) {
#define RM_LAUNCH_MODE_(bits)                                            \
  case (bits):                                                           \
    launchFor<(bits)>(kernel, stream, blocks, block_threads, b, params); \
    break;
    RM_OCCUPANCY_PROGRAM_MODES(RM_LAUNCH_MODE_)
#undef RM_LAUNCH_MODE_
    default:
      return cudaErrorInvalidValue;  // no kernel for this mode (rm_map_mode_has_kernels)
  }
  return cudaGetLastError();
}

}  // namespace raymap::cuda
