// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate BAG` with depth cameras: sensor_msgs/Image and CameraInfo serialized by
// Foxglove's ROS 2 serializer (independent of raymap's decoders), rendered here from the stairs
// scene by casting each pixel's ray, map to the voxels of the same pixel rays written as a PLY,
// and to the scene's true heights; images before their CameraInfo, malformed images and the rate
// limit are skipped and counted.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/core/eigen_conversions.hpp"
#include "src/core/pinhole_camera.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/replay/replay_harness.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/rosbag/depth_bag.hpp"
#include "tests/support/bag_spec.hpp"
#include "tests/support/scene_truth.hpp"

namespace raymap::test {
namespace {

struct Stats {
  double free = -1, occupied = -1, rays = -1;
  double no_info = -1, skipped = -1, rate_limited = -1, camera_infos = -1;
};

Stats populateDepth(const TempDir& dir, const std::string& input, std::vector<std::string> extra) {
  static int run = 0;
  const std::string stats = dir.file("depth_stats" + std::to_string(run++) + ".json");
  std::vector<std::string> args{"populate", input, "--stats-json", stats, "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  const RunResult r = runRaymap(args);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  const std::string json = readFile(stats);
  Stats s;
  s.free = jsonNumber(json, "voxels_free").value_or(-1);
  s.occupied = jsonNumber(json, "voxels_occupied").value_or(-1);
  s.rays = jsonNumber(json, "rays_integrated").value_or(-1);
  s.no_info = jsonNumber(json, "images_no_camera_info").value_or(-1);
  s.skipped = jsonNumber(json, "clouds_skipped").value_or(-1);
  s.rate_limited = jsonNumber(json, "rate_limited").value_or(-1);
  s.camera_infos = jsonNumber(json, "camera_infos").value_or(-1);
  return s;
}

TEST(BagDepth, DepthImagesGiveTheVoxelsOfTheirPixelRays) {
  REQUIRE_NODE_HARNESS();
  for (const bool distorted : {false, true}) {
    for (const bool millimetres : {false, true}) {
      SCOPED_TRACE(std::string(distorted ? "plumb_bob" : "no distortion") +
                   (millimetres ? ", 16UC1" : ", 32FC1"));
      TempDir dir;
      const DepthBag bag = makeDepthBag(dir, 8, distorted, millimetres);
      ASSERT_GT(bag.rays, 50000u);
      const std::string out = dir.file("depth_bag");
      writeBag(bag.spec, out, {});
      const Stats from_ply = populateDepth(dir, bag.ply, {});
      const Stats from_bag = populateDepth(dir, out, {});
      // Every valid pixel is one ray; the voxels agree with the PLY's rays to float rounding of
      // the back-projection (a ray ending on a voxel face may end on its other side).
      EXPECT_EQ(from_bag.rays, static_cast<double>(bag.rays));
      EXPECT_EQ(from_ply.rays, static_cast<double>(bag.rays));
      EXPECT_NEAR(from_bag.occupied, from_ply.occupied, 0.002 * from_ply.occupied + 2);
      EXPECT_NEAR(from_bag.free, from_ply.free, 0.002 * from_ply.free + 2);
      EXPECT_EQ(from_bag.camera_infos, 8.0);
      EXPECT_EQ(from_bag.no_info, 0.0);
    }
  }
}

TEST(BagDepth, TheMapOfADownwardLookingCameraGivesTheStairsTrueHeights) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const DepthBag bag = makeDepthBag(dir, 12, true, true);
  const std::string out = dir.file("stairs_bag");
  writeBag(bag.spec, out, {});
  const OfflineHeights heights =
      offlineHeights(dir, out, {"--max-range", "3", "--downsample", "2"}, 2.0, 0.0, 0.0, 6.0);
  int compared = 0;
  int within_voxel = 0;
  for (const auto& [key, cell] : heights) {
    if (!cell.surface) {
      continue;
    }
    const Vec3d centre{(static_cast<double>(key.first) + 0.5) * 0.1,
                       (static_cast<double>(key.second) + 0.5) * 0.1, 0.0};
    const auto truth = unambiguousTruth(bag.scene, centre, 0.1, 0.0, 0.5);
    if (!truth) {
      continue;
    }
    ++compared;
    within_voxel += std::fabs(static_cast<double>(cell.elevation) - truth->height) <= 0.1 ? 1 : 0;
  }
  ASSERT_GT(compared, 200);
  EXPECT_GE(static_cast<double>(within_voxel) / compared, 0.95)
      << within_voxel << " of " << compared << " surface cells within a voxel of the truth";
}

TEST(BagDepth, ImagesBeforeTheirCameraInfoMalformedImagesAndTheRateLimitAreCounted) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const DepthBag bag = makeDepthBag(dir, 6, false, false, /*info_after_first_image=*/true,
                                    /*bad_image=*/true);
  const std::string out = dir.file("counted_bag");
  writeBag(bag.spec, out, {});
  const Stats all = populateDepth(dir, out, {});
  EXPECT_EQ(all.no_info, 1.0);  // the first image came before any CameraInfo
  EXPECT_EQ(all.skipped, 1.0);  // the rgb8 image
  EXPECT_EQ(all.camera_infos, 5.0);
  EXPECT_EQ(all.rate_limited, 0.0);
  // 5 Hz frames at most 2 Hz (0.5 s apart by stamp): of frames 1 to 5 (0.2 to 1.0 s), 1 and 4
  // are taken; 2 and 3 follow 1 by 0.2 and 0.4 s, 5 follows 4 by 0.2 s.
  const Stats limited = populateDepth(dir, out, {"--max-rate", "2"});
  EXPECT_EQ(limited.rate_limited, 3.0);
  EXPECT_LT(limited.rays, all.rays);
  // Down-sampling: each 4 x 4 block gives one point.
  const Stats down = populateDepth(dir, out, {"--downsample", "4"});
  EXPECT_LE(down.rays, all.rays / 16 + 1200);
  EXPECT_GT(down.rays, all.rays / 20);
  // --invalid-as-free needs the length of its free rays.
  const RunResult no_range =
      runRaymap({"populate", out, "--invalid-as-free", "-o", dir.file("never.rmap"), "-q"});
  EXPECT_NE(no_range.exit_code, 0);
  EXPECT_NE(no_range.err.find("--invalid-as-free needs --max-range"), std::string::npos)
      << describe(no_range);
}

TEST(BagDepth, InvalidPixelsClearFreeSpaceOnlyWhenAsked) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const DepthBag bag = makeDepthBag(dir, 4, false, false);
  const std::string out = dir.file("free_bag");
  writeBag(bag.spec, out, {});
  const Stats plain = populateDepth(dir, out, {"--max-range", "3"});
  const Stats freed = populateDepth(dir, out, {"--max-range", "3", "--invalid-as-free"});
  EXPECT_GT(freed.rays, plain.rays);  // the sky above the stairs: no depth
  EXPECT_GT(freed.free, plain.free);
  // Free rays into open space cross no surface; at most they graze a voxel near 3 m.
  EXPECT_NEAR(freed.occupied, plain.occupied, 0.01 * plain.occupied);
}

}  // namespace
}  // namespace raymap::test
