// SPDX-License-Identifier: BSD-3-Clause
// decodeGridMap over the bounded CDR reader, field by field in the order of
// config/idl/grid_map_msgs.idl (what GridMapMessage writes).
#include "src/msgs/grid_map_decode.hpp"

#include <cmath>
#include <limits>
#include <string_view>

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

// Smallest encodings, so that a corrupt count is refused before anything is reserved for it:
// a string is its uint32 length; a dimension is a string and two uint32; an array is the
// dimension count, data_offset and the data count.
constexpr std::size_t kMinStringBytes = 4;
constexpr std::size_t kMinDimBytes = 12;
constexpr std::size_t kMinArrayBytes = 12;

Unexpected<GridMapError> readFailure(const CdrReader& reader) {
  return Unexpected(reader.malformed() ? GridMapError::kMalformed : GridMapError::kTruncated);
}

bool readStrings(CdrReader& reader, std::vector<std::string>& out) {
  std::uint32_t count = 0;
  if (!reader.readSequenceLength(count, kMinStringBytes)) {
    return false;
  }
  out.resize(count);
  for (std::string& text : out) {
    if (!reader.readString(text)) {
      return false;
    }
  }
  return true;
}

bool readArray(CdrReader& reader, GridMapLayerData& out) {
  std::uint32_t dims = 0;
  if (!reader.readSequenceLength(dims, kMinDimBytes)) {
    return false;
  }
  out.dims.resize(dims);
  for (GridMapArrayDim& dim : out.dims) {
    if (!reader.readString(dim.label) || !reader.readU32(dim.size) || !reader.readU32(dim.stride)) {
      return false;
    }
  }
  std::uint32_t count = 0;
  if (!reader.readU32(out.data_offset) || !reader.readSequenceLength(count, sizeof(float))) {
    return false;
  }
  out.data.resize(count);
  for (float& value : out.data) {
    if (!reader.readF32(value)) {
      return false;
    }
  }
  return true;
}

/// grid_map_ros reads exactly two dimensions and size[0] * size[1] cells after data_offset.
bool layoutConsistent(const GridMapLayerData& array) noexcept {
  if (array.dims.size() != 2) {
    return false;
  }
  const std::uint64_t cells = std::uint64_t{array.dims[0].size} * array.dims[1].size;
  return cells + array.data_offset == array.data.size();
}

}  // namespace

const char* toString(GridMapError error) noexcept {
  switch (error) {
    case GridMapError::kTruncated:
      return "truncated";
    case GridMapError::kBadEncapsulation:
      return "bad_encapsulation";
    case GridMapError::kMalformed:
      return "malformed";
    case GridMapError::kLayerCountMismatch:
      return "layer_count_mismatch";
    case GridMapError::kLayoutMismatch:
      return "layout_mismatch";
  }
  return "unknown";
}

Expected<DecodedGridMap, GridMapError> decodeGridMap(std::span<const std::byte> cdr) {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(GridMapError::kBadEncapsulation);
  }
  DecodedGridMap map;
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(map.frame_id)) {
    return readFailure(reader);
  }
  map.stamp_ns = nanosecondsOf(sec, nanosec);
  // info: resolution, lengths, pose (position, then orientation x, y, z, w)
  if (!reader.readF64(map.resolution) || !reader.readF64(map.length_x) ||
      !reader.readF64(map.length_y) || !reader.readF64(map.centre_x) ||
      !reader.readF64(map.centre_y) || !reader.readF64(map.centre_z) || !reader.readF64(map.qx) ||
      !reader.readF64(map.qy) || !reader.readF64(map.qz) || !reader.readF64(map.qw)) {
    return readFailure(reader);
  }
  if (!readStrings(reader, map.layers) || !readStrings(reader, map.basic_layers)) {
    return readFailure(reader);
  }
  std::uint32_t arrays = 0;
  if (!reader.readSequenceLength(arrays, kMinArrayBytes)) {
    return readFailure(reader);
  }
  map.data.resize(arrays);
  for (GridMapLayerData& array : map.data) {
    if (!readArray(reader, array)) {
      return readFailure(reader);
    }
  }
  if (!reader.readU16(map.outer_start_index) || !reader.readU16(map.inner_start_index)) {
    return readFailure(reader);
  }
  if (map.data.size() != map.layers.size()) {
    return Unexpected(GridMapError::kLayerCountMismatch);
  }
  for (const GridMapLayerData& array : map.data) {
    if (!layoutConsistent(array)) {
      return Unexpected(GridMapError::kLayoutMismatch);
    }
  }
  return map;
}

LayerStats layerStats(std::span<const float> values) noexcept {
  LayerStats stats;
  stats.cells = values.size();
  float min = std::numeric_limits<float>::infinity();
  float max = -std::numeric_limits<float>::infinity();
  for (const float value : values) {
    if (std::isfinite(value)) {
      ++stats.finite;
      min = value < min ? value : min;
      max = value > max ? value : max;
    }
  }
  if (stats.finite == 0) {
    min = std::numeric_limits<float>::quiet_NaN();
    max = std::numeric_limits<float>::quiet_NaN();
  }
  stats.min = min;
  stats.max = max;
  return stats;
}

}  // namespace raymap::msgs
