// SPDX-License-Identifier: BSD-3-Clause
// A depth camera walking up the stairs scene, recorded as a rosbag2 spec (Foxglove's serializer
// writes the bag) and as the PLY of the same pixel rays.
#include "tests/rosbag/depth_bag.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "src/core/eigen_conversions.hpp"
#include "src/core/pinhole_camera.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/support/bag_spec.hpp"
#include "tests/support/json_doc.hpp"

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

}  // namespace

DepthBag makeDepthBag(const TempDir& dir, int frames, bool distorted, bool encoding_16,
                      bool info_after_first_image, bool bad_image) {
  DepthBag bag;
  auto file = sim::loadSceneFile(std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml");
  EXPECT_TRUE(file) << (file ? "" : file.error().message);
  bag.scene = file.value().scene;
  const CameraIntrinsics camera = bodyCamera(distorted);
  bag.camera = camera;
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
    DepthFrame frame;
    frame.depth = depth;
    frame.camera_to_world.translation() = sensor.position;
    frame.camera_to_world.linear() = sensor.orientation.toRotationMatrix();
    bag.frames.push_back(std::move(frame));
    if (bad_image && k == 1) {
      const Json rgb = {
          {"header", {{"stamp", {{"sec", 1}, {"nanosec", 0}}}, {"frame_id", kFrame}}},
          {"height", 1},
          {"width", 1},
          {"encoding", "rgb8"},
          {"step", 3},
          {"data", {1, 2, 3}},
      };
      spec.message(kImageTopic, logged + 2, rgb.dump());
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

}  // namespace raymap::test
