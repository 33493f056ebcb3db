// SPDX-License-Identifier: BSD-3-Clause
// The OpenCL backend: occupancy integration on an OpenCL 1.2 device with a preallocated device
// region cache and double-buffered batches.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "src/core/error.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"
#include "src/opencl/cl_runtime.hpp"
#include "src/opencl/program_cache.hpp"

namespace raymap {

/// Where the device keeps the map while it integrates.
enum class DeviceMemory : std::uint8_t {
  kAuto,    ///< kShared where the device shares memory with the host and the map fits, else kCache
  kCache,   ///< a region cache in device buffers; regions are copied in and out as needed
  kShared,  ///< the host map itself (CL_MEM_USE_HOST_PTR): nothing is copied (PoCL, Intel iGPU)
};

/// @brief Options of the OpenCL backend.
struct OpenClBackendOptions {
  static constexpr std::uint64_t kDefaultCacheBytes = std::uint64_t{1} << 30;  // 1 GiB

  opencl::DeviceSelector device;  ///< platform/device by index or name substring
  DeviceMemory memory = DeviceMemory::kAuto;
  /// Device region cache size in bytes (all layers). 0: min(1 GiB, half the device's global
  /// memory, the host store); never more regions than the host store holds.
  std::uint64_t cache_bytes = 0;
  /// Device region cache size in regions; when non-zero it is used instead of cache_bytes.
  std::uint32_t cache_regions = 0;
  /// Most rays per device batch with per-scan semantics, where one integrate() call (one scan)
  /// must be one device batch for "occupied wins" to hold across the scan; larger scans are
  /// integrated in parts, each as its own scan. Staging buffers are sized for it, twice.
  std::size_t batch_rays = std::size_t{1} << 18;
  /// Most rays per device batch with per-ray semantics, where integrate() calls are cut into
  /// batches of this size: smaller batches let planning overlap the device sooner (measured on
  /// PoCL: 64 Ki rays was faster than 256 Ki; see docs/benchmarks.md).
  std::size_t per_ray_batch_rays = std::size_t{1} << 16;
  /// Use 32-bit counters even where the device has cl_khr_int64_base_atomics (tests both paths).
  bool force_32bit_atomics = false;
  opencl::ProgramCacheOptions program_cache;
  /// Appended to the kernel build options (tuning, tests).
  std::string extra_build_options;
};

/// @brief Creates an OpenCL backend integrating into `map` (which must outlive it).
///
/// Design (see docs/architecture.md, "Device backends"):
///  - At creation: picks the device, builds the embedded kernel source (binary cached on disk),
///    allocates one device buffer per map layer cut into cache slots, and two sets of batch
///    staging buffers. Nothing is allocated on the device afterwards.
///  - integrate(): the host plans a batch (coarse region walk, span records, regions moved into
///    the cache, samples grouped per voxel) while the device may still run the previous batch,
///    then enqueues the copies and kernels and returns without waiting. Regions leave the cache
///    (downloaded to the host store) only when their slot is needed and the batch being planned
///    does not use them.
///  - synchronise(): waits for the device and downloads every region changed since the last call.
///  - Shared memory (DeviceMemory::kShared, chosen automatically on devices that share memory with
///    the host when every layer of the host store fits one device allocation): the device works
///    on the host store in place; no cache, no copies, and synchronise() only waits.
///
/// Errors: creation fails with a clear message when no platform exists, the kernel does not build
/// (the build log is in the message) or the buffers cannot be allocated. integrate() returns
/// kDeviceFailure when the device reports an error; the map must then be discarded.
/// Thread-safety: none; the map must not be changed by others between integrate() and
/// synchronise(), except for rolling-window moves, which the next integrate() takes into account.
Result<std::unique_ptr<Backend>> createOpenClBackend(VoxelMap& map,
                                                     const OpenClBackendOptions& options);

}  // namespace raymap
