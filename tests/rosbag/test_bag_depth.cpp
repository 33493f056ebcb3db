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
#include "tests/support/bag_spec.hpp"
#include "tests/support/scene_truth.hpp"

namespace raymap::test {
namespace {

constexpr std::int64_t kDepthT0 = 1700000000000000000;
constexpr std::int64_t kFramePeriod = 200000000;  // 5 Hz
constexpr std::int64_t kPosePeriod = 20000000;    // 50 Hz odometry
constexpr double kMaxRange = 3.0;                 // the camera reports nothing further away
const char* const kImageTopic = "/body/depth/image_rect_raw";
const char* const kInfoTopic = "/body/depth/camera_info";
const char* const kFrame = "body_depth_optical_frame";

/// The camera's optical frame in base_link: 0.3 m ahead, 0.1 m up, looking forward and 45
/// degrees down (optical z along (cos 45, 0, -sin 45), x to the robot's right, y down).
io::Pose cameraMount() {
  Eigen::Matrix3d optical_in_base;
  optical_in_base.col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  optical_in_base.col(1) = Eigen::Vector3d(-std::sqrt(0.5), 0.0, -std::sqrt(0.5));
  optical_in_base.col(2) = Eigen::Vector3d(std::sqrt(0.5), 0.0, -std::sqrt(0.5));
  return io::Pose{{0.3, 0.0, 0.1}, Eigen::Quaterniond(optical_in_base).normalized()};
}

CameraIntrinsics bodyCamera(bool distorted) {
  CameraIntrinsics c;
  c.width = 160;
  c.height = 120;
  c.fx = 80.0;
  c.fy = 80.0;
  c.cx = 79.5;
  c.cy = 59.5;
  if (distorted) {
    c.distortion = DistortionModel::kPlumbBob;
    c.k1 = -0.12;
    c.k2 = 0.03;
    c.p1 = 0.001;
    c.p2 = -0.0008;
  }
  return c;
}

/// The walking body: 0.55 m above the ground, towards the stairs (their foot at x = 2.0) at
/// 0.5 m/s.
io::Pose bodyAt(std::int64_t t_ns) {
  const double t = static_cast<double>(t_ns - kDepthT0) * 1e-9;
  return io::Pose{{0.2 + 0.5 * t, 0.0, 0.55}, Eigen::Quaterniond::Identity()};
}

struct DepthBag {
  std::string spec;
  std::string ply;  ///< the valid pixels' rays, as the decoder gives them (no down-sampling)
  std::size_t rays = 0;
  sim::Scene scene;
};

/// Renders `frames` depth images of the stairs and writes the bag's spec and the PLY of the
/// same rays. `encoding_16` writes 16UC1 millimetres (the PLY then uses the rounded depths).
DepthBag makeDepthBag(const TempDir& dir, int frames, bool distorted, bool encoding_16,
                      bool info_after_first_image = false, bool bad_image = false) {
  DepthBag bag;
  auto file = sim::loadSceneFile(std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml");
  EXPECT_TRUE(file) << (file ? "" : file.error().message);
  bag.scene = file.value().scene;
  const CameraIntrinsics camera = bodyCamera(distorted);
  PixelRayTable rays;
  const auto built = rays.build(camera);
  EXPECT_TRUE(built) << (built ? "" : built.error().message);
  const io::Pose mount = cameraMount();

  bag.spec = dir.file("depth.jsonl");
  BagSpecWriter spec(bag.spec);
  spec.channel("/tf_static", "tf2_msgs/msg/TFMessage",
               "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n");
  spec.channel("/odom", "nav_msgs/msg/Odometry");
  spec.channel(kImageTopic, "sensor_msgs/msg/Image");
  spec.channel(kInfoTopic, "sensor_msgs/msg/CameraInfo");
  spec.tf("/tf_static", kDepthT0 - 1000000000, {{kDepthT0, "base_link", kFrame, mount}});

  PlyTestFile ply = float64RayCloud();
  std::int64_t next_pose = kDepthT0 - 5 * kPosePeriod;
  std::vector<float> depth(std::size_t{camera.width} * camera.height);
  for (int k = 0; k < frames; ++k) {
    const std::int64_t stamp = kDepthT0 + kFramePeriod * k;
    while (next_pose <= stamp + 5 * kPosePeriod) {
      spec.odometry("/odom", next_pose, next_pose, "odom", "base_link", bodyAt(next_pose));
      next_pose += kPosePeriod;
    }
    const io::Pose sensor = io::compose(bodyAt(stamp), mount);
    for (std::uint32_t v = 0; v < camera.height; ++v) {
      for (std::uint32_t u = 0; u < camera.width; ++u) {
        const float* r = rays.ray(u, v);
        const Eigen::Vector3d optical(static_cast<double>(r[0]), static_cast<double>(r[1]), 1.0);
        const Eigen::Vector3d direction = (sensor.orientation * optical).normalized();
        const double t = sim::castRay(bag.scene, toVec3(sensor.position), toVec3(direction));
        float d = std::numeric_limits<float>::quiet_NaN();
        if (t <= kMaxRange) {
          d = static_cast<float>(t / optical.norm());  // depth is z along the optical axis
          if (encoding_16) {
            d = std::round(d * 1000.0f) / 1000.0f;
          }
        }
        depth[std::size_t{v} * camera.width + u] = d;
        if (!std::isfinite(d) || d <= 0.0f) {
          continue;
        }
        const Eigen::Vector3d point(static_cast<double>(d * r[0]), static_cast<double>(d * r[1]),
                                    static_cast<double>(d));
        addRay(ply, toVec3(sensor.position), toVec3(sensor.transform(point)),
               static_cast<double>(stamp - kDepthT0) * 1e-9);
        ++bag.rays;
      }
    }
    const std::int64_t logged = stamp + 1000000;
    if (!(info_after_first_image && k == 0)) {
      spec.cameraInfo(kInfoTopic, logged, stamp, kFrame, camera);
    }
    spec.depthImage(kImageTopic, logged + 1, stamp, kFrame, camera.width, camera.height, depth,
                    encoding_16);
    if (bad_image && k == 1) {
      spec.message(kImageTopic, logged + 2,
                   "{\"header\":{\"stamp\":{\"sec\":1,\"nanosec\":0},\"frame_id\":\"" +
                       std::string(kFrame) +
                       "\"},\"height\":1,\"width\":1,\"encoding\":\"rgb8\",\"step\":3,"
                       "\"data\":[1,2,3]}");
    }
  }
  // Poses past the last frame, so that it is covered.
  for (int i = 0; i < 10; ++i, next_pose += kPosePeriod) {
    spec.odometry("/odom", next_pose, next_pose, "odom", "base_link", bodyAt(next_pose));
  }
  EXPECT_TRUE(spec.ok());
  bag.ply = dir.file("depth_rays.ply");
  writePly(bag.ply, ply);
  return bag;
}

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
