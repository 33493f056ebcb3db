// SPDX-License-Identifier: BSD-3-Clause
// A simulated depth camera on a robot body: a pinhole model (CameraIntrinsics, with plumb_bob
// distortion) rendering depth images of a scene, the truth behind the depth-image tests.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "raymap/error.hpp"

#include "src/core/pinhole_camera.hpp"
#include "src/core/vec3.hpp"
#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::sim {

/// How a frame is encoded on the wire (sensor_msgs/Image::encoding; the public enum). Rendering
/// is in float metres either way; the encoding matters when the frame is serialised.
using raymap::DepthEncoding;

/// @brief "16UC1" or "32FC1". @rt allocates: no.
const char* toString(DepthEncoding encoding) noexcept;

/// @brief Where a camera sits on the robot body.
///
/// Frames: the body frame is REP 103 (x forward, y left, z up). The mount's roll, pitch and yaw
/// (degrees) rotate a "camera link" frame, first about body x (roll), then about body y (pitch),
/// then about body z (yaw), i.e. R_body_link = Rz(yaw) Ry(pitch) Rx(roll) as in URDF and tf.
/// With all three 0 the camera looks along body +x; a positive pitch tilts it DOWN (a rotation
/// about +y takes +x towards -z), so pitch 45 looks 45° below the horizon and pitch 90 straight
/// down. The image is taken in the link's optical frame (REP 103 "_optical": x right, y down,
/// z forward): z_optical = x_link, x_optical = -y_link, y_optical = -z_link.
struct CameraMount {
  Vec3d position_m;  ///< the optical centre in the body frame, metres
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double yaw_deg = 0.0;
};

/// @brief A depth camera as a scene file describes it (docs/scenes.md, depth_cameras).
/// Plain value type.
struct DepthCameraModel {
  std::string name = "depth";
  std::uint32_t width = 640;   ///< pixels
  std::uint32_t height = 480;  ///< pixels
  /// Horizontal field of view between the outer edges of the outer pixels, degrees (0, 180);
  /// fx = fy = (width / 2) / tan(hfov / 2) (square pixels).
  double hfov_deg = 87.0;
  std::optional<double> cx;  ///< principal point, pixels; default (width - 1) / 2, the centre
  std::optional<double> cy;  ///< default (height - 1) / 2
  /// plumb_bob k1, k2, p1, p2, k3; all zero = no distortion.
  std::array<double, 5> distortion{};
  CameraMount mount;
  double rate_hz = 15.0;
  /// Depths (z, along the optical axis) beyond this are invalid: REP 117 +inf (and nothing hit).
  double max_range_m = 3.0;
  /// Depths (z) nearer than this are invalid: REP 117 -inf.
  double min_range_m = 0.1;
  /// Standard deviation of the Gaussian noise added to each valid depth (z), metres.
  double depth_noise_m = 0.0;
  DepthEncoding encoding = DepthEncoding::k32FC1;
  /// Pixels per block side when frames become rays (raymapd's `downsample`): rendering is always
  /// at full resolution.
  std::uint32_t downsample = 1;
};

/// @brief The pinhole intrinsics of `model` (fx = fy from the field of view, the principal point
/// at the centre unless given, plumb_bob when any coefficient is non-zero). Not validated.
CameraIntrinsics intrinsics(const DepthCameraModel& model) noexcept;

/// @brief The optical frame in the world: its origin and its axes as world-frame unit vectors
/// (the columns of R_world_optical). Plain value type.
struct CameraPose {
  Vec3d origin;  ///< world frame, metres
  Vec3d x_axis;  ///< optical x (image right)
  Vec3d y_axis;  ///< optical y (image down)
  Vec3d z_axis;  ///< optical z (viewing direction)

  /// @brief A point given in the optical frame, in the world frame.
  Vec3d toWorld(Vec3d p_optical) const noexcept {
    return origin + x_axis * p_optical.x + y_axis * p_optical.y + z_axis * p_optical.z;
  }
};

/// @brief The camera's optical frame for a body pose: T_world_optical = T_world_body(pose: level,
/// rotated by yaw_rad about +z) ∘ T_body_link(mount) ∘ R_link_optical. @rt allocates: no.
CameraPose cameraPose(const CameraMount& mount, const SensorPose& body) noexcept;

/// @brief Frame f of a camera running at `rate_hz` from `start_s` is taken at start_s + f / rate;
/// a recording of `duration_s` seconds holds floor(duration × rate) of them (a hair of slack, so
/// that 2 s at 5 Hz is 10 frames despite rounding).
int frameCount(double duration_s, double rate_hz) noexcept;

/// @brief The seed of frame `frame` of camera `camera`: the frames' noise is independent of the
/// order they are rendered in (splitmix64 of the three).
std::uint64_t frameSeed(std::uint64_t seed, std::uint32_t camera, std::uint32_t frame) noexcept;

/// @brief A depth camera ready to render: the model, its intrinsics and the undistorted ray of
/// every pixel (from PixelRayTable: the same rays the depth-image decoder back-projects along).
/// Thread-safety: immutable after create(); render() may run on several threads at once.
class DepthCamera {
 public:
  /// @brief Checks the model (size, field of view, ranges, rate, noise, downsample, a distortion
  /// that does not fold over the image) and builds the ray table. The message names the field.
  static Result<DepthCamera> create(const DepthCameraModel& model);

  const DepthCameraModel& model() const noexcept { return model_; }
  const CameraIntrinsics& intrinsics() const noexcept { return rays_.camera(); }
  const PixelRayTable& rays() const noexcept { return rays_; }
  std::size_t pixels() const noexcept {
    return static_cast<std::size_t>(model_.width) * model_.height;
  }

  /// @brief Renders one frame: for every pixel, the ray through it from the optical centre to the
  /// first surface, stored as the depth z along the optical axis (REP 118), float metres,
  /// row-major (v, then u). Invalid pixels follow REP 117: +inf when nothing lies within
  /// max_range_m (z), -inf when nearer than min_range_m. Gaussian noise (depth_noise_m) is added
  /// to valid depths from a generator seeded with `seed` (std::mt19937_64 and libstdc++'s
  /// normal distribution: deterministic on one standard library).
  /// @pre depth_m.size() == pixels()
  /// @rt allocates: no.
  void render(const Scene& scene, const CameraPose& pose, std::uint64_t seed,
              std::span<float> depth_m) const noexcept;

 private:
  DepthCamera() = default;

  DepthCameraModel model_;
  PixelRayTable rays_;
};

}  // namespace raymap::sim
