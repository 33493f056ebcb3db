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

/// The fields of a CameraInfo as read, before they are interpreted.
struct RawCameraInfo {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string_view model;
  std::uint32_t d_count = 0;
  double d[kMaxStoredCoefficients] = {};
  bool d_finite = true;
  bool d_extra_nonzero = false;
  bool d_any_nonzero = false;
  double k[9] = {};
  std::uint32_t binning_x = 0;
  std::uint32_t binning_y = 0;
  std::uint32_t roi_x = 0;
  std::uint32_t roi_y = 0;
  std::uint32_t roi_height = 0;
  std::uint32_t roi_width = 0;
  bool do_rectify = false;
};

/// The header, the image size, the distortion model and D. D's first five are plumb_bob's; any
/// further one (rational_polynomial's k4..k6, or more) must be zero for the model raymap
/// implements. Non-finite anywhere is invalid.
Expected<void, CameraInfoError> readHeaderAndDistortion(CdrReader& reader,
                                                        RawCameraInfo& raw) noexcept {
  if (!reader.readI32(raw.sec) || !reader.readU32(raw.nanosec) ||
      !reader.readString(raw.frame_id) || !reader.readU32(raw.height) ||
      !reader.readU32(raw.width) || !reader.readString(raw.model) ||
      !reader.readSequenceLength(raw.d_count, sizeof(double))) {
    return readFailure(reader);
  }
  for (std::uint32_t i = 0; i < raw.d_count; ++i) {
    double value = 0.0;
    if (!reader.readF64(value)) {
      return readFailure(reader);
    }
    if (i < kMaxStoredCoefficients) {
      raw.d[i] = value;
    }
    raw.d_finite = raw.d_finite && std::isfinite(value);
    raw.d_any_nonzero = raw.d_any_nonzero || value != 0.0;
    raw.d_extra_nonzero = raw.d_extra_nonzero || (i >= kPlumbBobCoefficients && value != 0.0);
  }
  return {};
}

/// K, then R and P (not used, but they must be there), binning, ROI and do_rectify.
Expected<void, CameraInfoError> readMatricesAndRoi(CdrReader& reader, RawCameraInfo& raw) noexcept {
  for (double& value : raw.k) {
    if (!reader.readF64(value)) {
      return readFailure(reader);
    }
  }
  for (int i = 0; i < 9 + 12; ++i) {
    double unused = 0.0;
    if (!reader.readF64(unused)) {
      return readFailure(reader);
    }
  }
  if (!reader.readU32(raw.binning_x) || !reader.readU32(raw.binning_y) ||
      !reader.readU32(raw.roi_x) || !reader.readU32(raw.roi_y) || !reader.readU32(raw.roi_height) ||
      !reader.readU32(raw.roi_width) || !reader.readBool(raw.do_rectify)) {
    return readFailure(reader);
  }
  return {};
}

/// The distortion model raymap implements from the named one and D.
Expected<void, CameraInfoError> applyDistortion(const RawCameraInfo& raw,
                                                CameraIntrinsics& camera) noexcept {
  if (!raw.d_finite) {
    return Unexpected(CameraInfoError::kInvalidIntrinsics);
  }
  if (raw.model == "plumb_bob" || raw.model == "rational_polynomial") {
    if (raw.d_count < kPlumbBobCoefficients || raw.d_extra_nonzero) {
      return Unexpected(CameraInfoError::kUnsupportedDistortion);
    }
    // Every coefficient zero is a rectified image (drivers of rectified depth often say
    // plumb_bob with D = 0): kNone skips the Newton inversion.
    camera.distortion = raw.d_any_nonzero ? DistortionModel::kPlumbBob : DistortionModel::kNone;
    camera.k1 = raw.d[0];
    camera.k2 = raw.d[1];
    camera.p1 = raw.d[2];
    camera.p2 = raw.d[3];
    camera.k3 = raw.d[4];
    return {};
  }
  if (raw.model.empty()) {
    // No model named: only "no distortion" can be meant; coefficients without a model cannot
    // be interpreted.
    if (raw.d_any_nonzero) {
      return Unexpected(CameraInfoError::kUnsupportedDistortion);
    }
    camera.distortion = DistortionModel::kNone;
    return {};
  }
  return Unexpected(CameraInfoError::kUnsupportedDistortion);
}

/// The image size, focal lengths and principal point: K, then the ROI, then the binning.
Expected<void, CameraInfoError> applyGeometry(const RawCameraInfo& raw,
                                              CameraIntrinsics& camera) noexcept {
  // K is row-major [fx s cx; 0 fy cy; 0 0 1]; skew is not modelled (no ROS driver sets it).
  double fx = raw.k[0];
  double fy = raw.k[4];
  double cx = raw.k[2];
  double cy = raw.k[5];
  // Binning 0 means 1; a ROI of all zeros is the whole image (sensor_msgs/CameraInfo). The ROI
  // is in full-resolution pixels, so it is applied first, then the binning (image_geometry's
  // order and formulas: K's focal lengths and principal point divided by the binning).
  const std::uint32_t bx = raw.binning_x == 0 ? 1 : raw.binning_x;
  const std::uint32_t by = raw.binning_y == 0 ? 1 : raw.binning_y;
  std::uint32_t full_width = raw.width;
  std::uint32_t full_height = raw.height;
  if (raw.roi_x != 0 || raw.roi_y != 0 || raw.roi_width != 0 || raw.roi_height != 0) {
    if (raw.roi_width == 0 || raw.roi_height == 0 ||
        std::uint64_t{raw.roi_x} + raw.roi_width > std::uint64_t{raw.width} ||
        std::uint64_t{raw.roi_y} + raw.roi_height > std::uint64_t{raw.height}) {
      return Unexpected(CameraInfoError::kInvalidIntrinsics);
    }
    cx -= static_cast<double>(raw.roi_x);
    cy -= static_cast<double>(raw.roi_y);
    full_width = raw.roi_width;
    full_height = raw.roi_height;
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
  return {};
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
  RawCameraInfo raw;
  if (auto ok = readHeaderAndDistortion(reader, raw); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = readMatricesAndRoi(reader, raw); !ok) {
    return Unexpected(ok.error());
  }
  CameraInfoHeader out{};
  if (raw.frame_id.size() >= sizeof(out.frame_id)) {
    return Unexpected(CameraInfoError::kFrameIdTooLong);
  }
  if (!raw.frame_id.empty()) {  // an empty view may have a null data()
    std::memcpy(out.frame_id, raw.frame_id.data(), raw.frame_id.size());
  }
  out.frame_id[raw.frame_id.size()] = '\0';
  out.stamp_ns = nanosecondsOf(raw.sec, raw.nanosec);
  if (auto ok = applyDistortion(raw, out.camera); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = applyGeometry(raw, out.camera); !ok) {
    return Unexpected(ok.error());
  }
  return out;
}

}  // namespace raymap::msgs
