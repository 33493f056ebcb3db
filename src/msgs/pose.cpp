// SPDX-License-Identifier: BSD-3-Clause
// decodeOdometry and decodeTfMessage over the bounded CDR reader.
#include "src/msgs/pose.hpp"

#include <cmath>
#include <cstring>
#include <string_view>

#include <Eigen/Geometry>

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

/// Below this norm a quaternion carries no usable rotation.
constexpr double kMinQuaternionNorm = 1e-6;

Unexpected<PoseError> readFailure(const CdrReader& reader) noexcept {
  return Unexpected(reader.malformed() ? PoseError::kMalformed : PoseError::kTruncated);
}

bool copyFrame(std::string_view name, char (&out)[64]) noexcept {
  if (name.size() >= sizeof(out)) {
    return false;
  }
  if (!name.empty()) {  // an empty view may have a null data()
    std::memcpy(out, name.data(), name.size());
  }
  out[name.size()] = '\0';
  return true;
}

/// std_msgs/Header: stamp and frame_id.
bool readHeader(CdrReader& reader, std::int64_t& stamp_ns, std::string_view& frame_id) noexcept {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(frame_id)) {
    return false;
  }
  stamp_ns = nanosecondsOf(sec, nanosec);
  return true;
}

/// Point/Vector3 then Quaternion (x, y, z, w): the same layout in Pose and Transform.
bool readPose(CdrReader& reader, StampedTransform& out) noexcept {
  return reader.readF64(out.tx) && reader.readF64(out.ty) && reader.readF64(out.tz) &&
         reader.readF64(out.qx) && reader.readF64(out.qy) && reader.readF64(out.qz) &&
         reader.readF64(out.qw);
}

/// Checks the translation and normalises the rotation.
Expected<void, PoseError> checkPose(StampedTransform& out) noexcept {
  if (!std::isfinite(out.tx) || !std::isfinite(out.ty) || !std::isfinite(out.tz)) {
    return Unexpected(PoseError::kBadTranslation);
  }
  // The wire struct stays plain (trivially copyable); Eigen normalises at use: the division by
  // the norm that Quaterniond::normalized() does, which tests predicting the decoder rely on.
  Eigen::Quaterniond q(out.qw, out.qx, out.qy, out.qz);
  const double norm = q.norm();
  if (!std::isfinite(norm) || norm < kMinQuaternionNorm) {
    return Unexpected(PoseError::kBadQuaternion);
  }
  q.coeffs() /= norm;
  out.qw = q.w();
  out.qx = q.x();
  out.qy = q.y();
  out.qz = q.z();
  return {};
}

}  // namespace

const char* toString(PoseError error) noexcept {
  switch (error) {
    case PoseError::kTruncated:
      return "truncated";
    case PoseError::kBadEncapsulation:
      return "bad_encapsulation";
    case PoseError::kMalformed:
      return "malformed";
    case PoseError::kFrameIdTooLong:
      return "frame_id_too_long";
    case PoseError::kBadQuaternion:
      return "bad_quaternion";
    case PoseError::kBadTranslation:
      return "bad_translation";
  }
  return "unknown";
}

Expected<StampedTransform, PoseError> decodeOdometry(std::span<const std::byte> cdr) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(PoseError::kBadEncapsulation);
  }
  StampedTransform out{};
  std::string_view parent;
  std::string_view child;
  // header, child_frame_id, pose.pose; pose.covariance and the twist follow and are not needed,
  // but they must be there: a message cut short after the pose is refused.
  constexpr std::size_t kCovarianceBytes = 36 * sizeof(double);
  constexpr std::size_t kTwistWithCovarianceBytes = 6 * sizeof(double) + kCovarianceBytes;
  if (!readHeader(reader, out.stamp_ns, parent) || !reader.readString(child) ||
      !readPose(reader, out) || !reader.skip(kCovarianceBytes + kTwistWithCovarianceBytes)) {
    return readFailure(reader);
  }
  if (!copyFrame(parent, out.parent) || !copyFrame(child, out.child)) {
    return Unexpected(PoseError::kFrameIdTooLong);
  }
  if (auto checked = checkPose(out); !checked) {
    return Unexpected(checked.error());
  }
  return out;
}

Expected<std::uint32_t, PoseError> decodeTfMessage(std::span<const std::byte> cdr,
                                                   std::span<StampedTransform> out) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(PoseError::kBadEncapsulation);
  }
  // A TransformStamped is at least 8 (stamp) + 4 + 4 (two empty strings) + 56 (transform).
  constexpr std::size_t kMinTransformBytes = 72;
  std::uint32_t count = 0;
  if (!reader.readSequenceLength(count, kMinTransformBytes)) {
    return readFailure(reader);
  }
  std::uint32_t written = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    StampedTransform transform{};
    std::string_view parent;
    std::string_view child;
    if (!readHeader(reader, transform.stamp_ns, parent) || !reader.readString(child) ||
        !readPose(reader, transform)) {
      return readFailure(reader);
    }
    if (!copyFrame(parent, transform.parent) || !copyFrame(child, transform.child)) {
      return Unexpected(PoseError::kFrameIdTooLong);
    }
    if (auto checked = checkPose(transform); !checked) {
      return Unexpected(checked.error());
    }
    if (written < out.size()) {
      out[written] = transform;
      ++written;
    }
  }
  return written;
}

}  // namespace raymap::msgs
