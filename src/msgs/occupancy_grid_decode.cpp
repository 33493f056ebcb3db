// SPDX-License-Identifier: BSD-3-Clause
// decodeOccupancyGrid over the bounded CDR reader, field by field in the order of
// config/idl/nav_msgs.idl (what OccupancyGridMessage writes).
#include "src/msgs/occupancy_grid_decode.hpp"

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {

const char* toString(OccupancyGridError error) noexcept {
  switch (error) {
    case OccupancyGridError::kTruncated:
      return "truncated";
    case OccupancyGridError::kBadEncapsulation:
      return "bad_encapsulation";
    case OccupancyGridError::kMalformed:
      return "malformed";
    case OccupancyGridError::kSizeMismatch:
      return "size_mismatch";
  }
  return "unknown";
}

Expected<DecodedOccupancyGrid, OccupancyGridError> decodeOccupancyGrid(
    std::span<const std::byte> cdr) {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(OccupancyGridError::kBadEncapsulation);
  }
  const auto failure = [&reader] {
    return Unexpected(reader.malformed() ? OccupancyGridError::kMalformed
                                         : OccupancyGridError::kTruncated);
  };
  DecodedOccupancyGrid grid;
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(grid.frame_id)) {
    return failure();
  }
  grid.stamp_ns = nanosecondsOf(sec, nanosec);
  // info: map_load_time, resolution, width, height, origin (position, orientation x, y, z, w)
  if (!reader.readI32(sec) || !reader.readU32(nanosec)) {
    return failure();
  }
  grid.map_load_time_ns = nanosecondsOf(sec, nanosec);
  if (!reader.readF32(grid.resolution) || !reader.readU32(grid.width) ||
      !reader.readU32(grid.height) || !reader.readF64(grid.origin_x) ||
      !reader.readF64(grid.origin_y) || !reader.readF64(grid.origin_z) ||
      !reader.readF64(grid.qx) || !reader.readF64(grid.qy) || !reader.readF64(grid.qz) ||
      !reader.readF64(grid.qw)) {
    return failure();
  }
  std::uint32_t count = 0;
  std::span<const std::byte> bytes;
  if (!reader.readSequenceLength(count, 1) || !reader.readBytes(count, bytes)) {
    return failure();
  }
  if (std::uint64_t{grid.width} * grid.height != count) {
    return Unexpected(OccupancyGridError::kSizeMismatch);
  }
  grid.data.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    grid.data[i] = static_cast<std::int8_t>(bytes[i]);
  }
  return grid;
}

}  // namespace raymap::msgs
