// SPDX-License-Identifier: BSD-3-Clause
// The simulated lidar driver the raymapd tests publish: its sensor-frame points, put back into
// the world with its own poses, are the scene's surfaces.
#include <cmath>

#include <gtest/gtest.h>

#include "src/core/eigen_conversions.hpp"
#include "src/sim/scene.hpp"
#include "tests/service/service_fixture.hpp"

namespace raymap::test {
namespace {

TEST(SimulatedLidar, PointsPutBackWithThePosesLieOnTheSceneWhileMoving) {
  const driver::SimulatedLidar lidar = yardLidar(16, 256, /*moving=*/true);
  std::vector<msgs::ScanPoint> points;
  std::vector<std::uint16_t> rings;
  for (std::uint64_t k : {0u, 7u, 15u}) {
    lidar.scan(k, points, rings);
    ASSERT_EQ(points.size(), 16u * 256u);
    int checked = 0;
    int on_surface = 0;
    for (const msgs::ScanPoint& p : points) {
      if ((p.flags & msgs::kPointNoReturn) != 0u) {
        continue;
      }
      const double t = static_cast<double>(k) * lidar.scanPeriod() + static_cast<double>(p.time_s);
      const io::Pose pose = lidar.poseAt(t);
      const Vec3d w = toVec3(pose.transform(
          {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)}));
      const Vec3d origin = toVec3(pose.position);
      // The point lies where a ray from the pose's position first meets the scene (noise 1 cm).
      const double range = (w - origin).norm();
      const double hit = sim::castRay(lidar.scene(), origin, (w - origin) * (1 / range));
      ++checked;
      if (std::fabs(hit - range) < 0.05) {
        ++on_surface;
      }
    }
    EXPECT_GE(on_surface, checked * 95 / 100) << "scan " << k;
  }
}

}  // namespace
}  // namespace raymap::test
