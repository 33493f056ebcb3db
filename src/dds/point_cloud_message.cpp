// SPDX-License-Identifier: BSD-3-Clause
// The preallocated PointCloud2 message: a fixed field layout chosen at construction and a data
// buffer for `capacity` points, sequences with _release false.
#include "src/dds/point_cloud_message.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "raymap/assert.hpp"
#include "sensor_msgs.h"

#include "src/core/byte_order.hpp"
#include "src/dds/frame_id.hpp"
#include "src/dds/ros_time.hpp"
#include "src/dds/topic_types.hpp"

namespace raymap::dds {
namespace {

constexpr std::size_t kMaxFields = 6;

char* mutableText(const char* text) noexcept {
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): C API
  return const_cast<char*>(text);
}

/// Stores a field of a point: little-endian on any host, as the message says (is_bigendian is
/// false).
template <ByteValue T>
void store(std::uint8_t* p, T value) noexcept {
  storeLe(reinterpret_cast<std::byte*>(p), value);
}

}  // namespace

/// Design: one heap block per message (moves keep the addresses in `msg` valid); fill() writes
/// the data and the header, Writer::write() reads them.
struct PointCloudMessage::Impl {
  std::uint32_t capacity = 0;
  CloudLayout layout;
  std::uint32_t point_step = 0;
  std::uint32_t intensity_offset = 0;
  std::uint32_t time_offset = 0;
  std::uint32_t ring_offset = 0;
  sensor_msgs_msg_dds__PointCloud2_ msg{};
  char frame_id[64] = {};
  sensor_msgs_msg_dds__PointField_ fields[kMaxFields]{};
  std::vector<std::uint8_t> data;

  /// Sets the header and sizes for `count` points; returns the data pointer.
  std::uint8_t* begin(std::size_t count, std::int64_t stamp_ns, const char* frame) noexcept {
    RAYMAP_EXPECTS(count <= capacity && count % layout.rows == 0);
    setRosTime(msg.header.stamp, stamp_ns);
    copyFrameId(frame_id, frame);
    const auto n = static_cast<std::uint32_t>(count);
    msg.height = layout.rows;
    msg.width = n / layout.rows;
    msg.row_step = msg.width * point_step;
    msg.data._length = n * point_step;
    std::memset(data.data(), 0, std::size_t{n} * point_step);
    return data.data();
  }
};

PointCloudMessage::PointCloudMessage(std::uint32_t capacity, CloudLayout layout)
    : impl_(std::make_unique<Impl>()) {
  RAYMAP_EXPECTS(capacity > 0 && layout.rows >= 1);
  Impl& m = *impl_;
  m.capacity = capacity;
  m.layout = layout;
  std::uint32_t field_count = 0;
  std::uint32_t offset = 0;
  const auto add = [&](const char* name, msgs::PointFieldType type, std::uint32_t bytes) {
    auto& field = m.fields[field_count++];
    field.name = mutableText(name);
    field.offset = offset;
    field.datatype = static_cast<std::uint8_t>(type);
    field.count = 1;
    const std::uint32_t at = offset;
    offset += bytes;
    return at;
  };
  add("x", msgs::PointFieldType::kFloat32, 4);
  add("y", msgs::PointFieldType::kFloat32, 4);
  add("z", msgs::PointFieldType::kFloat32, 4);
  if (layout.intensity) {
    m.intensity_offset = add("intensity", msgs::PointFieldType::kFloat32, 4);
  }
  if (layout.time) {
    m.time_offset = add("t", msgs::PointFieldType::kUInt32, 4);
  }
  if (layout.ring) {
    m.ring_offset = add("ring", msgs::PointFieldType::kUInt16, 2);
  }
  m.point_step = (offset + 3U) / 4U * 4U;  // 4-byte aligned points
  RAYMAP_EXPECTS(std::uint64_t{capacity} * m.point_step <=
                 std::numeric_limits<std::uint32_t>::max());
  m.data.assign(std::size_t{capacity} * m.point_step, 0);

  m.msg.header.frame_id = m.frame_id;
  m.msg.fields._buffer = m.fields;
  m.msg.fields._length = field_count;
  m.msg.fields._maximum = field_count;
  m.msg.fields._release = false;
  m.msg.is_bigendian = false;
  m.msg.point_step = m.point_step;
  m.msg.data._buffer = m.data.data();
  m.msg.data._maximum = static_cast<std::uint32_t>(m.data.size());
  m.msg.data._length = 0;
  m.msg.data._release = false;
  m.msg.height = layout.rows;
  m.msg.is_dense = true;
}

PointCloudMessage::PointCloudMessage(PointCloudMessage&&) noexcept = default;
PointCloudMessage& PointCloudMessage::operator=(PointCloudMessage&&) noexcept = default;
PointCloudMessage::~PointCloudMessage() = default;

void PointCloudMessage::fill(std::span<const float> xyz, std::int64_t stamp_ns,
                             const char* frame_id) noexcept {
  Impl& m = *impl_;
  RAYMAP_EXPECTS(xyz.size() % 3 == 0);
  const std::size_t count = xyz.size() / 3;
  std::uint8_t* data = m.begin(count, stamp_ns, frame_id);
  bool dense = true;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint8_t* p = data + i * m.point_step;
    const float x = xyz[3 * i];
    const float y = xyz[3 * i + 1];
    const float z = xyz[3 * i + 2];
    store(p, x);
    store(p + 4, y);
    store(p + 8, z);
    dense = dense && std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
  }
  m.msg.is_dense = dense;
}

void PointCloudMessage::fill(std::span<const msgs::ScanPoint> points,
                             std::span<const std::uint16_t> rings, std::int64_t stamp_ns,
                             const char* frame_id) noexcept {
  Impl& m = *impl_;
  RAYMAP_EXPECTS(rings.empty() || rings.size() == points.size());
  std::uint8_t* data = m.begin(points.size(), stamp_ns, frame_id);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  constexpr double kMaxTimeNs = std::numeric_limits<std::uint32_t>::max();
  bool dense = true;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const msgs::ScanPoint& point = points[i];
    std::uint8_t* p = data + i * m.point_step;
    const bool no_return = (point.flags & msgs::kPointNoReturn) != 0U;
    const float x = no_return ? kNaN : point.x;
    const float y = no_return ? kNaN : point.y;
    const float z = no_return ? kNaN : point.z;
    store(p, x);
    store(p + 4, y);
    store(p + 8, z);
    dense = dense && std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
    if (m.layout.intensity) {
      store(p + m.intensity_offset, point.intensity);
    }
    if (m.layout.time) {
      double t_ns = std::round(static_cast<double>(point.time_s) * 1e9);
      if (!(t_ns > 0.0)) {  // also NaN
        t_ns = 0.0;
      } else if (t_ns > kMaxTimeNs) {
        t_ns = kMaxTimeNs;
      }
      store(p + m.time_offset, static_cast<std::uint32_t>(t_ns));
    }
    if (m.layout.ring) {
      store(p + m.ring_offset, rings.empty() ? std::uint16_t{0} : rings[i]);
    }
  }
  m.msg.is_dense = dense;
}

std::uint32_t PointCloudMessage::capacity() const noexcept { return impl_->capacity; }
std::uint32_t PointCloudMessage::pointStep() const noexcept { return impl_->point_step; }
const CloudLayout& PointCloudMessage::layout() const noexcept { return impl_->layout; }

const void* PointCloudMessage::sample() const noexcept { return &impl_->msg; }

const dds_topic_descriptor_t* PointCloudMessage::descriptor() noexcept { return pointCloud2Type(); }

}  // namespace raymap::dds
