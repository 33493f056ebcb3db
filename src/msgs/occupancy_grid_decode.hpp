// SPDX-License-Identifier: BSD-3-Clause
// Decoding nav_msgs/OccupancyGrid from its serialized XCDR1 bytes, for `raymap echo` and tests.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/expected.hpp"

namespace raymap::msgs {

/// @brief A decoded OccupancyGrid. Metres; the origin is cell (0, 0)'s outer corner in
/// `frame_id`.
struct DecodedOccupancyGrid {
  std::int64_t stamp_ns = 0;                              ///< header.stamp, nanoseconds
  std::string frame_id;                                   ///< header.frame_id
  std::int64_t map_load_time_ns = 0;                      ///< info.map_load_time
  float resolution = 0.0F;                                ///< info.resolution, metres per cell
  std::uint32_t width = 0;                                ///< info.width, cells along x
  std::uint32_t height = 0;                               ///< info.height, cells along y
  double origin_x = 0.0, origin_y = 0.0, origin_z = 0.0;  ///< info.origin.position
  double qw = 1.0, qx = 0.0, qy = 0.0, qz = 0.0;          ///< info.origin.orientation
  std::vector<std::int8_t> data;                          ///< row-major, -1 unknown, 0..100
};

/// Why an OccupancyGrid was rejected. Nothing is read out of bounds for any input.
enum class OccupancyGridError : std::uint8_t {
  kTruncated,         ///< the bytes end before the message does (also absurd sequence lengths)
  kBadEncapsulation,  ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,         ///< a string without its NUL
  kSizeMismatch,      ///< data does not hold width × height cells
};

/// @brief Short, stable name ("truncated", "size_mismatch", ...). @rt allocates: no.
const char* toString(OccupancyGridError error) noexcept;

/// @brief Decodes a serialized nav_msgs/OccupancyGrid (with the 4-byte encapsulation header),
/// in either CDR byte order.
Expected<DecodedOccupancyGrid, OccupancyGridError> decodeOccupancyGrid(
    std::span<const std::byte> cdr);

}  // namespace raymap::msgs
