// SPDX-License-Identifier: BSD-3-Clause
// The shared Ouster OS-1-128 drive (three real 128 x 1024 scans) converted to a rosbag2 bag by
// Foxglove's libraries: one PointCloud2 per scan in the sensor frame in the Ouster driver's
// layout, Odometry at each scan's origin, /tf_static first. `raymap populate` maps the bag to
// exactly the voxels of the same rays in a PLY. Skips without the shared data.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "src/core/eigen_conversions.hpp"
#include "tests/replay/replay_harness.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/support/bag_spec.hpp"
#include "tests/support/shared_data.hpp"

namespace raymap::test {
namespace {

constexpr std::int64_t kOusterT0 = 1700000000000000000;

std::int64_t nanoseconds(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

TEST(BagOuster, TheOusterDataSetAsABagGivesTheVoxelsOfItsRays) {
  std::string why;
  if (!nodeHarnessReady(&why)) {
    GTEST_SKIP() << why;
  }
  const auto sets = sharedDataSets();
  const auto ouster = std::find_if(sets.begin(), sets.end(), [](const DataSet& d) {
    return std::string(d.name).find("ouster") != std::string::npos;
  });
  ASSERT_NE(ouster, sets.end());
  const DataFiles files = dataFiles(*ouster);
  if (!files.missing.empty()) {
    GTEST_SKIP() << files.missing;
  }
  const std::vector<Ray> rays = loadRays(files.file, files.trajectory);
  ASSERT_FALSE(rays.empty());

  TempDir dir;
  const std::string spec_path = dir.file("ouster.jsonl");
  PlyTestFile ply = float64RayCloud();
  std::size_t scans = 0;
  {
    BagSpecWriter spec(spec_path);
    spec.channel("/tf_static", "tf2_msgs/msg/TFMessage");
    spec.channel("/odom", "nav_msgs/msg/Odometry");
    spec.channel("/ouster/points", "sensor_msgs/msg/PointCloud2");
    spec.tf("/tf_static", kOusterT0 - 1000000000,
            {{kOusterT0, "base_link", "os_sensor", io::Pose{}}});
    forEachScan(rays, [&](std::span<const Ray> scan) {
      // The scan's origin as the base's pose (identity rotation) over its time span, the rays'
      // ends in its frame as float32 as the Ouster driver publishes them; the PLY gets the rays
      // those make (the data set's rays to float32 rounding of the ends' offsets).
      const Vec3d origin = scan.front().origin;
      double first = scan.front().time_s;
      double last = first;
      for (const Ray& r : scan) {
        // One origin per scan (the PLY stores it per ray, as point + normal: equal to rounding).
        ASSERT_LT((r.origin - origin).norm(), 1e-5);
        first = std::min(first, r.time_s);
        last = std::max(last, r.time_s);
      }
      const std::int64_t stamp = kOusterT0 + nanoseconds(first);
      const io::Pose pose{toEigen(origin)};  // identity rotation
      // 10 us either side: inside the 98 us between a scan's last column and the next's first,
      // so that no point is interpolated between two scans' origins.
      spec.odometry("/odom", stamp - 10000, stamp - 10000, "odom", "base_link", pose);
      spec.odometry("/odom", kOusterT0 + nanoseconds(last) + 10000,
                    kOusterT0 + nanoseconds(last) + 10000, "odom", "base_link", pose);
      std::vector<msgs::ScanPoint> points;
      for (const Ray& r : scan) {
        if ((r.flags & kRayNoReturn) != 0u) {
          continue;
        }
        const float x = static_cast<float>(r.sample.x - origin.x);
        const float y = static_cast<float>(r.sample.y - origin.y);
        const float z = static_cast<float>(r.sample.z - origin.z);
        if (x == 0.0f && y == 0.0f && z == 0.0f) {
          continue;  // a no-return in the Ouster layout
        }
        points.push_back({x, y, z, static_cast<float>(r.time_s - first), r.intensity, 0u});
        addRay(ply, origin, {origin.x + double(x), origin.y + double(y), origin.z + double(z)},
               r.time_s);
      }
      spec.ousterCloud("/ouster/points", kOusterT0 + nanoseconds(last) + 100000, stamp, "os_sensor",
                       points, {});
      ++scans;
    });
    ASSERT_TRUE(spec.ok());
  }
  ASSERT_EQ(scans, 3u);
  const std::string ply_path = dir.file("ouster_rays.ply");
  writePly(ply_path, ply);
  const std::string bag = dir.file("ouster_bag");
  writeBag(spec_path, bag, {"--compression", "zstd"});

  std::map<std::string, std::string> stats;
  for (const std::string& input : {ply_path, bag}) {
    const std::string json = dir.file("stats.json");
    const RunResult r = runRaymap({"populate", input, "--stats-json", json, "-q"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    stats[input] = readFile(json);
  }
  for (const char* key : {"rays_integrated", "voxels_free", "voxels_occupied"}) {
    EXPECT_EQ(jsonNumber(stats[bag], key), jsonNumber(stats[ply_path], key)) << key;
  }
  EXPECT_GT(jsonNumber(stats[bag], "voxels_occupied").value_or(0), 10000.0);
}

}  // namespace
}  // namespace raymap::test
