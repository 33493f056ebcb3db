// SPDX-License-Identifier: BSD-3-Clause
// decodeCameraInfo over the bounded CDR reader: the intrinsics, binning and ROI applied as
// image_geometry applies them, then CameraIntrinsics::validate().
#include "src/msgs/camera_info.hpp"

#include <cmath>
#include <cstring>
#include <string_view>

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

/// plumb_bob's coefficients (k1 k2 p1 p2 k3); rational_polynomial adds k4 k5 k6 after them.
constexpr std::uint32_t kPlumbBobCoefficients = 5;
/// D entries read at most; a longer D is checked entry by entry without being stored.
constexpr std::uint32_t kMaxStoredCoefficients = 8;

Unexpected<CameraInfoError> readFailure(const CdrReader& reader) noexcept {
  return Unexpected(reader.malformed() ? CameraInfoError::kMalformed : CameraInfoError::kTruncated);
}

}  // namespace

const char* toString(CameraInfoError error) noexcept {
  switch (error) {
    case CameraInfoError::kTruncated:
      return "truncated";
    case CameraInfoError::kBadEncapsulation:
      return "bad_encapsulation";
    case CameraInfoError::kMalformed:
      return "malformed";
    case CameraInfoError::kFrameIdTooLong:
      return "frame_id_too_long";
    case CameraInfoError::kUnsupportedDistortion:
      return "unsupported_distortion";
    case CameraInfoError::kInvalidIntrinsics:
      return "invalid_intrinsics";
    case CameraInfoError::kTooLarge:
      return "too_large";
  }
  return "unknown";
}

Expected<CameraInfoHeader, CameraInfoError> decodeCameraInfo(
    std::span<const std::byte> cdr) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(CameraInfoError::kBadEncapsulation);
  }
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string_view model;
  std::uint32_t d_count = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(frame_id) ||
      !reader.readU32(height) || !reader.readU32(width) || !reader.readString(model) ||
      !reader.readSequenceLength(d_count, sizeof(double))) {
    return readFailure(reader);
  }
  // D: the first five are plumb_bob's; any further one (rational_polynomial's k4..k6, or more)
  // must be zero for the model raymap implements. Non-finite anywhere is invalid.
  double d[kMaxStoredCoefficients] = {};
  bool d_finite = true;
  bool d_extra_nonzero = false;
  bool d_any_nonzero = false;
  for (std::uint32_t i = 0; i < d_count; ++i) {
    double value = 0.0;
    if (!reader.readF64(value)) {
      return readFailure(reader);
    }
    if (i < kMaxStoredCoefficients) {
      d[i] = value;
    }
    d_finite = d_finite && std::isfinite(value);
    d_any_nonzero = d_any_nonzero || value != 0.0;
    d_extra_nonzero = d_extra_nonzero || (i >= kPlumbBobCoefficients && value != 0.0);
  }
  double k[9];
  for (double& value : k) {
    if (!reader.readF64(value)) {
      return readFailure(reader);
    }
  }
  // R (9) and P (12) are not used, but they must be there.
  for (int i = 0; i < 9 + 12; ++i) {
    double unused = 0.0;
    if (!reader.readF64(unused)) {
      return readFailure(reader);
    }
  }
  std::uint32_t binning_x = 0;
  std::uint32_t binning_y = 0;
  std::uint32_t roi_x = 0;
  std::uint32_t roi_y = 0;
  std::uint32_t roi_height = 0;
  std::uint32_t roi_width = 0;
  bool do_rectify = false;
  if (!reader.readU32(binning_x) || !reader.readU32(binning_y) || !reader.readU32(roi_x) ||
      !reader.readU32(roi_y) || !reader.readU32(roi_height) || !reader.readU32(roi_width) ||
      !reader.readBool(do_rectify)) {
    return readFailure(reader);
  }

  CameraInfoHeader out{};
  if (frame_id.size() >= sizeof(out.frame_id)) {
    return Unexpected(CameraInfoError::kFrameIdTooLong);
  }
  if (!frame_id.empty()) {  // an empty view may have a null data()
    std::memcpy(out.frame_id, frame_id.data(), frame_id.size());
  }
  out.frame_id[frame_id.size()] = '\0';
  out.stamp_ns = nanosecondsOf(sec, nanosec);

  if (!d_finite) {
    return Unexpected(CameraInfoError::kInvalidIntrinsics);
  }
  CameraIntrinsics& camera = out.camera;
  if (model == "plumb_bob" || model == "rational_polynomial") {
    if (d_count < kPlumbBobCoefficients || d_extra_nonzero) {
      return Unexpected(CameraInfoError::kUnsupportedDistortion);
    }
    // Every coefficient zero is a rectified image (drivers of rectified depth often say
    // plumb_bob with D = 0): kNone skips the Newton inversion.
    camera.distortion = d_any_nonzero ? DistortionModel::kPlumbBob : DistortionModel::kNone;
    camera.k1 = d[0];
    camera.k2 = d[1];
    camera.p1 = d[2];
    camera.p2 = d[3];
    camera.k3 = d[4];
  } else if (model.empty()) {
    // No model named: only "no distortion" can be meant; coefficients without a model cannot
    // be interpreted.
    if (d_any_nonzero) {
      return Unexpected(CameraInfoError::kUnsupportedDistortion);
    }
    camera.distortion = DistortionModel::kNone;
  } else {
    return Unexpected(CameraInfoError::kUnsupportedDistortion);
  }

  // K is row-major [fx s cx; 0 fy cy; 0 0 1]; skew is not modelled (no ROS driver sets it).
  double fx = k[0];
  double fy = k[4];
  double cx = k[2];
  double cy = k[5];
  // Binning 0 means 1; a ROI of all zeros is the whole image (sensor_msgs/CameraInfo). The ROI
  // is in full-resolution pixels, so it is applied first, then the binning (image_geometry's
  // order and formulas: K's focal lengths and principal point divided by the binning).
  const std::uint32_t bx = binning_x == 0 ? 1 : binning_x;
  const std::uint32_t by = binning_y == 0 ? 1 : binning_y;
  std::uint32_t full_width = width;
  std::uint32_t full_height = height;
  if (roi_x != 0 || roi_y != 0 || roi_width != 0 || roi_height != 0) {
    if (roi_width == 0 || roi_height == 0 ||
        std::uint64_t{roi_x} + roi_width > std::uint64_t{width} ||
        std::uint64_t{roi_y} + roi_height > std::uint64_t{height}) {
      return Unexpected(CameraInfoError::kInvalidIntrinsics);
    }
    cx -= static_cast<double>(roi_x);
    cy -= static_cast<double>(roi_y);
    full_width = roi_width;
    full_height = roi_height;
  }
  if (bx > 1) {
    fx /= static_cast<double>(bx);
    cx /= static_cast<double>(bx);
  }
  if (by > 1) {
    fy /= static_cast<double>(by);
    cy /= static_cast<double>(by);
  }
  camera.width = full_width / bx;
  camera.height = full_height / by;
  camera.fx = fx;
  camera.fy = fy;
  camera.cx = cx;
  camera.cy = cy;
  if (!camera.usable()) {  // validate()'s checks, without building its message
    return Unexpected(CameraInfoError::kInvalidIntrinsics);
  }
  return out;
}

}  // namespace raymap::msgs
