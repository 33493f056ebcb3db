// SPDX-License-Identifier: BSD-3-Clause
#include "tests/rosbag/bag_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include "src/core/eigen_conversions.hpp"
#include "src/driver/simulated_lidar.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pose_history.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/support/bag_spec.hpp"

namespace raymap::test {
namespace {

constexpr std::int64_t kT0 = 1700000000000000000;   // the drive's first scan stamp, ns
constexpr std::int64_t kOdometryPeriod = 10000000;  // 100 Hz

std::string harnessDir() { return std::string(RAYMAP_SOURCE_DIR) + "/tests/rosbag/node"; }

/// The quaternion as the ROS decoders leave it (divided by its norm), iterated to a fixed point,
/// so that what the test computes with is bit for bit what raymap decodes.
Eigen::Quaterniond decoderStable(Eigen::Quaterniond q) {
  for (int i = 0; i < 8; ++i) {
    const Eigen::Quaterniond next = q.normalized();  // what msgs::decodeOdometry/TfMessage do
    if (next.coeffs() == q.coeffs()) {
      break;
    }
    q = next;
  }
  return q;
}

io::Pose inverse(const io::Pose& p) {
  const Eigen::Quaterniond conj = p.orientation.conjugate();
  return io::Pose{-(conj * p.position), conj};
}

}  // namespace

bool nodeHarnessReady(std::string* why) {
  const RunResult node = runProgram({"node", "--version"});
  if (node.exit_code != 0) {
    *why = "Node.js is not installed (tools/setup-node.sh installs it)";
  } else if (!std::filesystem::exists(harnessDir() + "/node_modules/@mcap/core")) {
    *why = "the harness's npm packages are not installed (run tools/setup-node.sh)";
  } else {
    return true;
  }
  const char* required = std::getenv("RAYMAP_REQUIRE_NODE_HARNESS");
  if (required != nullptr && std::string(required) == "1") {
    ADD_FAILURE() << *why << " and RAYMAP_REQUIRE_NODE_HARNESS=1";
  }
  return false;
}

RunResult runHarness(const std::string& script, const std::vector<std::string>& args) {
  std::vector<std::string> words{"node", harnessDir() + "/" + script};
  words.insert(words.end(), args.begin(), args.end());
  return runProgram(words);
}

void writeBag(const std::string& spec, const std::string& out,
              const std::vector<std::string>& options) {
  std::vector<std::string> args{spec, out};
  args.insert(args.end(), options.begin(), options.end());
  const RunResult r = runHarness("write_bag.mjs", args);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
}

std::vector<msgs::ScanPoint> ringCloud(std::size_t n) {
  std::vector<msgs::ScanPoint> points(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 0.1 * static_cast<double>(i);
    points[i] = {static_cast<float>(5.0 * std::cos(a)),
                 static_cast<float>(5.0 * std::sin(a)),
                 -0.5f,
                 0.001f * static_cast<float>(i),
                 1.0f,
                 0u};
  }
  return points;
}

PlyTestFile float64RayCloud() {
  PlyTestFile ply;
  std::vector<PlyTestProperty> properties;
  for (const char* name : {"x", "y", "z", "nx", "ny", "nz", "time"}) {
    properties.push_back({"double", name, ""});
  }
  ply.elements.emplace_back("vertex", std::move(properties));
  return ply;
}

void addRay(PlyTestFile& ply, Vec3d origin, Vec3d sample, double time_s) {
  const Vec3d normal = origin - sample;
  ply.elements.front().add({sample.x, sample.y, sample.z, normal.x, normal.y, normal.z, time_s});
}

Drive makeDrive(const TempDir& dir, DrivePoses poses, int scans) {
  Drive drive;
  auto file = sim::loadSceneFile(std::string(RAYMAP_SCENES_DIR) + "/yard.yaml");
  EXPECT_TRUE(file.has_value());
  sim::SimulationConfig simulation = file.value().simulation;
  simulation.lidar.beams = 16;
  simulation.lidar.columns = 256;
  const driver::SimulatedLidar lidar(file.value().scene, simulation);
  drive.scene = file.value().scene;
  drive.scans = static_cast<std::size_t>(scans);

  // The lidar 0.3 m ahead of and 1.2 m above base_link, turned half round (an exactly unit
  // quaternion, so decoding it changes nothing).
  const io::Pose extrinsic{{0.3, 0.0, 1.2}, {0.0, 0.0, 0.0, 1.0}};
  const io::Pose sensor_to_base = inverse(extrinsic);
  const auto period = static_cast<std::int64_t>(std::llround(lidar.scanPeriod() * 1e9));
  const auto baseAt = [&](std::int64_t stamp) {
    io::Pose b = io::compose(lidar.poseAt(static_cast<double>(stamp - kT0) * 1e-9), sensor_to_base);
    b.orientation = decoderStable(b.orientation);
    return b;
  };
  drive.centre = toVec3(baseAt(kT0 + period * scans / 2).position);

  drive.spec = dir.file("drive.jsonl");
  BagSpecWriter spec(drive.spec);
  const bool odometry = poses == DrivePoses::kOdometry;
  spec.channel("/tf_static", "tf2_msgs/msg/TFMessage",
               "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n");
  spec.channel(odometry ? "/odom" : "/tf",
               odometry ? "nav_msgs/msg/Odometry" : "tf2_msgs/msg/TFMessage");
  spec.channel("/ouster/points", "sensor_msgs/msg/PointCloud2");
  std::vector<SpecTransform> statics{{kT0, "base_link", "os_sensor", extrinsic}};
  if (!odometry) {
    statics.push_back({kT0, "map", "odom", io::Pose{}});
  }
  spec.tf("/tf_static", kT0 - 1000000000, statics);

  pipeline::PoseHistory history(4096);
  pipeline::PointDeskewer deskewer;
  PlyTestFile ply = float64RayCloud();

  std::int64_t next_pose = kT0 - 5 * kOdometryPeriod;
  std::vector<msgs::ScanPoint> points;
  std::vector<std::uint16_t> rings;
  std::vector<std::pair<std::int64_t, std::vector<msgs::ScanPoint>>> pending;  // stamp, points
  for (int k = 0; k <= scans; ++k) {
    const std::int64_t stamp = kT0 + period * k;
    const std::int64_t logged = stamp + period + 1;  // a driver publishes at the scan's end
    // Poses up to this scan's log time, then the scan itself.
    while (next_pose < logged && (k < scans || next_pose <= stamp + 5 * kOdometryPeriod)) {
      const io::Pose b = baseAt(next_pose);
      if (odometry) {
        spec.odometry("/odom", next_pose, next_pose, "odom", "base_link", b);
      } else {
        spec.tf("/tf", next_pose, {{next_pose, "odom", "base_link", b}});
      }
      EXPECT_TRUE(history.push(next_pose, b));
      next_pose += kOdometryPeriod;
    }
    if (k == scans) {
      break;
    }
    lidar.scan(static_cast<std::uint64_t>(k), points, rings);
    spec.ousterCloud("/ouster/points", logged, stamp, "os_sensor", points, rings);
    // The points as raymap decodes them: float coordinates; the time written as integer
    // nanoseconds and read back as float seconds; (0, 0, 0) and NaN are no-returns.
    std::vector<msgs::ScanPoint> decoded;
    for (const msgs::ScanPoint& p : points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
          (p.x == 0.0f && p.y == 0.0f && p.z == 0.0f)) {
        continue;
      }
      msgs::ScanPoint q = p;
      const auto ns = static_cast<std::uint32_t>(std::llround(double(p.time_s) * 1e9));
      q.time_s = static_cast<float>(static_cast<double>(ns) * 1e-9);
      q.flags = 0;
      decoded.push_back(q);
    }
    pending.emplace_back(stamp, std::move(decoded));
  }
  for (std::size_t k = 0; k < pending.size(); ++k) {
    for (const msgs::ScanPoint& p : pending[k].second) {
      Ray ray;
      if (!deskewer.toRay(p, pending[k].first, history, 20000000, extrinsic, k, ray)) {
        ADD_FAILURE() << "no pose for a point of scan " << k;
        continue;
      }
      addRay(ply, ray.origin, ray.sample, ray.time_s);
      ++drive.rays;
    }
    deskewer.reset();
  }
  EXPECT_TRUE(spec.ok());
  drive.ply = dir.file("drive.ply");
  writePly(drive.ply, ply);
  return drive;
}

}  // namespace raymap::test
