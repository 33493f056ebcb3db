// SPDX-License-Identifier: BSD-3-Clause
// Ray casting against the floor and the four walls of the room.
#include "tests/fastdds/peer/room_lidar.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace raymap::fastdds_peer {
namespace {

constexpr double kNoHit = std::numeric_limits<double>::infinity();

/// Distance along `d` from `o` to the plane coordinate = `at` of one axis (kNoHit behind).
double toPlane(double o, double d, double at) {
  if (d == 0.0) {
    return kNoHit;
  }
  const double s = (at - o) / d;
  if (s <= 0.0) {
    return kNoHit;  // behind
  }
  return s;
}

/// Distance to the first surface of the room along the unit direction `d` from `o`.
double cast(const RoomLidar& room, const Vec3& o, const Vec3& d) {
  const double w = room.half_width_m;
  double wall =
      std::min(toPlane(o.x, d.x, d.x > 0.0 ? w : -w), toPlane(o.y, d.y, d.y > 0.0 ? w : -w));
  if (wall != kNoHit) {
    const double z = o.z + wall * d.z;
    if (z < 0.0 || z > room.wall_height_m) {
      wall = kNoHit;  // under the floor (the floor is nearer) or over the wall
    }
  }
  const double floor = d.z < 0.0 ? toPlane(o.z, d.z, 0.0) : kNoHit;
  return std::min(wall, floor);
}

}  // namespace

void sweep(const RoomLidar& lidar, Vec3 origin, Vec3 velocity, std::vector<LidarPoint>& points) {
  points.clear();
  const double to_rad = std::numbers::pi / 180.0;
  for (int c = 0; c < lidar.columns; ++c) {
    const double t_s = lidar.scan_period_s * c / lidar.columns;
    const Vec3 o{origin.x + velocity.x * t_s, origin.y + velocity.y * t_s,
                 origin.z + velocity.z * t_s};
    const double azimuth = 2.0 * std::numbers::pi * c / lidar.columns;
    for (int b = 0; b < lidar.beams; ++b) {
      const double step =
          lidar.beams > 1 ? (lidar.highest_deg - lidar.lowest_deg) / (lidar.beams - 1) : 0.0;
      const double elevation = (lidar.lowest_deg + step * b) * to_rad;
      const Vec3 d{std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                   std::sin(elevation)};
      const double s = cast(lidar, o, d);
      if (s == kNoHit) {
        continue;
      }
      points.push_back({static_cast<float>(s * d.x), static_cast<float>(s * d.y),
                        static_cast<float>(s * d.z), static_cast<std::uint32_t>(t_s * 1e9)});
    }
  }
}

}  // namespace raymap::fastdds_peer
