// SPDX-License-Identifier: BSD-3-Clause
// The CUDA backend: occupancy integration on an NVIDIA GPU (Jetson Orin, x86 GPUs) with the same
// kernels as OpenCL, a preallocated device region cache and double-buffered batches.
#pragma once

#include <memory>

#include "raymap/error.hpp"

#include "src/device/staging/device_options.hpp"
#include "src/device/staging/staged_backend.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

struct CUstream_st;  // cudaStream_t, without the CUDA headers

namespace raymap {

/// @brief Options of the CUDA backend: the shared device options (memory, cache, batches) and
/// the CUDA ones.
struct CudaBackendOptions : DeviceBackendOptions {
  int device = -1;               ///< CUDA device ordinal (after CUDA_VISIBLE_DEVICES); -1: device 0
  unsigned block_threads = 256;  ///< threads per block of the integration kernels
  /// Tests and benchmarks: let DeviceMemory::kShared map the host store into a discrete GPU too
  /// (page-locked, every access across the bus), so that a workstation GPU runs the code path of
  /// a Jetson, whose GPU shares the host's memory. Never faster on a discrete GPU.
  bool map_host_memory_on_discrete = false;
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

namespace cuda {

/// @brief What a CUDA backend lends to other kernels on its device: the height-map generator
/// reads the map's layers where integration left them (device region cache, or the host pool
/// mapped into the device) instead of through the host store.
/// Thread-safety: as the backend's (one thread at a time, under the map's lock in raymapd).
class BackendDevice {
 public:
  virtual ~BackendDevice() = default;
  /// The device ordinal and the backend's one stream (work on it runs after the batches).
  virtual int deviceIndex() const noexcept = 0;
  virtual CUstream_st* stream() const noexcept = 0;
  /// Device address of map layer `layer` (a placeholder for -1): the layout of the host store,
  /// one region per slot.
  virtual const void* layerPointer(int layer) const noexcept = 0;
  /// The batch loop: placeForRead(), synchronise().
  virtual gpu::StagedBackend& staged() noexcept = 0;
};

/// @brief `backend` as a CUDA backend, or nullptr when it is another kind.
BackendDevice* backendDevice(Backend& backend) noexcept;

}  // namespace cuda
}  // namespace raymap
