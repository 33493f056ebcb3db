// SPDX-License-Identifier: BSD-3-Clause
// Sizing rules shared by the device backends.
#include "src/device/staging/device_options.hpp"

#include <algorithm>

#include "kernels/common/batch.h"

namespace raymap::gpu {
namespace {

/// Whether the device should work on the host store in place.
bool useSharedMemory(const VoxelMap& map, const DeviceMemoryLimits& device, DeviceMemory memory) {
  if (memory != DeviceMemory::kAuto) {
    return memory == DeviceMemory::kShared;
  }
  const RegionStore& store = map.store();
  if (!device.unified_memory || !device.can_map_host_memory ||
      std::uint64_t{store.capacity()} * store.voxelsPerRegion() >= (std::uint64_t{1} << 32)) {
    return false;
  }
  for (int l = 0; l < store.schema().size(); ++l) {
    if (std::uint64_t{store.layerRegionBytes(l)} * store.capacity() > device.max_alloc_bytes) {
      return false;
    }
  }
  return true;
}

}  // namespace

Expected<void, Error> checkBatchOptions(const DeviceBackendOptions& options, const char* api) {
  if (options.batch_rays == 0 || options.batch_rays > (std::size_t{1} << 24) ||
      options.per_ray_batch_rays == 0 || options.per_ray_batch_rays > RM_TAG_MAX_GROUPS) {
    return fail(
        ErrorCode::kInvalidArgument,
        std::string(api) + " batch sizes must be 1 to 16777216 rays (per-ray: 1 to 4194304)");
  }
  return {};
}

BatchLimits batchLimits(const VoxelMap& map, const DeviceBackendOptions& options) {
  // 8 spans per ray on average is far more than lidar rays need; a batch also ends when its spans
  // run out.
  const std::size_t rays = map.semantics() == Semantics::kPerScan
                               ? options.batch_rays
                               : std::min(options.batch_rays, options.per_ray_batch_rays);
  return BatchLimits{rays, rays * 8};
}

Result<std::uint32_t> deviceCacheSlots(const VoxelMap& map, const DeviceMemoryLimits& device,
                                       const DeviceBackendOptions& options, const char* api) {
  if (useSharedMemory(map, device, options.memory)) {
    if (!device.unified_memory || !device.can_map_host_memory) {
      return fail(ErrorCode::kUnsupported, "shared device memory: " + device.device_name +
                                               " does not share memory with the host; use the "
                                               "region cache (backend.gpu_memory: cache)");
    }
    return std::uint32_t{0};
  }
  const RegionStore& store = map.store();
  std::uint64_t region_bytes = 0;
  std::uint64_t largest_layer = 0;
  for (int l = 0; l < store.schema().size(); ++l) {
    region_bytes += store.layerRegionBytes(l);
    largest_layer = std::max<std::uint64_t>(largest_layer, store.layerRegionBytes(l));
  }
  std::uint64_t budget = options.cache_bytes;
  if (budget == 0) {
    budget = std::min<std::uint64_t>(DeviceBackendOptions::kDefaultCacheBytes,
                                     device.global_mem_bytes / 2);
  }
  std::uint64_t slots = options.cache_regions > 0 ? options.cache_regions : budget / region_bytes;
  slots = std::min<std::uint64_t>(slots, store.capacity());
  slots = std::min<std::uint64_t>(slots, device.max_alloc_bytes / largest_layer);
  slots = std::min<std::uint64_t>(slots, (std::uint64_t{1} << 32) / store.voxelsPerRegion() - 1);
  if (slots == 0) {
    return fail(ErrorCode::kInvalidArgument,
                std::string("the ") + api + " region cache of " + std::to_string(budget) +
                    " bytes cannot hold one region of " + std::to_string(region_bytes) +
                    " bytes; raise backend.gpu_cache");
  }
  return static_cast<std::uint32_t>(slots);
}

}  // namespace raymap::gpu
