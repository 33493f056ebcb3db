// SPDX-License-Identifier: BSD-3-Clause
// SimulatedLidar: one scan of sim::simulateScans at a time, turned back into the sensor frame.
#include "src/driver/simulated_lidar.hpp"

#include <cmath>
#include <limits>

#include "src/core/eigen_conversions.hpp"

namespace raymap::driver {

SimulatedLidar::SimulatedLidar(sim::Scene scene, sim::SimulationConfig config)
    : scene_(std::move(scene)), config_(std::move(config)) {}

std::uint32_t SimulatedLidar::pointsPerScan() const noexcept {
  return static_cast<std::uint32_t>(config_.lidar.beams) *
         static_cast<std::uint32_t>(config_.lidar.columns);
}

io::Pose SimulatedLidar::poseAt(double time_s) const {
  const sim::SensorPose p = config_.path.at(config_.path.startTime() + time_s);
  // The sensor stays level: its orientation is the heading, a turn about +z.
  return io::Pose{toEigen(p.position),
                  Eigen::Quaterniond(Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()))};
}

void SimulatedLidar::scan(std::uint64_t k, std::vector<msgs::ScanPoint>& points,
                          std::vector<std::uint16_t>& rings) const {
  // Simulate only scan k: a one-scan recording along the piece of the path it covers, shifted
  // to start at time 0 (knots every tenth of the scan keep the motion within the scan).
  const double period = config_.lidar.scan_period_s;
  const double start = config_.path.startTime() + static_cast<double>(k) * period;
  std::vector<sim::SensorPose> knots;
  constexpr int kKnots = 10;
  for (int i = 0; i <= kKnots; ++i) {
    sim::SensorPose pose = config_.path.at(start + period * i / kKnots);
    pose.time_s = period * i / kKnots;
    knots.push_back(pose);
  }
  sim::SimulationConfig one = config_;
  one.path = sim::SensorPath::fromPoses(std::move(knots)).value();
  one.scans = 1;
  one.seed = config_.seed + k;
  const std::vector<Ray> rays = sim::simulateScans(scene_, one);
  points.resize(rays.size());
  rings.resize(rays.size());
  const auto beams = static_cast<std::size_t>(config_.lidar.beams);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& ray = rays[i];
    const double yaw = one.path.at(ray.time_s).yaw_rad;
    const Vec3d d = ray.sample - ray.origin;
    const double c = std::cos(yaw);
    const double s = std::sin(yaw);
    msgs::ScanPoint& p = points[i];
    if ((ray.flags & kRayNoReturn) != 0u) {
      p.x = p.y = p.z = nan;
      p.flags = msgs::kPointNoReturn;
    } else {
      // World direction into the level sensor frame: rotate by -yaw about z.
      p.x = static_cast<float>(c * d.x + s * d.y);
      p.y = static_cast<float>(-s * d.x + c * d.y);
      p.z = static_cast<float>(d.z);
      p.flags = 0;
    }
    p.time_s = static_cast<float>(ray.time_s);
    p.intensity = ray.intensity;
    rings[i] = static_cast<std::uint16_t>(i % beams);
  }
}

}  // namespace raymap::driver
