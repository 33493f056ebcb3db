// SPDX-License-Identifier: BSD-3-Clause
// A spinning lidar in a square room with a flat floor: what the peer's simulated driver scans.
#pragma once

#include <cstdint>
#include <vector>

namespace raymap::fastdds_peer {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};

/// @brief The room (floor z = 0, four walls at x, y = +-half_width_m up to wall_height_m) and
/// the lidar: `beams` rows evenly from lowest_deg to highest_deg of elevation, `columns` azimuths
/// a revolution, one revolution per scan_period_s.
struct RoomLidar {
  double half_width_m = 5.0;
  double wall_height_m = 2.0;
  int beams = 16;
  int columns = 512;
  double lowest_deg = -25.0;
  double highest_deg = 5.0;
  double scan_period_s = 0.1;
};

/// @brief A return in the lidar's frame (axes parallel to the room's: the robot does not turn)
/// and its time after the scan's start, nanoseconds.
struct LidarPoint {
  float x = 0.0f, y = 0.0f, z = 0.0f;
  std::uint32_t t_ns = 0;
};

/// @brief One revolution of `lidar` starting at `origin` (the sensor in the room) and moving at
/// `velocity` (metres per second) while it turns. Beams that hit nothing are left out.
/// @param[out] points cleared, then the returns column by column
void sweep(const RoomLidar& lidar, Vec3 origin, Vec3 velocity, std::vector<LidarPoint>& points);

}  // namespace raymap::fastdds_peer
