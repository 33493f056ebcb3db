// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper::integrate for depth images (issue 55): a camera facing a wall sees it at the
// depth its pixels say, in either encoding; pixels without depth are counted; images and options
// that do not fit are refused naming the field, and nothing is integrated then.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

namespace raymap {
namespace {

/// A 16 x 12 camera with a 90-degree horizontal field of view, no distortion.
CameraIntrinsics wallCamera() {
  CameraIntrinsics c;
  c.width = 16;
  c.height = 12;
  c.fx = 8.0;
  c.fy = 8.0;
  c.cx = 7.5;
  c.cy = 5.5;
  return c;
}

/// The optical frame (x right, y down, z forward) looking along world +x from 1 m up.
Eigen::Isometry3d lookingAlongX() {
  Eigen::Matrix3d optical_in_world;
  optical_in_world.col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  optical_in_world.col(1) = Eigen::Vector3d(0.0, 0.0, -1.0);
  optical_in_world.col(2) = Eigen::Vector3d(1.0, 0.0, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = optical_in_world;
  pose.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
  return pose;
}

MapperConfig config() {
  MapperConfig c;
  c.map.resolution = 0.1;
  c.map.max_memory_bytes = std::uint64_t{64} << 20;
  return c;
}

DepthImageView view(const void* data, std::uint32_t width, std::uint32_t height, std::size_t step,
                    DepthEncoding encoding) {
  DepthImageView v;
  v.data = data;
  v.width = width;
  v.height = height;
  v.step = step;
  v.encoding = encoding;
  return v;
}

TEST(MapperDepth, AWallAtTwoMetresIsOccupiedThereInEitherEncoding) {
  const CameraIntrinsics camera = wallCamera();
  // A wall 2.04 m ahead: depth (z along the optical axis) is 2.04 m for every pixel (its points
  // 0.255 m apart, at y and z = ±0.1275, ±0.3825, … about the axis); one pixel has no depth (0
  // in 16UC1, NaN in 32FC1).
  std::vector<std::uint16_t> millimetres(16 * 12, 2040);
  std::vector<float> metres(16 * 12, 2.04f);
  millimetres[5] = 0;
  metres[5] = std::numeric_limits<float>::quiet_NaN();
  for (const bool sixteen : {true, false}) {
    SCOPED_TRACE(sixteen ? "16UC1" : "32FC1");
    auto mapper = Mapper::create(config());
    ASSERT_TRUE(mapper) << mapper.error().message;
    const DepthImageView image =
        sixteen ? view(millimetres.data(), 16, 12, 16 * 2, DepthEncoding::k16UC1)
                : view(metres.data(), 16, 12, 16 * 4, DepthEncoding::k32FC1);

    auto ok = mapper->integrate(image, camera, lookingAlongX());
    ASSERT_TRUE(ok) << ok.error().message;
    ASSERT_TRUE(mapper->flush());

    EXPECT_EQ(mapper->counters().rays_in, 16u * 12u - 1u);
    EXPECT_EQ(mapper->counters().depth_no_depth, 1u);
    EXPECT_EQ(mapper->counters().scans, 1u);
    EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(2.05, 0.15, 1.15)), VoxelState::kOccupied);
    EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(1.05, 0.05, 1.05)), VoxelState::kFree);
    EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(2.55, 0.15, 1.15)), VoxelState::kUnobserved);
  }
}

TEST(MapperDepth, ImagesAndOptionsThatDoNotFitAreRefusedByFieldAndIntegrateNothing) {
  const CameraIntrinsics camera = wallCamera();
  std::vector<float> metres(16 * 12, 2.0f);
  auto mapper = Mapper::create(config());
  ASSERT_TRUE(mapper) << mapper.error().message;
  const auto refused = [&](const DepthImageView& image, const CameraIntrinsics& c,
                           const DepthOptions& options) {
    auto ok = mapper->integrate(image, c, lookingAlongX(), options);
    return ok ? std::string() : ok.error().message;
  };
  const DepthImageView good = view(metres.data(), 16, 12, 64, DepthEncoding::k32FC1);
  DepthOptions no_block;
  no_block.downsample = 0;
  DepthOptions free_without_range;
  free_without_range.invalid_as_free = true;
  CameraIntrinsics no_focal = camera;
  no_focal.fx = 0.0;

  EXPECT_NE(refused(view(metres.data(), 12, 16, 48, DepthEncoding::k32FC1), camera, {})
                .find("image.width"),
            std::string::npos);
  EXPECT_NE(refused(view(metres.data(), 16, 12, 32, DepthEncoding::k32FC1), camera, {})
                .find("image.step"),
            std::string::npos);
  EXPECT_NE(
      refused(view(nullptr, 16, 12, 64, DepthEncoding::k32FC1), camera, {}).find("image.data"),
      std::string::npos);
  EXPECT_NE(refused(good, camera, no_block).find("depth.downsample"), std::string::npos);
  EXPECT_NE(refused(good, camera, free_without_range).find("depth.invalid_as_free"),
            std::string::npos);
  EXPECT_NE(refused(good, no_focal, {}).find("camera focal lengths K[0] (fx)"), std::string::npos)
      << refused(good, no_focal, {});
  EXPECT_EQ(mapper->counters().rays_in, 0u);
  EXPECT_EQ(mapper->counters().scans, 0u);
}

}  // namespace
}  // namespace raymap
