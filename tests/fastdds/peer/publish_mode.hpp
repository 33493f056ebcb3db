// SPDX-License-Identifier: BSD-3-Clause
// `raymap-fastdds-peer publish`: a lidar driver and an odometry source as Fast DDS nodes publish
// them.
#pragma once

#include <string>

#include "tests/fastdds/peer/json_result.hpp"
#include "tests/fastdds/peer/peer_participant.hpp"
#include "tests/fastdds/peer/room_lidar.hpp"

namespace raymap::fastdds_peer {

struct PublishOptions {
  double seconds = 10.0;
  double scan_rate_hz = 10.0;
  double odometry_rate_hz = 50.0;
  double speed_mps = 0.0;  ///< the robot drives along +x at this speed (0: it stands still)
  RoomLidar lidar;         ///< its scan_period_s is 1 / scan_rate_hz
  /// Hold the clouds until a reader of /tf_static has acknowledged the transform, as on a robot
  /// whose robot_state_publisher latched it before the lidar driver started.
  bool clouds_after_tf_static = false;
  /// With clouds_after_tf_static: how many readers must have acknowledged /tf_static, and
  /// matched the clouds, before the lidar starts (every one of a known set of subscribers gets
  /// every cloud).
  std::int64_t readers = 1;
  /// Odometry goes on for this long after the last cloud (the lidar stops at `seconds`), so that
  /// every cloud has a pose after its end: a reader that waits pose.max_wait_s for it gets it.
  double odometry_tail_s = 0.0;
  std::string points_topic = "rt/points";
  std::string odom_topic = "rt/odom";
  std::string tf_static_topic = "rt/tf_static";
  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  std::string lidar_frame = "lidar";
};

/// @brief base_link in the room when the robot starts (x, y = 0), and the lidar on it: the
/// transform /tf_static publishes.
inline constexpr Vec3 kBaseStart{0.0, 0.0, 1.0};
inline constexpr Vec3 kLidarInBase{0.1, 0.0, 0.3};

/// @brief Publishes /tf_static base -> lidar once (reliable, transient local: latched), then
/// odometry world -> base (reliable, keep last 10) at odometry_rate_hz and a PointCloud2 in the
/// lidar's frame (best effort, keep last 5) at scan_rate_hz, stamped with the wall clock, each
/// scan when its revolution has ended; until `seconds` have passed or SIGINT/SIGTERM, and the
/// odometry `odometry_tail_s` longer. With clouds_after_tf_static the lidar waits too until the
/// odometry's readers have matched and one odometry message was written to them, so that each
/// reader has a pose from before the first scan.
/// @param[out] result what was published, how many readers matched, and when /tf_static was
/// first acknowledged by every matched reader (at least one), after the start
/// @return false when an endpoint could not be created (result says which)
bool runPublish(PeerParticipant& participant, const PublishOptions& options, Json& result);

}  // namespace raymap::fastdds_peer
