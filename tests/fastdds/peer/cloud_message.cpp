// SPDX-License-Identifier: BSD-3-Clause
// fillCloud: the field layout and the points' bytes.
#include "tests/fastdds/peer/cloud_message.hpp"

#include <bit>
#include <cstring>

namespace raymap::fastdds_peer {
namespace {

// sensor_msgs/PointField datatypes.
constexpr std::uint8_t kUint32 = 6;
constexpr std::uint8_t kFloat32 = 7;

sensor_msgs::msg::dds_::PointField_ field(const char* name, std::uint32_t offset,
                                          std::uint8_t datatype) {
  sensor_msgs::msg::dds_::PointField_ f;
  f.name(name);
  f.offset(offset);
  f.datatype(datatype);
  f.count(1);
  return f;
}

}  // namespace

builtin_interfaces::msg::dds_::Time_ rosTime(std::int64_t stamp_ns) {
  builtin_interfaces::msg::dds_::Time_ time;
  time.sec(static_cast<std::int32_t>(stamp_ns / 1000000000));
  time.nanosec(static_cast<std::uint32_t>(stamp_ns % 1000000000));
  return time;
}

void fillCloud(std::span<const LidarPoint> points, std::int64_t stamp_ns, const std::string& frame,
               sensor_msgs::msg::dds_::PointCloud2_& cloud) {
  cloud.header().stamp(rosTime(stamp_ns));
  cloud.header().frame_id(frame);
  cloud.height(1);
  cloud.width(static_cast<std::uint32_t>(points.size()));
  cloud.fields({field("x", 0, kFloat32), field("y", 4, kFloat32), field("z", 8, kFloat32),
                field("t", 12, kUint32)});
  cloud.is_bigendian(std::endian::native == std::endian::big);
  cloud.point_step(kPointStep);
  cloud.row_step(kPointStep * static_cast<std::uint32_t>(points.size()));
  cloud.is_dense(true);
  std::vector<std::uint8_t>& data = cloud.data();
  data.resize(points.size() * kPointStep);
  std::uint8_t* out = data.data();
  for (const LidarPoint& p : points) {
    std::memcpy(out, &p.x, 4);
    std::memcpy(out + 4, &p.y, 4);
    std::memcpy(out + 8, &p.z, 4);
    std::memcpy(out + 12, &p.t_ns, 4);
    out += kPointStep;
  }
}

}  // namespace raymap::fastdds_peer
