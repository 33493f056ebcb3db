// SPDX-License-Identifier: BSD-3-Clause
// A depth camera's images into raymap::Mapper, as a program with its own camera driver would
// give them: each image (16UC1 millimetres here, as a RealSense publishes) with the camera's
// intrinsics (sensor_msgs/CameraInfo's K and plumb_bob D) and the optical frame's pose.
// The world: a wall 3.02 m ahead (x = 3.02) with a 0.5 m box standing in front of it (its face
// at x = 2.02, y = -0.25 to 0.25, z = 0 to 0.5) on a floor at z = 0; the camera, 0.5 m up, moves
// sideways along y and looks along +x. Prints four voxels' states and the map's counts.
//   depth_camera [--downsample N]
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <raymap/mapper.hpp>

namespace {

constexpr std::uint32_t kWidth = 64;
constexpr std::uint32_t kHeight = 48;

/// 90 degrees across, a rectified image (a driver's raw image would carry its plumb_bob
/// coefficients: distortion = kPlumbBob, k1, k2, p1, p2, k3).
raymap::CameraIntrinsics camera() {
  raymap::CameraIntrinsics c;
  c.width = kWidth;
  c.height = kHeight;
  c.fx = c.fy = 32.0;
  c.cx = 31.5;
  c.cy = 23.5;
  return c;
}

/// The optical frame (x right, y down, z forward) at (0, y, 0.5) looking along world +x.
Eigen::Isometry3d opticalPose(double y) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  pose.linear().col(1) = Eigen::Vector3d(0.0, 0.0, -1.0);
  pose.linear().col(2) = Eigen::Vector3d(1.0, 0.0, 0.0);
  pose.translation() = Eigen::Vector3d(0.0, y, 0.5);
  return pose;
}

/// The depth (z along the optical axis = metres ahead along x, in millimetres) that pixel (u, v)
/// sees from the camera at (0, y0, 0.5).
std::uint16_t depthOf(double y0, std::uint32_t u, std::uint32_t v) {
  const double xn = (u - 31.5) / 32.0;  // optical x / z: world -y per metre ahead
  const double yn = (v - 23.5) / 32.0;  // optical y / z: world -z per metre ahead
  double ahead = 3.02;                  // the wall
  const double at_box = 2.02;
  const double y = y0 - xn * at_box;
  const double z = 0.5 - yn * at_box;
  if (std::abs(y) <= 0.25 && z >= 0.0 && z <= 0.5) {
    ahead = at_box;
  }
  if (0.5 - yn * ahead < 0.0) {
    ahead = 0.5 / yn;  // the floor (z = 0) before the wall
  }
  return static_cast<std::uint16_t>(std::lround(ahead * 1000.0));
}

}  // namespace

int main(int argc, char** argv) {
  raymap::DepthOptions options;
  if (argc == 3 && std::string(argv[1]) == "--downsample") {
    options.downsample = static_cast<std::uint32_t>(std::atoi(argv[2]));
  } else if (argc != 1) {
    std::fprintf(stderr, "usage: depth_camera [--downsample N]\n");
    return 2;
  }
  raymap::MapperConfig config;
  config.map.resolution = 0.1;  // the pixels 6 cm apart on the box: every voxel of its face seen
  config.map.max_memory_bytes = std::uint64_t{256} << 20;
  config.rays.max_range = 5.0;
  auto mapper = raymap::Mapper::create(config);
  if (!mapper) {
    std::fprintf(stderr, "depth_camera: %s\n", mapper.error().message.c_str());
    return 1;
  }
  std::vector<std::uint16_t> pixels(kWidth * kHeight);
  for (int frame = 0; frame < 10; ++frame) {
    const double y = -0.5 + 0.1 * frame;
    for (std::uint32_t v = 0; v < kHeight; ++v) {
      for (std::uint32_t u = 0; u < kWidth; ++u) {
        pixels[v * kWidth + u] = depthOf(y, u, v);
      }
    }
    raymap::DepthImageView image;
    image.data = pixels.data();
    image.width = kWidth;
    image.height = kHeight;
    image.step = kWidth * sizeof(std::uint16_t);
    image.encoding = raymap::DepthEncoding::k16UC1;
    if (auto ok = mapper->integrate(image, camera(), opticalPose(y), options); !ok) {
      std::fprintf(stderr, "depth_camera: %s\n", ok.error().message.c_str());
      return 1;
    }
  }
  if (auto ok = mapper->flush(); !ok) {
    std::fprintf(stderr, "depth_camera: %s\n", ok.error().message.c_str());
    return 1;
  }
  const char* names[] = {"unobserved", "free", "occupied"};
  // In front of the box (free), its face (occupied), behind it (never seen), and the wall
  // beside it.
  for (const Eigen::Vector3d& at :
       {Eigen::Vector3d(1.05, 0.05, 0.45), Eigen::Vector3d(2.05, 0.05, 0.45),
        Eigen::Vector3d(2.75, 0.05, 0.45), Eigen::Vector3d(3.05, 1.05, 0.45)}) {
    const raymap::VoxelState state = mapper->occupancy(at);
    std::printf("voxel at (%.2f, %.2f, %.2f): %s\n", at.x(), at.y(), at.z(),
                names[static_cast<int>(state)]);
  }
  const raymap::MapCounts counts = mapper->counts();
  std::printf("voxels_occupied %llu\nvoxels_free %llu\nrays_in %llu\n",
              static_cast<unsigned long long>(counts.voxels_occupied),
              static_cast<unsigned long long>(counts.voxels_free),
              static_cast<unsigned long long>(mapper->counters().rays_in));
  return 0;
}
