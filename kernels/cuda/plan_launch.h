// SPDX-License-Identifier: BSD-3-Clause
// Host launcher of the device planner's kernels (kernels/cuda/plan.cu, compiled by nvcc), callable
// from host C++ built by the ordinary compiler. Plain device pointers and the ABI structs of
// kernels/common/plan_abi.h cross this boundary, nothing else.
#pragma once

#include <cstdint>

#include <cuda_runtime_api.h>

#include "kernels/common/plan_abi.h"

namespace raymap::cuda {

/// @brief Enqueues planning kernel number `kernel` (the order of RM_PLAN_KERNELS, as
/// gpu::PlanKernel) on `stream` over `items` threads in blocks of RM_PLAN_GROUP, with `args` and
/// RM_PLAN_BUFFERS device buffers (nullptr where the kernel takes none); returns the launch
/// status. Real-time: allocates nothing; does not wait for the kernel.
cudaError_t launchPlanKernel(unsigned kernel, cudaStream_t stream, std::uint32_t items,
                             const rm_plan_args& args,
                             std::uint32_t* const (&buffers)[RM_PLAN_BUFFERS]) noexcept;

}  // namespace raymap::cuda
