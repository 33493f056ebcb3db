// SPDX-License-Identifier: BSD-3-Clause
// The CUDA backend: occupancy integration on an NVIDIA GPU (Jetson Orin, x86 GPUs) with the same
// kernels as OpenCL, a preallocated device region cache and double-buffered batches.
#pragma once

#include <memory>

#include "src/core/error.hpp"
#include "src/gpu/device_options.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief Options of the CUDA backend: the shared device options (memory, cache, batches) and
/// the CUDA ones.
struct CudaBackendOptions : DeviceBackendOptions {
  int device = -1;               ///< CUDA device ordinal (after CUDA_VISIBLE_DEVICES); -1: device 0
  unsigned block_threads = 256;  ///< threads per block of the integration kernels
};

/// @brief Creates a CUDA backend integrating into `map` (which must outlive it).
///
/// Design (see docs/architecture.md, "Device backends"; the batch loop is gpu::StagedBackend's):
///  - At creation: picks the device, allocates one cudaMalloc buffer per map layer cut into
///    cache slots (cleared on the device), two sets of device batch buffers and their host arrays
///    in page-locked memory (so batch copies are asynchronous DMA), and creates one non-blocking
///    stream and one event per batch. Nothing is allocated afterwards. No managed memory.
///  - integrate(): plans a batch on the host while the stream may still run the previous one,
///    enqueues copies and kernels on the stream and returns without waiting.
///  - synchronise(): waits for the stream and downloads every region changed since the last call.
///  - Shared memory (DeviceMemory::kShared; chosen automatically on integrated GPUs such as
///    Jetson when the map fits): the host region store is page-locked and mapped into the device
///    (cudaHostRegisterMapped), and the kernels work on it in place: no cache, no copies, no
///    second copy of the map. This page-locks the whole region pool (--max-memory) at start-up.
///
/// Errors: creation fails with a clear message when the NVIDIA driver or a device is missing, the
/// device ordinal does not exist, or memory cannot be allocated. integrate() returns
/// kDeviceFailure when the device reports an error; the map must then be discarded.
/// Thread-safety: none; calls may come from any one thread at a time (the backend makes its
/// device current on each call). The map must not be changed by others between integrate() and
/// synchronise(), except for rolling-window moves, which the next integrate() takes into account.
Result<std::unique_ptr<Backend>> createCudaBackend(VoxelMap& map,
                                                   const CudaBackendOptions& options);

}  // namespace raymap
