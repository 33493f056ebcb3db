// SPDX-License-Identifier: BSD-3-Clause
// Feeding a pipeline::Integrator as raymapd's ingest thread does: base poses and sensor
// extrinsics into its pose queue, decoded scans into its mailbox. For the integrator's tests on
// the CPU and on devices.
#pragma once

#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/trajectory.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"

namespace raymap::test {

/// Queues the base's pose in the world at `stamp_ns` (the pose source's clock).
inline void pushBasePose(pipeline::PoseQueue& queue, std::int64_t stamp_ns,
                         const io::Pose& base_in_world) {
  pipeline::PoseUpdate u;
  u.stamp_ns = stamp_ns;
  u.pose = base_in_world;
  u.kind = pipeline::PoseUpdate::kBaseInWorld;
  ASSERT_TRUE(queue.push(u));
}

/// Queues sensor `sensor`'s pose in the base frame.
inline void pushSensorExtrinsic(pipeline::PoseQueue& queue, std::uint32_t sensor,
                                const io::Pose& sensor_in_base) {
  pipeline::PoseUpdate u;
  u.pose = sensor_in_base;
  u.sensor = sensor;
  u.kind = pipeline::PoseUpdate::kSensorExtrinsic;
  ASSERT_TRUE(queue.push(u));
}

/// Publishes a scan of `points` (per-point times) stamped `stamp_ns` from `sensor`.
inline void publishScan(pipeline::ScanMailbox& mailbox, std::int64_t stamp_ns,
                        const std::vector<msgs::ScanPoint>& points, std::uint32_t sensor,
                        std::int64_t arrival_ns) {
  pipeline::ScanSlot* slot = mailbox.acquire();
  ASSERT_NE(slot, nullptr);
  ASSERT_LE(points.size(), slot->buffer.size());
  slot->header = msgs::CloudHeader{};
  slot->header.stamp_ns = stamp_ns;
  slot->header.points = static_cast<std::uint32_t>(points.size());
  slot->header.width = slot->header.points;
  slot->header.height = 1;
  slot->header.has_time = true;
  slot->sensor = sensor;
  slot->arrival_ns = arrival_ns;
  for (std::size_t i = 0; i < points.size(); ++i) {
    slot->buffer[i] = points[i];
  }
  mailbox.publish(slot);
}

}  // namespace raymap::test
