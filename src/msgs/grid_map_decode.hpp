// SPDX-License-Identifier: BSD-3-Clause
// Decoding grid_map_msgs/GridMap (ROS 2 layout) from its serialized XCDR1 bytes, for tools that
// inspect the traffic (`raymap echo`) and for tests of the encoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/expected.hpp"

namespace raymap::msgs {

/// std_msgs/MultiArrayDimension.
struct GridMapArrayDim {
  std::string label;         ///< "column_index" / "row_index" in grid_map's column-major layout
  std::uint32_t size = 0;    ///< elements along this dimension
  std::uint32_t stride = 0;  ///< elements per step of the dimension before it
};

/// One std_msgs/Float32MultiArray of GridMap::data (one per layer, in the order of `layers`).
struct GridMapLayerData {
  std::vector<GridMapArrayDim> dims;
  std::uint32_t data_offset = 0;  ///< elements to skip before the first cell
  std::vector<float> data;        ///< every element, in host byte order (NaN = unknown cell)
};

/// @brief A decoded GridMap. Lengths in metres; the pose is the map's centre in `frame_id`.
struct DecodedGridMap {
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds since the epoch of the sender's clock
  std::string frame_id;       ///< header.frame_id
  double resolution = 0.0;    ///< info.resolution, metres per cell
  double length_x = 0.0;      ///< info.length_x, metres
  double length_y = 0.0;      ///< info.length_y, metres
  double centre_x = 0.0, centre_y = 0.0, centre_z = 0.0;  ///< info.pose.position, metres
  double qw = 1.0, qx = 0.0, qy = 0.0, qz = 0.0;          ///< info.pose.orientation, as sent
  std::vector<std::string> layers;
  std::vector<std::string> basic_layers;
  std::vector<GridMapLayerData> data;  ///< as many as `layers` (checked)
  std::uint16_t outer_start_index = 0;
  std::uint16_t inner_start_index = 0;
};

/// Why a GridMap was rejected. Nothing is read out of bounds for any input.
enum class GridMapError : std::uint8_t {
  kTruncated,           ///< the bytes end before the message does (also absurd sequence lengths)
  kBadEncapsulation,    ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,           ///< a string without its NUL
  kLayerCountMismatch,  ///< `data` does not hold one array per name in `layers`
  kLayoutMismatch,      ///< an array without two dimensions, or whose dimension sizes (times,
                        ///< plus data_offset) do not add up to its number of elements
};

/// @brief Short, stable name ("truncated", "layout_mismatch", ...). @rt allocates: no.
const char* toString(GridMapError error) noexcept;

/// @brief Decodes a serialized grid_map_msgs/GridMap (the bytes from RawReader::take, with the
/// 4-byte encapsulation header), in either CDR byte order. Trailing bytes are ignored (padding).
/// The checks are those grid_map_ros's converter relies on: one array per layer, two dimensions
/// whose sizes multiply to the number of cells.
/// @return the message, or why it was refused
/// Allocates (strings and the layers' data): a tool and test decoder, not for the real-time
/// path. Thread-safety: any thread (no shared state).
Expected<DecodedGridMap, GridMapError> decodeGridMap(std::span<const std::byte> cdr);

/// @brief What a layer's values hold.
struct LayerStats {
  std::uint64_t cells = 0;   ///< values looked at
  std::uint64_t finite = 0;  ///< values that are finite (unknown cells are NaN; +inf is "open")
  float min = 0.0F;          ///< smallest finite value (NaN when finite == 0)
  float max = 0.0F;          ///< largest finite value (NaN when finite == 0)
};

/// @brief Counts the finite values and their range. @rt allocates: no; thread: any.
LayerStats layerStats(std::span<const float> values) noexcept;

}  // namespace raymap::msgs
