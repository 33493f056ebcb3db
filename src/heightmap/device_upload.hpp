// SPDX-License-Identifier: BSD-3-Clause
// What a device height-map generator (OpenCL, CUDA) copies to the device for a plan, and the size
// of each of its buffers: written once here, so that the two APIs differ only in their calls.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::heightmap {

/// The device buffers of a generation, in kernel-argument order after the parameter block.
enum DeviceBuffer : std::uint8_t {
  kTableBuffer,        ///< the plan's region table
  kRegionSlotsBuffer,  ///< region r's slot in the layer buffers: r when uploaded (packed), else
                       ///< its slot in the integration backend's layers
  kMasksBuffer,        ///< column masks, written by the mask kernel
  kOccupancyBuffer,    ///< occupancy layer of the regions under the box, packed in plan order
                       ///< (resident: the backend's buffer, nothing uploaded)
  kMeanBuffer,         ///< voxel-mean layer, likewise (a placeholder without means)
  kNdtBuffer,          ///< NDT layer, likewise (a placeholder without normals)
  kElevationBuffer,    ///< the output layers of HeightMap, in this order
  kClearanceBuffer,
  kKindBuffer,
  kObservedCountBuffer,
  kReferenceBuffer,
  kNormalXBuffer,  ///< the normal layers (placeholders without normals)
  kNormalYBuffer,
  kNormalZBuffer,
  kDeviceBufferCount
};

/// @brief Name of a buffer, for allocation errors ("column masks").
const char* toString(DeviceBuffer buffer) noexcept;

/// @brief Sizes and sources of one generation's upload. Value type; reusable (keeps capacity).
/// Two ways to reach the map's layers: uploaded (the regions under the box copied from the host
/// store, packed in plan order), or resident (the device backend that integrates the map holds
/// them in its layer buffers, and only the slot of each region is uploaded).
struct DeviceUpload {
  std::array<std::size_t, kDeviceBufferCount> bytes{};  ///< at least 8 each (no empty buffers)
  std::vector<std::uint32_t> region_slots;              ///< what kRegionSlotsBuffer holds
  bool resident = false;                   ///< the map's layers are the backend's buffers
  std::size_t occupancy_region_bytes = 0;  ///< one region of the occupancy layer
  std::size_t mean_region_bytes = 0;       ///< one region of the mean layer; 0: not uploaded
  std::size_t ndt_region_bytes = 0;        ///< one region of the NDT layer; 0: not uploaded
  bool with_mean = false;
  bool with_ndt = false;              ///< the plan writes normals: the NDT layer is uploaded
  std::uint64_t total_bytes = 0;      ///< host <-> device over every generation (bytesCopied())
  std::uint64_t total_map_bytes = 0;  ///< of those, the map's layers (mapBytesCopied())

  /// @brief Fills the sizes for `plan` on `map`. `device_slots`: the regions are resident at
  /// these slots of the backend's layer buffers (one per plan region); empty: they are uploaded.
  /// @rt allocates only when the plan grows.
  void prepare(const VoxelMap& map, const HeightmapPlan& plan,
               std::span<const std::uint32_t> device_slots = {});
  /// @brief Adds region bytes a device backend uploaded to make the regions resident.
  void countResidencyUploads(std::uint64_t uploaded) noexcept {
    total_bytes += uploaded;
    total_map_bytes += uploaded;
  }
  /// @brief Adds one finished generation of `plan` into `out` to the totals.
  void countGeneration(const HeightmapPlan& plan, HeightMap& out) {
    total_bytes += copiedBytes(plan, out);
    total_map_bytes += mapBytes(plan);
  }

  /// @brief Calls read(buffer, host_target) for each output layer of `out` (cells * 4 bytes); the
  /// normal layers only when `out` has them.
  template <class Read>
  static void forEachOutput(HeightMap& out, Read&& read) {
    read(kElevationBuffer, static_cast<void*>(out.elevation.data()));
    read(kClearanceBuffer, static_cast<void*>(out.clearance.data()));
    read(kKindBuffer, static_cast<void*>(out.kind.data()));
    read(kObservedCountBuffer, static_cast<void*>(out.observed_count.data()));
    read(kReferenceBuffer, static_cast<void*>(out.reference.data()));
    if (out.has_normals) {
      read(kNormalXBuffer, static_cast<void*>(out.normal_x.data()));
      read(kNormalYBuffer, static_cast<void*>(out.normal_y.data()));
      read(kNormalZBuffer, static_cast<void*>(out.normal_z.data()));
    }
  }

  /// @brief Bytes one generation of `plan` into `out` copies: everything forEachCopy uploads and
  /// forEachOutput reads back.
  std::uint64_t copiedBytes(const HeightmapPlan& plan, HeightMap& out) const {
    std::uint64_t total = (plan.region_table.size() + region_slots.size()) * 4 + mapBytes(plan);
    forEachOutput(out, [&](DeviceBuffer, void*) { total += out.cellCount() * 4; });
    return total;
  }

  /// @brief True for the buffers that hold the map's layers (occupancy, mean, NDT): the
  /// backend's own where resident.
  static bool isMapLayer(DeviceBuffer buffer) noexcept {
    return buffer == kOccupancyBuffer || buffer == kMeanBuffer || buffer == kNdtBuffer;
  }
  /// @brief The map layer that map-layer buffer `buffer` reads: the occupancy, mean or NDT layer,
  /// or -1 (a placeholder) for one the plan does not read.
  int layerOf(DeviceBuffer buffer, const VoxelMap& map) const noexcept {
    switch (buffer) {
      case kOccupancyBuffer:
        return map.occupancyLayer();
      case kMeanBuffer:
        return with_mean ? map.meanLayer() : -1;
      case kNdtBuffer:
        return with_ndt ? map.ndtLayer() : -1;
      default:
        return -1;
    }
  }

  /// @brief Of copiedBytes(): the map's layers uploaded (0 when resident).
  std::uint64_t mapBytes(const HeightmapPlan& plan) const {
    return resident ? 0
                    : plan.region_slots.size() *
                          (occupancy_region_bytes + (with_mean ? mean_region_bytes : 0) +
                           (with_ndt ? ndt_region_bytes : 0));
  }

  /// @brief Calls copy(buffer, device_offset, host_source, bytes) for every host-to-device copy:
  /// the table, the slot list, then (unless resident) each region's occupancy (and mean, and NDT)
  /// layer.
  template <class Copy>
  void forEachCopy(const VoxelMap& map, const HeightmapPlan& plan, Copy&& copy) const {
    copy(kTableBuffer, 0, plan.region_table.data(), plan.region_table.size() * 4);
    copy(kRegionSlotsBuffer, 0, region_slots.data(), region_slots.size() * 4);
    if (resident) {
      return;
    }
    const RegionStore& store = map.store();
    for (std::size_t r = 0; r < plan.region_slots.size(); ++r) {
      copy(kOccupancyBuffer, r * occupancy_region_bytes,
           store.layerBytes(plan.region_slots[r], map.occupancyLayer()), occupancy_region_bytes);
      if (with_mean) {
        copy(kMeanBuffer, r * mean_region_bytes,
             store.layerBytes(plan.region_slots[r], map.meanLayer()), mean_region_bytes);
      }
      if (with_ndt) {
        copy(kNdtBuffer, r * ndt_region_bytes,
             store.layerBytes(plan.region_slots[r], map.ndtLayer()), ndt_region_bytes);
      }
    }
  }
};

}  // namespace raymap::heightmap
