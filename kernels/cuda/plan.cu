// SPDX-License-Identifier: BSD-3-Clause
// CUDA build of the device planner: the entry points of kernels/device/plan_kernels.h (the OpenCL
// program compiles the same header) and their host launcher. Compiled with --fmad=false: the host
// planner walks the same regions in IEEE float without fused multiply-add, and a contracted
// a * b + c could move a region crossing and give another plan.
#include "kernels/cuda/plan_launch.h"
#include "kernels/device/plan_kernels.h"
#include "kernels/device/prepare_kernels.h"

namespace raymap::cuda {
namespace {

using PlanKernelFn = void (*)(rm_plan_args, rm_u32*, rm_u32*, rm_u32*, rm_u32*, rm_u32*, rm_u32*,
                              rm_u32*, rm_u32*);

// In the order of RM_PLAN_KERNELS, then RM_PREPARE_KERNELS, which gpu::PlanKernel follows.
constexpr PlanKernelFn kPlanKernels[] = {
#define RM_PLAN_KERNEL_FN(name) &rm_plan_##name,
    RM_PLAN_KERNELS(RM_PLAN_KERNEL_FN) RM_PREPARE_KERNELS(RM_PLAN_KERNEL_FN)
#undef RM_PLAN_KERNEL_FN
};
constexpr unsigned kPlanKernelCount = sizeof(kPlanKernels) / sizeof(kPlanKernels[0]);

}  // namespace

cudaError_t launchPlanKernel(unsigned kernel, cudaStream_t stream, std::uint32_t items,
                             const rm_plan_args& args,
                             std::uint32_t* const (&b)[RM_PLAN_BUFFERS]) noexcept {
  if (kernel >= kPlanKernelCount) {
    return cudaErrorInvalidValue;
  }
  const unsigned blocks = (items + RM_PLAN_GROUP - 1) / RM_PLAN_GROUP;
  if (blocks == 0) {
    return cudaSuccess;
  }
  kPlanKernels[kernel]<<<blocks, RM_PLAN_GROUP, 0, stream>>>(args, b[0], b[1], b[2], b[3], b[4],
                                                             b[5], b[6], b[7]);
  return cudaGetLastError();
}

}  // namespace raymap::cuda
