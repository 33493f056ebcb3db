// SPDX-License-Identifier: BSD-3-Clause
// rosbag2 fixtures for the tests: a simulated drive written as a bag by Foxglove's libraries
// (tests/rosbag/node), and the same rays as a ray-cloud PLY computed without any bag.
#pragma once

#include <string>
#include <vector>

#include "src/io/trajectory.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/sim/scene.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {

/// @brief True when Node.js and the harness's npm packages are installed (tools/setup-node.sh).
/// Without them the bag tests skip, unless RAYMAP_REQUIRE_NODE_HARNESS=1 (CI) makes that a
/// failure.
bool nodeHarnessReady(std::string* why);

/// @brief Skips the test (GTEST_SKIP) when the harness is missing, naming why.
#define REQUIRE_NODE_HARNESS()     \
  do {                             \
    std::string why;               \
    if (!nodeHarnessReady(&why)) { \
      GTEST_SKIP() << why;         \
    }                              \
  } while (false)

/// @brief A ray-cloud PLY with float64 ends, normals (origin - end) and time: the rays exactly.
PlyTestFile float64RayCloud();
/// @brief Appends one ray to a float64RayCloud().
void addRay(PlyTestFile& ply, Vec3d origin, Vec3d sample, double time_s);

/// @brief node tests/rosbag/node/SCRIPT ARGS...
RunResult runHarness(const std::string& script, const std::vector<std::string>& args);

/// @brief How the drive publishes its poses.
enum class DrivePoses {
  kOdometry,  ///< nav_msgs/Odometry on /odom (frame odom, child base_link), 100 Hz
  kTfChain,   ///< /tf odom -> base_link at 100 Hz, under a /tf_static map -> odom (identity)
};

/// @brief A simulated drive through the yard scene: an Ouster-like lidar (frame os_sensor,
/// mounted on base_link by a /tf_static sent first), 10 Hz scans with per-point time.
struct Drive {
  std::string spec;  ///< the bag's JSON-lines description (tests/rosbag/node/README.md)
  std::string ply;   ///< the same rays, deskewed, as a float64 ray-cloud PLY
  sim::Scene scene;
  Vec3d centre;  ///< the base's position in the middle of the drive
  std::size_t scans = 0;
  std::size_t rays = 0;  ///< returns (the PLY's rays)
};

/// @brief Writes the drive's spec and PLY into `dir`.
Drive makeDrive(const TempDir& dir, DrivePoses poses, int scans);

/// @brief `n` points on a 5 m ring half a metre below the sensor, 1 ms apart in time: a small
/// cloud for bags built by hand.
std::vector<msgs::ScanPoint> ringCloud(std::size_t n);

/// @brief Writes `spec` as a bag at `out` with write_bag.mjs `options` (e.g. --compression zstd).
/// Fails the test when the harness fails.
void writeBag(const std::string& spec, const std::string& out,
              const std::vector<std::string>& options);

}  // namespace raymap::test
