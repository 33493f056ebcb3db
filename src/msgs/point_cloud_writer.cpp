// SPDX-License-Identifier: BSD-3-Clause
#include "src/msgs/point_cloud_writer.hpp"

#include <cmath>
#include <cstring>
#include <iterator>
#include <string_view>

#include "raymap/assert.hpp"

#include "src/core/byte_order.hpp"
#include "src/msgs/cdr_le_writer.hpp"

namespace raymap::msgs {
namespace {

/// One PointField of the layout.
struct Field {
  std::string_view name;
  std::uint32_t offset;
  PointFieldType type;
};

constexpr Field kOusterFields[] = {
    {"x", 0, PointFieldType::kFloat32},     {"y", 4, PointFieldType::kFloat32},
    {"z", 8, PointFieldType::kFloat32},     {"intensity", 16, PointFieldType::kFloat32},
    {"t", 20, PointFieldType::kUInt32},     {"reflectivity", 24, PointFieldType::kUInt16},
    {"ring", 26, PointFieldType::kUInt16},  {"ambient", 28, PointFieldType::kUInt16},
    {"range", 32, PointFieldType::kUInt32},
};

/// `value` rounded to a uint32 field: NaN and negatives 0, beyond the field its largest value.
std::uint32_t roundedUInt32(double value) noexcept {
  const double rounded = std::nearbyint(value);
  if (!(rounded > 0.0)) {
    return 0;
  }
  return rounded >= 4294967295.0 ? 0xFFFFFFFFu : static_cast<std::uint32_t>(rounded);
}

/// One point in the layout, little-endian (is_bigendian false); padding zeroed.
void putPoint(std::byte* at, const ScanPoint& p, std::uint16_t ring) noexcept {
  std::memset(at, 0, kOusterPointStep);
  const bool no_return = (p.flags & kPointNoReturn) != 0u;
  const float x = no_return ? 0.0f : p.x;
  const float y = no_return ? 0.0f : p.y;
  const float z = no_return ? 0.0f : p.z;
  storeLe(at + 0, x);
  storeLe(at + 4, y);
  storeLe(at + 8, z);
  storeLe(at + 16, p.intensity);
  storeLe(at + 20, roundedUInt32(static_cast<double>(p.time_s) * 1e9));  // ns after the stamp
  storeLe(at + 26, ring);
  const double dx = static_cast<double>(x);
  const double dy = static_cast<double>(y);
  const double dz = static_cast<double>(z);
  storeLe(at + 32, roundedUInt32(1000.0 * std::sqrt(dx * dx + dy * dy + dz * dz)));  // mm
}

}  // namespace

void serializeOusterCloud(std::int64_t stamp_ns, std::string_view frame_id, std::uint32_t rows,
                          std::span<const ScanPoint> points, std::span<const std::uint16_t> rings,
                          std::vector<std::byte>& out) {
  RAYMAP_EXPECTS(rows > 0 && points.size() % rows == 0);
  RAYMAP_EXPECTS(rings.empty() || rings.size() == points.size());
  const auto width = static_cast<std::uint32_t>(points.size() / rows);
  const std::size_t data_bytes = points.size() * kOusterPointStep;

  CdrSizer size;
  addStdHeader(size, frame_id);
  size.add(4, 8);  // height, width
  size.add(4, 4);  // fields: count
  for (const Field& f : kOusterFields) {
    size.string(f.name);
    size.add(4, 4);  // offset
    size.add(1, 1);  // datatype
    size.add(4, 4);  // count
  }
  size.add(1, 1);               // is_bigendian
  size.add(4, 8);               // point_step, row_step
  size.add(4, 4 + data_bytes);  // data
  size.add(1, 1);               // is_dense

  CdrCursor cursor(startCdrLeMessage(out, size.size()));
  putStdHeader(cursor, stamp_ns, frame_id);
  cursor.put(rows);
  cursor.put(width);
  cursor.put(static_cast<std::uint32_t>(std::size(kOusterFields)));
  for (const Field& f : kOusterFields) {
    cursor.string(f.name);
    cursor.put(f.offset);
    cursor.put(static_cast<std::uint8_t>(f.type));
    cursor.put(std::uint32_t{1});
  }
  cursor.put(std::uint8_t{0});  // little-endian points
  cursor.put(kOusterPointStep);
  cursor.put(width * kOusterPointStep);
  cursor.put(static_cast<std::uint32_t>(data_bytes));
  std::byte* data = cursor.raw(data_bytes);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto ring = rings.empty() ? static_cast<std::uint16_t>(i / width) : rings[i];
    putPoint(data + i * kOusterPointStep, points[i], ring);
  }
  cursor.put(std::uint8_t{1});  // is_dense
  RAYMAP_ENSURES(cursor.position() + sizeof(kCdrLeHeader) == out.size());
}

}  // namespace raymap::msgs
