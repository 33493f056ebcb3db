// SPDX-License-Identifier: BSD-3-Clause
// A grid_map_msgs/GridMap sample preallocated for one grid size, filled from a HeightMap without
// allocating.
#pragma once

#include <cstdint>
#include <memory>

#include <dds/dds.h>

#include "src/heightmap/height_map.hpp"

namespace raymap::dds {

/// @brief The GridMap message of one fixed grid (cells_x by cells_y) with the float32 layers
/// {elevation, clearance, kind, observed_count} (kind and observed_count converted to float), and
/// when made with normals (maps with an NDT layer) then {normal_x, normal_y, normal_z}, as
/// elevation_mapping names its surface normals (unit vector, world frame, NaN where none).
///
/// grid_map conventions: info.pose.position = the grid centre (x, y, z = 0), identity
/// orientation, length_x = cells_x * resolution, length_y = cells_y * resolution, column-major
/// data with dim[0] = {"column_index", cells_y, cells_x * cells_y} and dim[1] = {"row_index",
/// cells_x, cells_x}, basic_layers = {"elevation"}, start indices 0, unknown = NaN. HeightMap is
/// already in this order, so layers are copied as they are.
///
/// Thread-safety: none; fill() and the Writer::write() of sample() from one thread.
/// Move-only (the sample points into buffers owned by the object).
class GridMapMessage {
 public:
  /// @brief The layer names, in the order of the message.
  static constexpr const char* kLayerNames[4] = {"elevation", "clearance", "kind",
                                                 "observed_count"};
  /// @brief The normal layers' names, after kLayerNames in a message made with normals.
  static constexpr const char* kNormalLayerNames[3] = {"normal_x", "normal_y", "normal_z"};

  /// @brief Preallocates the message for cells_x by cells_y cells, with the normal layers when
  /// `with_normals` (HeightMap::has_normals of the maps it will carry). Start-up only (allocates).
  /// @pre cells_x > 0, cells_y > 0
  GridMapMessage(int cells_x, int cells_y, bool with_normals = false);
  GridMapMessage(GridMapMessage&&) noexcept;
  GridMapMessage& operator=(GridMapMessage&&) noexcept;
  GridMapMessage(const GridMapMessage&) = delete;
  GridMapMessage& operator=(const GridMapMessage&) = delete;
  ~GridMapMessage();

  /// @brief Copies the map's layers, geometry, stamp and frame (truncated to 63 characters).
  /// @pre map.cells_x and map.cells_y equal the preallocated size and its layers are sized; with
  /// normals, map.has_normals (a message without normals ignores the map's normals)
  /// @rt allocates: no; blocks: no.
  void fill(const heightmap::HeightMap& map, std::int64_t stamp_ns, const char* frame_id) noexcept;

  /// @brief The idlc struct (grid_map_msgs_msg_dds__GridMap_) to pass to Writer::write().
  const void* sample() const noexcept;
  /// @brief The type of sample() (= gridMapType()).
  static const dds_topic_descriptor_t* descriptor() noexcept;

  int cellsX() const noexcept;
  int cellsY() const noexcept;
  bool withNormals() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::dds
