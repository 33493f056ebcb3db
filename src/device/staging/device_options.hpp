// SPDX-License-Identifier: BSD-3-Clause
// Options every device backend (OpenCL, CUDA) shares, and the sizing rules derived from them:
// device region cache slots, shared memory or not, batch limits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "raymap/error.hpp"

#include "src/device/staging/batch_plan.hpp"
#include "src/device/staging/device_planner.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// Where the device keeps the map while it integrates.
enum class DeviceMemory : std::uint8_t {
  kAuto,    ///< kShared where the device shares memory with the host and the map fits, else kCache
  kCache,   ///< a region cache in device memory; regions are copied in and out as needed
  kShared,  ///< the host map itself, mapped into the device: nothing is copied (PoCL, Intel iGPU,
            ///< Jetson)
};

/// @brief Options of any device backend (value type; the API-specific options embed it).
struct DeviceBackendOptions {
  static constexpr std::uint64_t kDefaultCacheBytes = std::uint64_t{1} << 30;  // 1 GiB

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
  /// Where batches are planned (the region walk of every ray, span records, hit groups): on the
  /// host, or on the device, where the host only places each batch's distinct regions
  /// (docs/architecture.md, "Planning on the device"). The maps are the same either way.
  gpu::Planning planning = gpu::Planning::kHost;
  /// With planning on the device: prepare the rays there too (range limits, clipping, the exact
  /// voxel keys and their counters; Backend::integrateRays), where the device has double
  /// precision (OpenCL: cl_khr_fp64), the map is not NDT and the ray filter has no segmentation;
  /// the host prepares otherwise. The maps and counters are the same either way. false: the host
  /// always prepares (for measuring the two apart).
  bool prepare_on_device = true;
  /// Host staging memory for region moves in and out of the device cache (page-locked on CUDA),
  /// bytes; 0: 64 MiB. Never less than four regions. A batch that moves more than it holds waits
  /// for the device (BackendStats::transfer_stalls).
  std::uint64_t transfer_staging_bytes = 0;
};

namespace gpu {

/// @brief What the sizing rules need to know about a device (filled by the API layer).
struct DeviceMemoryLimits {
  std::string device_name;
  std::uint64_t global_mem_bytes = 0;
  std::uint64_t max_alloc_bytes = 0;  ///< largest single allocation
  bool unified_memory = false;        ///< the device works on host memory without copies
  /// The device can address host memory in place (OpenCL: always; CUDA: mapped pinned memory).
  bool can_map_host_memory = true;
};

/// @brief Checks the batch sizes; `api` ("OpenCL", "CUDA") names the backend in the message.
Expected<void, Error> checkBatchOptions(const DeviceBackendOptions& options, const char* api);

/// @brief Rays and spans per device batch for the map's semantics.
BatchLimits batchLimits(const VoxelMap& map, const DeviceBackendOptions& options);

/// @brief Device cache slots for the options: the byte budget over the bytes of one region (all
/// layers), capped by the host store, the largest single allocation and 32-bit voxel indices.
/// 0 means shared memory: the device works on the host store in place, chosen when asked for or
/// (kAuto) when the device shares memory with the host and every layer fits one allocation.
/// Errors name the option to change.
Result<std::uint32_t> deviceCacheSlots(const VoxelMap& map, const DeviceMemoryLimits& device,
                                       const DeviceBackendOptions& options, const char* api);

}  // namespace gpu
}  // namespace raymap
