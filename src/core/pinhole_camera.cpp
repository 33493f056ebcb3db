// SPDX-License-Identifier: BSD-3-Clause
// Pinhole projection with plumb_bob distortion, and its inverse by Newton's method.
#include "src/core/pinhole_camera.hpp"

#include <cmath>
#include <string>

namespace raymap {
namespace {

/// Largest image side CameraInfo sizes are accepted with (a 16-bit pixel index on each axis).
constexpr std::uint32_t kMaxSide = 65535;
/// Newton stops when the distorted point is this close to the target (normalised units).
constexpr double kTolerance = 1e-12;
constexpr int kMaxIterations = 50;

struct Distorted {
  double x;
  double y;
  // The Jacobian d(x_d, y_d) / d(x, y).
  double dxdx;
  double dxdy;
  double dydx;
  double dydy;
};

Distorted distort(const CameraIntrinsics& c, double x, double y) noexcept {
  if (c.distortion == DistortionModel::kNone) {
    return {x, y, 1.0, 0.0, 0.0, 1.0};
  }
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double d_radial = c.k1 + r2 * (2.0 * c.k2 + 3.0 * r2 * c.k3);  // d radial / d r2
  Distorted d{};
  d.x = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  d.y = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
  d.dxdx = radial + 2.0 * x * x * d_radial + 2.0 * c.p1 * y + 6.0 * c.p2 * x;
  d.dxdy = 2.0 * x * y * d_radial + 2.0 * c.p1 * x + 2.0 * c.p2 * y;
  d.dydx = 2.0 * x * y * d_radial + 2.0 * c.p1 * x + 2.0 * c.p2 * y;
  d.dydy = radial + 2.0 * y * y * d_radial + 6.0 * c.p1 * y + 2.0 * c.p2 * x;
  return d;
}

bool finite(double v) noexcept { return std::isfinite(v); }

}  // namespace

namespace {

enum class Defect : std::uint8_t { kNone, kSize, kFocal, kPrincipal, kCoefficients, kFolds };

/// The first thing that makes `c` unusable (one list of checks for validate() and usable()); a
/// folding lens's pixel goes to `*u`, `*v`. Allocates nothing.
Defect firstDefect(const CameraIntrinsics& c, double* u_out, double* v_out) noexcept {
  if (c.width == 0 || c.height == 0 || c.width > kMaxSide || c.height > kMaxSide) {
    return Defect::kSize;
  }
  if (!finite(c.fx) || !finite(c.fy) || c.fx <= 0.0 || c.fy <= 0.0) {
    return Defect::kFocal;
  }
  if (!finite(c.cx) || !finite(c.cy)) {
    return Defect::kPrincipal;
  }
  if (!finite(c.k1) || !finite(c.k2) || !finite(c.p1) || !finite(c.p2) || !finite(c.k3)) {
    return Defect::kCoefficients;
  }
  // The corners and edge midpoints, where a folding distortion shows first.
  const double us[3] = {0.0, 0.5 * (c.width - 1.0), c.width - 1.0};
  const double vs[3] = {0.0, 0.5 * (c.height - 1.0), c.height - 1.0};
  for (const double u : us) {
    for (const double v : vs) {
      NormalisedPoint p;
      if (!pixelToNormalised(c, u, v, &p)) {
        *u_out = u;
        *v_out = v;
        return Defect::kFolds;
      }
    }
  }
  return Defect::kNone;
}

}  // namespace

Expected<void, Error> CameraIntrinsics::validate() const {
  double u = 0.0;
  double v = 0.0;
  switch (firstDefect(*this, &u, &v)) {
    case Defect::kNone:
      return {};
    case Defect::kSize:
      return fail(ErrorCode::kInvalidArgument,
                  "camera width and height must be 1 to 65535 pixels (got " +
                      std::to_string(width) + " x " + std::to_string(height) + ")");
    case Defect::kFocal:
      return fail(ErrorCode::kInvalidArgument,
                  "camera focal lengths K[0] (fx) and K[4] (fy) must be finite and > 0");
    case Defect::kPrincipal:
      return fail(ErrorCode::kInvalidArgument,
                  "camera principal point K[2] (cx) and K[5] (cy) must be finite");
    case Defect::kCoefficients:
      return fail(ErrorCode::kInvalidArgument, "camera distortion coefficients D must be finite");
    case Defect::kFolds:
      break;
  }
  return fail(ErrorCode::kInvalidArgument, "camera distortion D cannot be inverted at pixel (" +
                                               std::to_string(u) + ", " + std::to_string(v) +
                                               "): the lens model folds over the image");
}

bool CameraIntrinsics::usable() const noexcept {
  double u = 0.0;
  double v = 0.0;
  return firstDefect(*this, &u, &v) == Defect::kNone;
}

NormalisedPoint projectNormalised(const CameraIntrinsics& camera, NormalisedPoint point) noexcept {
  const Distorted d = distort(camera, point.x, point.y);
  return {camera.fx * d.x + camera.cx, camera.fy * d.y + camera.cy};
}

bool pixelToNormalised(const CameraIntrinsics& camera, double u, double v,
                       NormalisedPoint* out) noexcept {
  const double xd = (u - camera.cx) / camera.fx;
  const double yd = (v - camera.cy) / camera.fy;
  if (!finite(xd) || !finite(yd)) {
    return false;
  }
  if (camera.distortion == DistortionModel::kNone) {
    *out = {xd, yd};
    return true;
  }
  double x = xd;
  double y = yd;
  for (int i = 0; i < kMaxIterations; ++i) {
    const Distorted d = distort(camera, x, y);
    const double ex = d.x - xd;
    const double ey = d.y - yd;
    const double det = d.dxdx * d.dydy - d.dxdy * d.dydx;
    if (!(det > 0.0)) {
      return false;  // a fold (or NaN): no unique ray for this pixel
    }
    if (std::fabs(ex) < kTolerance && std::fabs(ey) < kTolerance) {
      *out = {x, y};
      return true;
    }
    x -= (d.dydy * ex - d.dxdy * ey) / det;
    y -= (d.dxdx * ey - d.dydx * ex) / det;
  }
  return false;
}

void PixelRayTable::reserve(std::size_t pixels) { rays_.reserve(2 * pixels); }

Expected<void, Error> PixelRayTable::build(const CameraIntrinsics& camera) {
  if (matches(camera)) {
    return {};
  }
  built_ = false;
  if (auto valid = camera.validate(); !valid) {
    return valid;
  }
  rays_.resize(2 * static_cast<std::size_t>(camera.width) * camera.height);
  std::size_t i = 0;
  for (std::uint32_t v = 0; v < camera.height; ++v) {
    for (std::uint32_t u = 0; u < camera.width; ++u) {
      NormalisedPoint p;
      if (!pixelToNormalised(camera, u, v, &p)) {
        return fail(ErrorCode::kInvalidArgument,
                    "camera distortion D cannot be inverted at pixel (" + std::to_string(u) + ", " +
                        std::to_string(v) + ")");
      }
      rays_[i++] = static_cast<float>(p.x);
      rays_[i++] = static_cast<float>(p.y);
    }
  }
  camera_ = camera;
  built_ = true;
  return {};
}

}  // namespace raymap
