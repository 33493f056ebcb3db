// SPDX-License-Identifier: BSD-3-Clause
#include "src/heightmap/device_upload.hpp"

#include <algorithm>

namespace raymap::heightmap {

const char* toString(DeviceBuffer buffer) noexcept {
  switch (buffer) {
    case kTableBuffer:
      return "region table";
    case kRegionSlotsBuffer:
      return "region slots";
    case kMasksBuffer:
      return "column masks";
    case kOccupancyBuffer:
      return "occupancy layer";
    case kMeanBuffer:
      return "voxel-mean layer";
    case kNdtBuffer:
      return "NDT layer";
    case kElevationBuffer:
      return "elevation";
    case kClearanceBuffer:
      return "clearance";
    case kKindBuffer:
      return "kind";
    case kObservedCountBuffer:
      return "observed count";
    case kReferenceBuffer:
      return "reference";
    case kNormalXBuffer:
      return "normal_x";
    case kNormalYBuffer:
      return "normal_y";
    case kNormalZBuffer:
      return "normal_z";
    case kDeviceBufferCount:
      break;
  }
  return "buffer";
}

void DeviceUpload::prepare(const VoxelMap& map, const HeightmapPlan& plan,
                           std::span<const std::uint32_t> device_slots) {
  const RegionStore& store = map.store();
  const rm_heightmap_params& p = plan.params;
  with_mean = (p.flags & RM_HM_FLAG_SAMPLES) != 0 && map.meanLayer() >= 0;
  occupancy_region_bytes = store.layerRegionBytes(map.occupancyLayer());
  mean_region_bytes = with_mean ? store.layerRegionBytes(map.meanLayer()) : 0;
  with_ndt = (p.flags & RM_HM_FLAG_NORMALS) != 0 && map.ndtLayer() >= 0;
  ndt_region_bytes = with_ndt ? store.layerRegionBytes(map.ndtLayer()) : 0;
  resident = !device_slots.empty();
  region_slots.resize(std::max<std::size_t>(plan.region_slots.size(), 1));
  for (std::size_t r = 0; r < region_slots.size(); ++r) {
    region_slots[r] = resident ? device_slots[r] : static_cast<std::uint32_t>(r);
  }
  const std::size_t regions = region_slots.size();
  const auto n = static_cast<std::size_t>(p.region_voxels);
  const std::size_t cells =
      static_cast<std::size_t>(p.cells_x) * static_cast<std::size_t>(p.cells_y);
  bytes[kTableBuffer] = plan.region_table.size() * 4;
  bytes[kRegionSlotsBuffer] = regions * 4;
  bytes[kMasksBuffer] = regions * n * n *
                        static_cast<std::size_t>(rm_hm_mask_words(p.region_voxels)) *
                        sizeof(rm_hm_mask);
  // Resident layers are the backend's buffers: the generator's own stay at the minimum.
  bytes[kOccupancyBuffer] = resident ? 0 : regions * occupancy_region_bytes;
  bytes[kMeanBuffer] = resident ? 0 : regions * mean_region_bytes;
  bytes[kNdtBuffer] = resident ? 0 : regions * ndt_region_bytes;
  for (const DeviceBuffer layer :
       {kElevationBuffer, kClearanceBuffer, kKindBuffer, kObservedCountBuffer, kReferenceBuffer}) {
    bytes[layer] = cells * 4;
  }
  for (const DeviceBuffer layer : {kNormalXBuffer, kNormalYBuffer, kNormalZBuffer}) {
    bytes[layer] = with_ndt ? cells * 4 : 0;
  }
  for (std::size_t& b : bytes) {
    b = std::max<std::size_t>(b, 8);
  }
}

}  // namespace raymap::heightmap
