// SPDX-License-Identifier: BSD-3-Clause
// The built-in yard scene, simulated with the general scene and lidar code.
#include "src/sim/yard_scan.hpp"

#include <algorithm>
#include <utility>

namespace raymap::sim {

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
  Scene scene;
  scene.name = "yard";
  scene.boxes = config.solids.empty() ? yardSolids() : config.solids;
  SimulationConfig simulation;
  simulation.lidar = config.lidar;
  simulation.scans = config.scans;
  simulation.seed = config.seed;
  simulation.sampling = PoseSampling::kPerScan;
  if (config.scans > 0) {
    std::vector<SensorPose> stops;
    for (int s = 0; s < config.scans; ++s) {
      const double f = config.scans > 1 ? static_cast<double>(s) / (config.scans - 1) : 0.0;
      stops.push_back(
          {s * config.lidar.scan_period_s, config.start + (config.end - config.start) * f, 0.0});
    }
    auto path = SensorPath::fromPoses(std::move(stops));
    RAYMAP_EXPECTS(path.has_value());  // fails only for a scan period <= 0
    simulation.path = std::move(*path);
  }
  return simulateScans(scene, simulation);
}

}  // namespace raymap::sim
