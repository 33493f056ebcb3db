// SPDX-License-Identifier: BSD-3-Clause
// The simulated depth camera: intrinsics from the field of view, the mount's rotation, and
// rendering by casting every pixel's undistorted ray into the scene.
#include "src/sim/depth_camera.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <utility>

#include "raymap/assert.hpp"

namespace raymap::sim {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// A 3 × 3 rotation held as its columns.
struct Rotation {
  Vec3d c0{1.0, 0.0, 0.0};
  Vec3d c1{0.0, 1.0, 0.0};
  Vec3d c2{0.0, 0.0, 1.0};

  Vec3d operator*(Vec3d v) const noexcept { return c0 * v.x + c1 * v.y + c2 * v.z; }
  Rotation operator*(const Rotation& o) const noexcept {
    return {*this * o.c0, *this * o.c1, *this * o.c2};
  }
};

Rotation rotX(double a) noexcept {
  const double c = std::cos(a);
  const double s = std::sin(a);
  return {{1.0, 0.0, 0.0}, {0.0, c, s}, {0.0, -s, c}};
}
Rotation rotY(double a) noexcept {
  const double c = std::cos(a);
  const double s = std::sin(a);
  return {{c, 0.0, -s}, {0.0, 1.0, 0.0}, {s, 0.0, c}};
}
Rotation rotZ(double a) noexcept {
  const double c = std::cos(a);
  const double s = std::sin(a);
  return {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
}

/// R_link_optical: its columns are the optical axes in the link frame (x forward, y left, z up).
constexpr Vec3d kOpticalXInLink{0.0, -1.0, 0.0};
constexpr Vec3d kOpticalYInLink{0.0, 0.0, -1.0};
constexpr Vec3d kOpticalZInLink{1.0, 0.0, 0.0};

std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

bool finite(double v) noexcept { return std::isfinite(v); }

}  // namespace

const char* toString(DepthEncoding encoding) noexcept {
  return encoding == DepthEncoding::k16UC1 ? "16UC1" : "32FC1";
}

CameraIntrinsics intrinsics(const DepthCameraModel& model) noexcept {
  CameraIntrinsics c;
  c.width = model.width;
  c.height = model.height;
  c.fx = 0.5 * model.width / std::tan(0.5 * model.hfov_deg * kDegToRad);
  c.fy = c.fx;
  c.cx = model.cx.value_or(0.5 * (model.width - 1.0));
  c.cy = model.cy.value_or(0.5 * (model.height - 1.0));
  const auto& d = model.distortion;
  const bool distorted = d[0] != 0.0 || d[1] != 0.0 || d[2] != 0.0 || d[3] != 0.0 || d[4] != 0.0;
  c.distortion = distorted ? DistortionModel::kPlumbBob : DistortionModel::kNone;
  c.k1 = d[0];
  c.k2 = d[1];
  c.p1 = d[2];
  c.p2 = d[3];
  c.k3 = d[4];
  return c;
}

CameraPose cameraPose(const CameraMount& mount, const SensorPose& body) noexcept {
  const Rotation world_body = rotZ(body.yaw_rad);
  const Rotation world_link = world_body * rotZ(mount.yaw_deg * kDegToRad) *
                              rotY(mount.pitch_deg * kDegToRad) * rotX(mount.roll_deg * kDegToRad);
  return {body.position + world_body * mount.position_m, world_link * kOpticalXInLink,
          world_link * kOpticalYInLink, world_link * kOpticalZInLink};
}

int frameCount(double duration_s, double rate_hz) noexcept {
  const double frames = std::floor(duration_s * rate_hz + 1e-6);
  if (!(frames >= 0.0)) {
    return 0;
  }
  return frames > static_cast<double>(std::numeric_limits<int>::max())
             ? std::numeric_limits<int>::max()
             : static_cast<int>(frames);
}

std::uint64_t frameSeed(std::uint64_t seed, std::uint32_t camera, std::uint32_t frame) noexcept {
  return splitmix64(splitmix64(splitmix64(seed) ^ camera) ^ frame);
}

Result<DepthCamera> DepthCamera::create(const DepthCameraModel& model) {
  const auto bad = [&model](const std::string& what) {
    return fail(ErrorCode::kInvalidArgument, "depth camera '" + model.name + "': " + what);
  };
  if (!(model.hfov_deg > 0.0 && model.hfov_deg < 180.0)) {
    return bad("hfov_deg must be between 0 and 180");
  }
  if (!(model.rate_hz > 0.0) || !finite(model.rate_hz)) {
    return bad("rate_hz must be > 0");
  }
  if (!(model.min_range_m >= 0.0) || !(model.max_range_m > model.min_range_m) ||
      !finite(model.max_range_m)) {
    return bad("ranges must satisfy 0 <= min_range < max_range");
  }
  if (!(model.depth_noise_m >= 0.0) || !finite(model.depth_noise_m)) {
    return bad("noise must be >= 0");
  }
  if (model.downsample < 1) {
    return bad("downsample must be >= 1");
  }
  const CameraMount& m = model.mount;
  if (!m.position_m.isFinite() || !finite(m.roll_deg) || !finite(m.pitch_deg) ||
      !finite(m.yaw_deg)) {
    return bad("the mount must be finite");
  }
  DepthCamera camera;
  camera.model_ = model;
  if (auto built = camera.rays_.build(sim::intrinsics(model)); !built) {
    return bad(built.error().message);
  }
  return camera;
}

void DepthCamera::render(const Scene& scene, const CameraPose& pose, std::uint64_t seed,
                         std::span<float> depth_m) const noexcept {
  RAYMAP_EXPECTS(depth_m.size() == pixels());
  constexpr float kTooFar = std::numeric_limits<float>::infinity();
  std::mt19937_64 rng(seed);
  const double sigma = model_.depth_noise_m;
  std::normal_distribution<double> noise(0.0, sigma > 0.0 ? sigma : 1.0);
  std::size_t i = 0;
  for (std::uint32_t v = 0; v < model_.height; ++v) {
    for (std::uint32_t u = 0; u < model_.width; ++u, ++i) {
      const float* r = rays_.ray(u, v);
      // The pixel's ray (x/z, y/z, 1) in the optical frame; its length converts range to depth.
      const double rx = static_cast<double>(r[0]);
      const double ry = static_cast<double>(r[1]);
      const double length = std::sqrt(rx * rx + ry * ry + 1.0);
      const Vec3d dir = (pose.x_axis * rx + pose.y_axis * ry + pose.z_axis) * (1.0 / length);
      const double z = castRay(scene, pose.origin, dir) / length;
      if (!(z <= model_.max_range_m)) {  // nothing hit (inf) or too far
        depth_m[i] = kTooFar;
      } else if (z < model_.min_range_m) {
        depth_m[i] = -kTooFar;
      } else {
        const double measured = sigma > 0.0 ? z + noise(rng) : z;
        depth_m[i] = measured > 0.0 ? static_cast<float>(measured) : -kTooFar;
      }
    }
  }
}

}  // namespace raymap::sim
