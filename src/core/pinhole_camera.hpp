// SPDX-License-Identifier: BSD-3-Clause
// The pinhole camera of sensor_msgs/CameraInfo (K, and D for the plumb_bob distortion model):
// pixels to the rays they see and back. One definition for the depth-image decoder (raymapd and
// bags) and the simulated depth camera, so what the simulator renders is what the decoder reads.
#pragma once

#include <cstdint>
#include <vector>

#include "raymap/depth_image.hpp"
#include "raymap/error.hpp"
#include "raymap/expected.hpp"

namespace raymap {

// CameraIntrinsics and DistortionModel are public (raymap/depth_image.hpp).

/// @brief Normalised image coordinates: the ray through (x, y, 1) in the optical frame.
struct NormalisedPoint {
  double x = 0.0;
  double y = 0.0;
};

/// @brief Pixel (u, v) of a normalised, undistorted point: distortion applied, then K.
/// @rt allocates: no.
NormalisedPoint projectNormalised(const CameraIntrinsics& camera, NormalisedPoint point) noexcept;

/// @brief The normalised, undistorted coordinates of pixel (u, v): K inverted, then the
/// distortion inverted by Newton's method in double precision (to 1e-12 of a normalised unit, so
/// projectNormalised(pixelToNormalised(u, v)) gives (u, v) back to about 1e-9 pixel).
/// @return false when the iteration did not converge (a distortion that folds over there).
/// @rt allocates: no.
bool pixelToNormalised(const CameraIntrinsics& camera, double u, double v,
                       NormalisedPoint* out) noexcept;

/// @brief The undistorted ray of every pixel of one camera, computed once per CameraInfo (the
/// inversion is iterative: far too slow per pixel per frame).
///
/// Storage is two floats per pixel (x / z and y / z), row-major; rebuilt only when the
/// intrinsics change. Thread-safety: build() on one thread; the const accessors from any thread
/// once built. @rt build(): allocates only when the image is larger than reserve() allowed for;
/// ray(): allocates no, blocks no.
class PixelRayTable {
 public:
  /// @brief Room for `pixels` pixels, so that build() for any camera up to that size does not
  /// allocate (start-up).
  void reserve(std::size_t pixels);

  /// @brief Computes the rays of `camera`'s pixels; a table already built for the same
  /// intrinsics is kept as it is.
  /// @return an error naming the field when the camera is invalid, or the pixel whose
  /// distortion cannot be inverted; the table is then empty.
  Expected<void, Error> build(const CameraIntrinsics& camera);

  /// @brief Whether build() succeeded for these intrinsics.
  bool matches(const CameraIntrinsics& camera) const noexcept {
    return built_ && camera == camera_;
  }
  bool built() const noexcept { return built_; }
  const CameraIntrinsics& camera() const noexcept { return camera_; }
  std::uint32_t width() const noexcept { return camera_.width; }
  std::uint32_t height() const noexcept { return camera_.height; }

  /// @brief x / z and y / z of the ray of pixel (u, v). @pre built(), u < width(), v < height()
  const float* ray(std::uint32_t u, std::uint32_t v) const noexcept {
    return &rays_[2 * (static_cast<std::size_t>(v) * camera_.width + u)];
  }

  /// @brief Forgets the table (the next build() computes it again).
  void clear() noexcept { built_ = false; }

 private:
  CameraIntrinsics camera_;
  bool built_ = false;
  std::vector<float> rays_;
};

}  // namespace raymap
