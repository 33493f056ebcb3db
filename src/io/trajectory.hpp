// SPDX-License-Identifier: BSD-3-Clause
// Sensor trajectories from text files, and poses interpolated from them at any covered time.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include <Eigen/Geometry>

#include "kernels/common/pose.h"

namespace raymap::io {

/// @brief One trajectory line: time (s, the time base of the points), the body position in the
/// world frame (metres) and its orientation (body to world, a unit Hamilton quaternion; the
/// identity when the file has none).
struct TrajectorySample {
  double time_s = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// @brief A pose of frame b in frame a: p_a = orientation * p_b + position (metres; orientation a
/// unit quaternion). Default: the identity.
///
/// Plain data, cheap to copy (seven doubles, 64 bytes with the quaternion's 16-byte alignment; no
/// allocation; trivially destructible): it travels by value through the SPSC pose queue and the
/// PoseHistory ring. Not trivially copyable, as Eigen's fixed-size types have user-provided copy
/// operations; the queue and the ring need only copy construction and assignment (see
/// PoseUpdate).
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< origin of b in a, metres
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< b to a, unit length

  /// @brief Maps a point from the body frame into the world frame (metres): rm_pose_apply
  /// (kernels/common/pose.h), the one definition. Inline: deskewing calls it for every point.
  Eigen::Vector3d transform(const Eigen::Vector3d& p_body) const noexcept {
    const rm_vec3d p =
        rm_quat_rotate(rm_quat{orientation.w(), orientation.x(), orientation.y(), orientation.z()},
                       rm_vec3d{p_body.x(), p_body.y(), p_body.z()});
    return Eigen::Vector3d(position.x() + p.x, position.y() + p.y, position.z() + p.z);
  }
  /// @brief The same pose as an Eigen rigid transform (p_a = T * p_b).
  Eigen::Isometry3d toIsometry() const noexcept {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = orientation.toRotationMatrix();
    t.translation() = position;
    return t;
  }
  /// @brief The pose of a rigid transform. @pre t.linear() is a rotation; its quaternion is
  /// normalised, so the rounding of the matrix does not leave it off unit length.
  static Pose fromIsometry(const Eigen::Isometry3d& t) noexcept {
    return Pose{t.translation(), Eigen::Quaterniond(t.linear()).normalized()};
  }
};

/// @brief The pose of frame c in frame a from a_b (b in a) and b_c (c in b): p_a = a_b(b_c(p_c)).
/// rm_pose_compose (kernels/common/pose.h), the one definition.
Pose compose(const Pose& a_b, const Pose& b_c) noexcept;
/// @brief The pose a fraction f in [0, 1] of the way from `a` to `b`: position linearly,
/// orientation by normalised linear interpolation along the shorter arc (nlerp; close to slerp
/// for the small steps between pose samples). f = 0 gives `a` exactly. rm_pose_interpolate
/// (kernels/common/pose.h), the one definition.
Pose interpolate(const Pose& a, const Pose& b, double f) noexcept;

/// @brief The pose as kernels/common/pose.h takes it, and back.
rm_pose toRmPose(const Pose& pose) noexcept;
Pose fromRmPose(const rm_pose& pose) noexcept;

/// @brief Time-ordered poses of the sensor body, with interpolation in between: position
/// linearly, orientation by normalised linear quaternion interpolation along the shorter arc
/// (nlerp; close to slerp for the small steps between trajectory samples). Immutable after
/// loading; const methods are safe to call from several threads.
class Trajectory {
 public:
  /// @brief Loads a text trajectory (plain or gzip): one sample per line, `time x y z` or
  /// `time x y z qw qx qy qz`, separated by whitespace or commas. Blank lines and `#` comments
  /// are ignored, and so is one non-numeric header line before the first sample. Every line has
  /// the column count of the first; times increase strictly; quaternions are normalised.
  /// @return the trajectory, or an error "PATH: line N: problem".
  static Result<Trajectory> load(const std::string& path);

  /// @brief Builds a trajectory from samples (same checks as load()); `name` names it in errors.
  static Result<Trajectory> fromSamples(std::vector<TrajectorySample> samples, bool has_orientation,
                                        std::string name);

  const std::string& path() const noexcept { return path_; }
  /// @brief True when the samples carry orientations (else they are the identity).
  bool hasOrientation() const noexcept { return has_orientation_; }
  std::span<const TrajectorySample> samples() const noexcept { return samples_; }
  double startTime() const noexcept { return samples_.front().time_s; }
  double endTime() const noexcept { return samples_.back().time_s; }
  /// @brief True when startTime() <= time_s <= endTime() (the endpoints are inside).
  bool covers(double time_s) const noexcept { return time_s >= startTime() && time_s <= endTime(); }

  /// @brief The pose at `time_s`: exactly a sample's pose at that sample's time, interpolated
  /// between the two bracketing samples otherwise.
  /// @param[in,out] segment_hint index of the sample before the previous query (start at 0);
  /// makes time-ordered queries O(1) instead of a binary search each.
  /// @return nullopt when the trajectory does not cover `time_s` (NaN included).
  std::optional<Pose> poseAt(double time_s, std::size_t& segment_hint) const noexcept;
  std::optional<Pose> poseAt(double time_s) const noexcept {
    std::size_t hint = 0;
    return poseAt(time_s, hint);
  }

 private:
  Trajectory(std::string path, std::vector<TrajectorySample> samples,
             bool has_orientation) noexcept;

  std::string path_;
  std::vector<TrajectorySample> samples_;  // at least one, times strictly increasing
  bool has_orientation_ = false;
};

/// @brief Writes a trajectory as text that Trajectory::load() reads back exactly: a `#` comment
/// naming the columns, then one line per sample, `time x y z` or `time x y z qw qx qy qz` (with
/// orientations), every value with 17 significant digits. Temporary file + rename.
Expected<void, Error> saveTrajectory(const Trajectory& trajectory, const std::string& path);

}  // namespace raymap::io
