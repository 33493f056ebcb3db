// SPDX-License-Identifier: BSD-3-Clause
// The preallocated OccupancyGrid message: the data sequence points into a buffer owned by the
// Impl, with _release false so that Cyclone never frees it.
#include "src/dds/occupancy_grid_message.hpp"

#include <vector>

#include "nav_msgs.h"
#include "raymap/assert.hpp"

#include "src/dds/frame_id.hpp"
#include "src/dds/ros_time.hpp"
#include "src/dds/topic_types.hpp"

namespace raymap::dds {

/// Design: one heap block per message, so that moving the object keeps the addresses inside
/// `msg` valid.
struct OccupancyGridMessage::Impl {
  nav_msgs_msg_dds__OccupancyGrid_ msg{};
  char frame_id[64] = {};
  std::vector<std::int8_t> data;
};

OccupancyGridMessage::OccupancyGridMessage(int width, int height)
    : impl_(std::make_unique<Impl>()) {
  RAYMAP_EXPECTS(width > 0 && height > 0);
  Impl& m = *impl_;
  const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  m.data.assign(cells, -1);
  m.msg.header.frame_id = m.frame_id;
  m.msg.info.width = static_cast<std::uint32_t>(width);
  m.msg.info.height = static_cast<std::uint32_t>(height);
  m.msg.info.origin.orientation.w = 1.0;
  m.msg.data._buffer = m.data.data();
  m.msg.data._length = static_cast<std::uint32_t>(cells);
  m.msg.data._maximum = static_cast<std::uint32_t>(cells);
  m.msg.data._release = false;
}

OccupancyGridMessage::OccupancyGridMessage(OccupancyGridMessage&&) noexcept = default;
OccupancyGridMessage& OccupancyGridMessage::operator=(OccupancyGridMessage&&) noexcept = default;
OccupancyGridMessage::~OccupancyGridMessage() = default;

std::span<std::int8_t> OccupancyGridMessage::cells() noexcept { return impl_->data; }

void OccupancyGridMessage::fill(double resolution, Vec3d origin, std::int64_t stamp_ns,
                                const char* frame_id) noexcept {
  Impl& m = *impl_;
  setRosTime(m.msg.header.stamp, stamp_ns);
  setRosTime(m.msg.info.map_load_time, stamp_ns);
  copyFrameId(m.frame_id, frame_id);
  m.msg.info.resolution = static_cast<float>(resolution);
  m.msg.info.origin.position.x = origin.x;
  m.msg.info.origin.position.y = origin.y;
  m.msg.info.origin.position.z = origin.z;
}

const void* OccupancyGridMessage::sample() const noexcept { return &impl_->msg; }

const dds_topic_descriptor_t* OccupancyGridMessage::descriptor() noexcept {
  return occupancyGridType();
}

}  // namespace raymap::dds
