// SPDX-License-Identifier: BSD-3-Clause
// Analytic ray casting for the built-in yard scene.
#include "src/sim/yard_scan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace raymap::sim {
namespace {

/// Distance along the unit direction d from o to the entry of a solid box (or +inf).
double hitBox(const Box& box, Vec3d o, Vec3d d) {
  double t_enter = 0.0;
  double t_exit = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < box.min[a] || o[a] > box.max[a]) {
        return std::numeric_limits<double>::infinity();
      }
      continue;
    }
    double t0 = (box.min[a] - o[a]) / d[a];
    double t1 = (box.max[a] - o[a]) / d[a];
    if (t0 > t1) {
      std::swap(t0, t1);
    }
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    if (t_enter > t_exit) {
      return std::numeric_limits<double>::infinity();
    }
  }
  return t_enter > 0.0 ? t_enter : std::numeric_limits<double>::infinity();
}

}  // namespace

std::vector<Box> yardSolids() {
  return {
      // Walls of a 24 m x 16 m yard, 2.5 m high, 0.3 m thick.
      {{-12.3, -8.3, 0.0}, {12.3, -8.0, 2.5}},
      {{-12.3, 8.0, 0.0}, {12.3, 8.3, 2.5}},
      {{-12.3, -8.0, 0.0}, {-12.0, 8.0, 2.5}},
      {{12.0, -8.0, 0.0}, {12.3, 8.0, 2.5}},
      // Crates, a pillar and a table top (an overhang with free space below).
      {{-7.0, 3.0, 0.0}, {-5.8, 4.2, 1.2}},
      {{2.5, -5.0, 0.0}, {3.5, -4.0, 0.8}},
      {{6.0, 3.5, 0.0}, {6.3, 3.8, 2.5}},
      {{-1.5, 4.0, 0.72}, {0.5, 5.0, 0.76}},
  };
}

double distanceToSurface(Vec3d p, const std::vector<Box>& solids) {
  double best = std::max(p.z, 0.0);  // the ground plane; below it counts as inside
  for (const Box& box : solids) {
    Vec3d outside;
    for (int a = 0; a < 3; ++a) {
      outside[a] = std::max({box.min[a] - p[a], 0.0, p[a] - box.max[a]});
    }
    best = std::min(best, outside.norm());
  }
  return best;
}

std::vector<Ray> simulateYardScans(const YardScanConfig& config) {
  const std::vector<Box> solids = config.solids.empty() ? yardSolids() : config.solids;
  const LidarModel& lidar = config.lidar;
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> noise(0.0,
                                         lidar.range_noise_m > 0.0 ? lidar.range_noise_m : 1.0);
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(config.scans) * static_cast<std::size_t>(lidar.beams) *
               static_cast<std::size_t>(lidar.columns));
  const double deg = std::numbers::pi / 180.0;
  for (int s = 0; s < config.scans; ++s) {
    const double f = config.scans > 1 ? static_cast<double>(s) / (config.scans - 1) : 0.0;
    const Vec3d origin = config.start + (config.end - config.start) * f;
    for (int c = 0; c < lidar.columns; ++c) {
      const double azimuth = 2.0 * std::numbers::pi * c / lidar.columns;
      const double time = s * lidar.scan_period_s + lidar.scan_period_s * c / lidar.columns;
      for (int b = 0; b < lidar.beams; ++b) {
        const double elevation =
            (lidar.beams > 1
                 ? lidar.elevation_min_deg +
                       (lidar.elevation_max_deg - lidar.elevation_min_deg) * b / (lidar.beams - 1)
                 : lidar.elevation_min_deg) *
            deg;
        const Vec3d dir{std::cos(elevation) * std::cos(azimuth),
                        std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
        double range = std::numeric_limits<double>::infinity();
        if (dir.z < 0.0) {
          range = -origin.z / dir.z;  // ground plane z = 0
        }
        for (const Box& box : solids) {
          range = std::min(range, hitBox(box, origin, dir));
        }
        Ray ray;
        ray.origin = origin;
        ray.time_s = time;
        ray.scan = static_cast<std::uint64_t>(s);
        if (range > lidar.max_range_m) {
          ray.sample = origin + dir * lidar.max_range_m;
          ray.flags = kRayNoReturn;
        } else {
          const double measured = lidar.range_noise_m > 0.0 ? range + noise(rng) : range;
          ray.sample = origin + dir * std::max(measured, 0.0);
          ray.intensity = static_cast<float>(100.0 / (1.0 + range));
        }
        rays.push_back(ray);
      }
    }
  }
  return rays;
}

}  // namespace raymap::sim
