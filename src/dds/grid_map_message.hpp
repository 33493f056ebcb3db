// SPDX-License-Identifier: BSD-3-Clause
// A grid_map_msgs/GridMap sample preallocated for one grid size, filled from a HeightMap without
// allocating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>

#include <dds/dds.h>

#include "src/heightmap/height_map.hpp"

namespace raymap::dds {

/// @brief A layer a GridMap can carry; the message keeps this order whatever the choice.
enum class GridLayer : std::uint8_t {
  kElevation,
  kClearance,
  kKind,
  kObservedCount,
  kNormalX,
  kNormalY,
  kNormalZ,
};
inline constexpr std::size_t kGridLayerCount = 7;

/// @brief The layer's name in the message ("elevation", ..., "normal_z").
const char* gridLayerName(GridLayer layer) noexcept;
/// @brief The layer of that name, or nullopt.
std::optional<GridLayer> gridLayerNamed(std::string_view name) noexcept;
/// @brief Whether the layer is a surface normal (only maps with an NDT layer have them).
constexpr bool isNormalLayer(GridLayer layer) noexcept { return layer >= GridLayer::kNormalX; }

/// @brief A choice of layers (heightmap.layers). Value type.
class GridLayerSet {
 public:
  /// @brief The four base layers, and the normals when `with_normals`.
  static GridLayerSet all(bool with_normals) noexcept;
  GridLayerSet& add(GridLayer layer) noexcept {
    bits_ = static_cast<std::uint8_t>(bits_ | (1u << static_cast<unsigned>(layer)));
    return *this;
  }
  bool has(GridLayer layer) const noexcept {
    return (bits_ >> static_cast<unsigned>(layer) & 1u) != 0;
  }
  bool empty() const noexcept { return bits_ == 0; }
  bool hasNormals() const noexcept;
  std::size_t count() const noexcept;

 private:
  std::uint8_t bits_ = 0;
};

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
  /// @brief The same with a choice of layers (in GridLayer order; basic_layers is {"elevation"}
  /// when it is chosen, else empty). Each layer costs cells_x * cells_y * 4 bytes on the wire.
  /// @pre cells_x > 0, cells_y > 0, !layers.empty()
  GridMapMessage(int cells_x, int cells_y, GridLayerSet layers);
  GridMapMessage(GridMapMessage&&) noexcept;
  GridMapMessage& operator=(GridMapMessage&&) noexcept;
  GridMapMessage(const GridMapMessage&) = delete;
  GridMapMessage& operator=(const GridMapMessage&) = delete;
  ~GridMapMessage();

  /// @brief Copies the map's layers, geometry, stamp and frame (truncated to 63 characters).
  /// @pre map.cells_x and map.cells_y equal the preallocated size and its layers are sized; with
  /// normal layers chosen, map.has_normals (a message without them ignores the map's normals)
  /// @rt allocates: no; blocks: no.
  void fill(const heightmap::HeightMap& map, std::int64_t stamp_ns, const char* frame_id) noexcept;

  /// @brief The idlc struct (grid_map_msgs_msg_dds__GridMap_) to pass to Writer::write().
  const void* sample() const noexcept;
  /// @brief The type of sample() (= gridMapType()).
  static const dds_topic_descriptor_t* descriptor() noexcept;

  int cellsX() const noexcept;
  int cellsY() const noexcept;
  bool withNormals() const noexcept;
  GridLayerSet layers() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::dds
