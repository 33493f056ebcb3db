// SPDX-License-Identifier: BSD-3-Clause
// A fixed-capacity history of the robot's pose over time, interpolated at any covered instant
// (deskewing a scan needs the pose at each point's time).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "kernels/common/deskew.h"
#include "src/io/trajectory.hpp"

namespace raymap::pipeline {

/// Result of a pose lookup.
enum class PoseLookup : std::uint8_t {
  kOk,      ///< inside the history (or within the tolerance beyond its newest pose)
  kNotYet,  ///< later than the newest pose: the pose source has not caught up yet
  kTooOld,  ///< earlier than the oldest pose kept
  kEmpty,   ///< no pose received yet
};
const char* toString(PoseLookup lookup) noexcept;

/// @brief Poses of one body (base frame in the world frame) at increasing times, in a ring of
/// fixed capacity: the newest `capacity` poses are kept.
/// Thread-safety: one thread (the integrator) owns it. @rt push/lookup allocate: no.
class PoseHistory {
 public:
  /// @brief Allocates room for `capacity` poses (start-up only). @pre capacity >= 2
  explicit PoseHistory(std::size_t capacity);

  /// @brief Appends a pose. A stamp not later than the newest is ignored (returns false).
  bool push(std::int64_t stamp_ns, const io::Pose& pose) noexcept;
  /// @brief The pose at `stamp_ns` (ns, the pose source's clock): interpolated between the two
  /// bracketing poses (io::interpolate); up to `hold_ns` after the newest pose, the newest pose.
  PoseLookup lookup(std::int64_t stamp_ns, std::int64_t hold_ns, io::Pose* out) const noexcept;

  /// @brief Copies the poses that cover [from_ns, to_ns] into `out`, in time order, for
  /// rm_deskew_base_pose (kernels/common/deskew.h), which then gives what lookup() gives now for
  /// any time in that range that lookup() finds: from the pose at or before from_ns (the oldest
  /// if none) to the first after to_ns (the newest if none). @return the poses written; 0 when
  /// the history is empty or they do not fit `out`.
  std::size_t copyCovering(std::int64_t from_ns, std::int64_t to_ns,
                           std::span<rm_pose_sample> out) const noexcept;

  /// @brief Forgets every pose (time went backwards, or the pose jumped): lookups find none until
  /// the next push(). @rt allocates: no.
  void clear() noexcept {
    first_ = 0;
    size_ = 0;
    hint_ = 0;
  }

  std::size_t size() const noexcept { return size_; }
  /// @brief The newest pose (nullptr when empty).
  const io::Pose* newestPose() const noexcept {
    return size_ == 0 ? nullptr : &poses_[at(size_ - 1)];
  }
  std::int64_t newestStamp() const noexcept;
  std::int64_t oldestStamp() const noexcept;

 private:
  std::size_t at(std::size_t k) const noexcept { return (first_ + k) % capacity_; }

  std::size_t capacity_;
  std::unique_ptr<std::int64_t[]> stamps_;
  std::unique_ptr<io::Pose[]> poses_;
  std::size_t first_ = 0;  // ring index of the oldest pose
  std::size_t size_ = 0;
  mutable std::size_t hint_ = 0;  // ordinal of the last bracket found (lookups are mostly ordered)

  /// The ordinal of the last pose at or before `stamp_ns` (0 when all are later).
  std::size_t floorOrdinal(std::int64_t stamp_ns) const noexcept;
};

}  // namespace raymap::pipeline
