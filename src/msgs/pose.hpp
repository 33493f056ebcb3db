// SPDX-License-Identifier: BSD-3-Clause
// Decoding nav_msgs/Odometry and tf2_msgs/TFMessage from serialized XCDR1 bytes into stamped
// transforms.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "raymap/expected.hpp"

namespace raymap::msgs {

/// @brief A rigid transform T_parent_child at a time: p_parent = R(q) * p_child + t.
struct StampedTransform {
  std::int64_t stamp_ns;  ///< header.stamp, nanoseconds
  char parent[64];        ///< header.frame_id, NUL-terminated
  char child[64];         ///< child_frame_id, NUL-terminated
  double tx, ty, tz;      ///< translation, metres
  double qw, qx, qy, qz;  ///< rotation, a unit quaternion (normalised by the decoder)
};
static_assert(std::is_trivially_copyable_v<StampedTransform>);

/// Why an Odometry or TFMessage was rejected.
enum class PoseError : std::uint8_t {
  kTruncated,         ///< the bytes end before the message does (also absurd sequence lengths)
  kBadEncapsulation,  ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,         ///< a string without its NUL
  kFrameIdTooLong,    ///< a frame id has 64 or more characters
  kBadQuaternion,     ///< a quaternion that is not finite or has (near) zero norm
  kBadTranslation,    ///< a translation that is not finite
};

/// @brief Short, stable name ("truncated", "bad_quaternion", ...). @rt allocates: no.
const char* toString(PoseError error) noexcept;

/// @brief Decodes a serialized nav_msgs/Odometry: parent = header.frame_id,
/// child = child_frame_id, the transform = pose.pose (covariance and twist are skipped).
/// @rt allocates: no; blocks: no; thread: any.
Expected<StampedTransform, PoseError> decodeOdometry(std::span<const std::byte> cdr) noexcept;

/// @brief Decodes a serialized tf2_msgs/TFMessage. Every transform in the message is checked;
/// one bad transform rejects the whole message. The first `out.size()` transforms are written,
/// the rest are checked and dropped (give `out` room for what the robot publishes).
/// @return the number written to `out` (<= out.size())
/// @rt allocates: no; blocks: no; thread: any.
Expected<std::uint32_t, PoseError> decodeTfMessage(std::span<const std::byte> cdr,
                                                   std::span<StampedTransform> out) noexcept;

}  // namespace raymap::msgs
