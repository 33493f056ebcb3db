// SPDX-License-Identifier: BSD-3-Clause
// A depth camera walking up the stairs scene (config/scenes/stairs.yaml): its images and camera
// intrinsics as a bag spec, and the same rays as a PLY, for the depth-bag tests.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "raymap/depth_image.hpp"
#include <Eigen/Geometry>

#include "src/sim/scene.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {

/// @brief One image as the camera took it: 32FC1 metres (16UC1's rounding applied when the bag
/// is 16UC1), and the optical frame's pose in the world at its stamp.
struct DepthFrame {
  std::vector<float> depth;
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
};

/// @brief A recording of the body camera (160 x 120, 5 Hz, 3 m range) with 50 Hz odometry.
struct DepthBag {
  CameraIntrinsics camera;
  std::vector<DepthFrame> frames;
  std::string spec;
  std::string ply;  ///< the valid pixels' rays, as the decoder gives them (no down-sampling)
  std::size_t rays = 0;
  sim::Scene scene;
};

/// @brief Renders `frames` depth images of the stairs and writes the bag's spec and the PLY of
/// the same rays into `dir`. `encoding_16` writes 16UC1 millimetres (the PLY then uses the
/// rounded depths); `info_after_first_image` leaves the first frame's CameraInfo out;
/// `bad_image` adds a malformed rgb8 image after the second frame.
DepthBag makeDepthBag(const TempDir& dir, int frames, bool distorted, bool encoding_16,
                      bool info_after_first_image = false, bool bad_image = false);

}  // namespace raymap::test
