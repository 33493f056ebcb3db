// SPDX-License-Identifier: BSD-3-Clause
// Feeds sensor-frame lidar sweeps with the sensor's pose at each point's time through
// raymap::Mapper (as a driver with odometry would), then writes a height map around the robot.
// The world: a floor at z = 0 and a 0.3 m step (a box from x = 3 to 4 m, y = -1 to 1 m). The
// robot drives along +x at 0.5 m/s; its lidar, 1 m above the floor, sweeps once per 0.1 s.
// --rolling keeps a robot-centric window instead (25.6 m x 25.6 m x 9.6 m, as raymapd does),
// moved to the robot before each sweep.
//   heightmap_from_scans OUT.csv [--backend cpu|opencl|cuda] [--rolling]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <raymap/mapper.hpp>

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSpeed = 0.5;        // m/s along +x
constexpr double kSweepPeriod = 0.1;  // s
constexpr double kSensorHeight = 1.0;
constexpr double kMaxRange = 12.0;

/// The sensor's pose (sensor to world) at time t: driving along +x, heading +x.
Eigen::Isometry3d sensorPose(double t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(kSpeed * t, 0.0, kSensorHeight);
  return pose;
}

/// Distance along a world ray to the floor or the step, or kMaxRange when it hits nothing.
double castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  double nearest = kMaxRange;
  if (direction.z() < 0.0) {
    nearest = std::min(nearest, -origin.z() / direction.z());
  }
  // The step: the box [3, 4] x [-1, 1] x [0, 0.3] (slab intersection).
  const Eigen::Vector3d lo(3.0, -1.0, 0.0);
  const Eigen::Vector3d hi(4.0, 1.0, 0.3);
  double enter = 0.0;
  double leave = kMaxRange;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(direction[axis]) < 1e-12) {
      if (origin[axis] < lo[axis] || origin[axis] > hi[axis]) {
        return nearest;
      }
      continue;
    }
    double a = (lo[axis] - origin[axis]) / direction[axis];
    double b = (hi[axis] - origin[axis]) / direction[axis];
    if (a > b) {
      std::swap(a, b);
    }
    enter = std::max(enter, a);
    leave = std::min(leave, b);
  }
  return enter <= leave ? std::min(nearest, enter) : nearest;
}

/// One sweep starting at t0: 360 azimuths x 16 elevations (-25 to -2 degrees), sensor frame.
/// Points with no return within kMaxRange are marked so (they clear free space).
std::vector<raymap::SensorPoint> sweep(double t0) {
  std::vector<raymap::SensorPoint> points;
  for (int a = 0; a < 360; ++a) {
    const double t = t0 + kSweepPeriod * a / 360.0;
    const Eigen::Isometry3d pose = sensorPose(t);
    const double azimuth = 2.0 * kPi * a / 360.0;
    for (int e = 0; e < 16; ++e) {
      const double elevation = (-25.0 + 23.0 * e / 15.0) * kPi / 180.0;
      const Eigen::Vector3d direction(std::cos(elevation) * std::cos(azimuth),
                                      std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const double range = castRay(pose.translation(), pose.linear() * direction);
      raymap::SensorPoint p;
      p.position = range * direction;
      p.time_s = t;
      p.no_return = range >= kMaxRange;
      points.push_back(p);
    }
  }
  return points;
}

const char* kindName(raymap::HeightCell kind) {
  switch (kind) {
    case raymap::HeightCell::kSurface:
      return "surface";
    case raymap::HeightCell::kVirtualSurface:
      return "virtual";
    case raymap::HeightCell::kVacant:
      return "vacant";
    case raymap::HeightCell::kUnknown:
      break;
  }
  return "unknown";
}

}  // namespace

int main(int argc, char** argv) {
  raymap::MapperConfig config;
  config.map.resolution = 0.1;
  config.map.max_memory_bytes = std::uint64_t{512} << 20;
  bool usage = argc < 2;
  for (int i = 2; i < argc && !usage; ++i) {
    const std::string flag = argv[i];
    if (flag == "--backend" && i + 1 < argc) {
      config.backend.name = argv[++i];
    } else if (flag == "--rolling") {
      config.map.window = Eigen::Vector3i(8, 8, 3);  // regions of 32 voxels: 3.2 m each
    } else {
      usage = true;
    }
  }
  if (usage) {
    std::fprintf(stderr,
                 "usage: heightmap_from_scans OUT.csv [--backend cpu|opencl|cuda] [--rolling]\n");
    return 2;
  }
  auto mapper = raymap::Mapper::create(config);
  if (!mapper) {
    std::fprintf(stderr, "heightmap_from_scans: %s\n", mapper.error().message.c_str());
    return 1;
  }
  // Four seconds of driving: 40 sweeps, each deskewed with the pose at every point's time.
  const raymap::SensorPoseFunction pose_at = [](double t) -> std::optional<Eigen::Isometry3d> {
    return sensorPose(t);
  };
  for (int s = 0; s < 40; ++s) {
    // A rolling window follows the robot (a map without one ignores this).
    if (auto moved = mapper->moveWindow(sensorPose(s * kSweepPeriod).translation()); !moved) {
      std::fprintf(stderr, "heightmap_from_scans: %s\n", moved.error().message.c_str());
      return 1;
    }
    const std::vector<raymap::SensorPoint> points = sweep(s * kSweepPeriod);
    if (auto ok = mapper->integrate(points, pose_at); !ok) {
      std::fprintf(stderr, "heightmap_from_scans: %s\n", ok.error().message.c_str());
      return 1;
    }
  }
  // A 10 m height map around the robot's last position, searched around the floor's height.
  raymap::HeightmapRequest request;
  request.centre = Eigen::Vector3d(kSpeed * 4.0, 0.0, 0.0);
  request.size = 10.0;
  request.min_clearance = 0.5;
  auto map = mapper->heightmap(request);
  if (!map) {
    std::fprintf(stderr, "heightmap_from_scans: %s\n", map.error().message.c_str());
    return 1;
  }
  std::ofstream csv(argv[1]);
  csv << "x,y,elevation,clearance,kind\n";
  for (int j = 0; j < map->cells_y; ++j) {
    for (int i = 0; i < map->cells_x; ++i) {
      const std::size_t k = map->index(i, j);
      const Eigen::Vector2d c = map->cellCentre(i, j);
      csv << c.x() << ',' << c.y() << ',' << map->elevation[k] << ',' << map->clearance[k] << ','
          << kindName(map->kind[k]) << '\n';
    }
  }
  csv.close();
  if (!csv) {
    std::fprintf(stderr, "heightmap_from_scans: cannot write %s\n", argv[1]);
    return 1;
  }
  // The elevation on the step and on the floor beside it.
  for (const Eigen::Vector2d& at : {Eigen::Vector2d(3.55, 0.05), Eigen::Vector2d(1.05, 2.55)}) {
    for (int j = 0; j < map->cells_y; ++j) {
      for (int i = 0; i < map->cells_x; ++i) {
        if ((map->cellCentre(i, j) - at).norm() < 1e-6) {
          const std::size_t k = map->index(i, j);
          std::printf("elevation at (%.2f, %.2f): %.3f m (%s)\n", at.x(), at.y(), map->elevation[k],
                      kindName(map->kind[k]));
        }
      }
    }
  }
  std::printf("backend %s, %llu rays integrated, %llu voxels occupied\n",
              mapper->backendName().c_str(),
              static_cast<unsigned long long>(mapper->counters().rays_integrated),
              static_cast<unsigned long long>(mapper->counts().voxels_occupied));
  return 0;
}
