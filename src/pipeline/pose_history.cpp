// SPDX-License-Identifier: BSD-3-Clause
// PoseHistory: a ring of stamped poses with ordered-lookup hinting.
#include "src/pipeline/pose_history.hpp"

#include <algorithm>

#include "raymap/assert.hpp"

namespace raymap::pipeline {

const char* toString(PoseLookup lookup) noexcept {
  switch (lookup) {
    case PoseLookup::kOk:
      return "ok";
    case PoseLookup::kNotYet:
      return "not yet";
    case PoseLookup::kTooOld:
      return "too old";
    case PoseLookup::kEmpty:
      return "no pose";
  }
  return "?";
}

PoseHistory::PoseHistory(std::size_t capacity)
    : capacity_(capacity),
      stamps_(std::make_unique<std::int64_t[]>(capacity)),
      poses_(std::make_unique<io::Pose[]>(capacity)) {
  RAYMAP_EXPECTS(capacity >= 2);
}

std::int64_t PoseHistory::newestStamp() const noexcept {
  return size_ == 0 ? 0 : stamps_[at(size_ - 1)];
}

std::int64_t PoseHistory::oldestStamp() const noexcept { return size_ == 0 ? 0 : stamps_[at(0)]; }

bool PoseHistory::push(std::int64_t stamp_ns, const io::Pose& pose) noexcept {
  if (size_ > 0 && stamp_ns <= newestStamp()) {
    return false;
  }
  if (size_ == capacity_) {
    // NOLINTNEXTLINE(clang-analyzer-core.DivideZero): capacity_ >= 2 (the constructor's @pre)
    first_ = (first_ + 1) % capacity_;
    --size_;
    hint_ = hint_ > 0 ? hint_ - 1 : 0;
  }
  const std::size_t slot = at(size_);
  stamps_[slot] = stamp_ns;
  poses_[slot] = pose;
  ++size_;
  return true;
}

PoseLookup PoseHistory::lookup(std::int64_t stamp_ns, std::int64_t hold_ns,
                               io::Pose* out) const noexcept {
  if (size_ == 0) {
    return PoseLookup::kEmpty;
  }
  const std::int64_t newest = newestStamp();
  if (stamp_ns >= newest) {
    if (stamp_ns - newest > hold_ns) {
      return PoseLookup::kNotYet;
    }
    *out = poses_[at(size_ - 1)];
    return PoseLookup::kOk;
  }
  if (stamp_ns < oldestStamp()) {
    return PoseLookup::kTooOld;
  }
  // Find k with stamp(k) <= stamp_ns < stamp(k + 1); start from the last bracket.
  std::size_t k = hint_ < size_ - 1 ? hint_ : 0;
  if (stamps_[at(k)] > stamp_ns) {
    std::size_t lo = 0;
    std::size_t hi = k;  // stamp(lo) <= stamp_ns < stamp(hi)
    while (hi - lo > 1) {
      const std::size_t mid = lo + (hi - lo) / 2;
      (stamps_[at(mid)] <= stamp_ns ? lo : hi) = mid;
    }
    k = lo;
  } else {
    while (stamps_[at(k + 1)] <= stamp_ns) {  // ends: stamp_ns < newest
      ++k;
      if (k + 1 >= size_) {
        break;
      }
    }
  }
  hint_ = k;
  const std::int64_t t0 = stamps_[at(k)];
  const std::int64_t t1 = stamps_[at(k + 1)];
  const double f = static_cast<double>(stamp_ns - t0) / static_cast<double>(t1 - t0);
  *out = io::interpolate(poses_[at(k)], poses_[at(k + 1)], f);
  return PoseLookup::kOk;
}

std::size_t PoseHistory::floorOrdinal(std::int64_t stamp_ns) const noexcept {
  std::size_t lo = 0;
  std::size_t hi = size_;  // stamp(lo) <= stamp_ns < stamp(hi), with stamp(size_) = +infinity
  if (stamps_[at(0)] > stamp_ns) {
    return 0;
  }
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    (stamps_[at(mid)] <= stamp_ns ? lo : hi) = mid;
  }
  return lo;
}

std::size_t PoseHistory::copyCovering(std::int64_t from_ns, std::int64_t to_ns,
                                      std::span<rm_pose_sample> out) const noexcept {
  if (size_ == 0) {
    return 0;
  }
  const std::size_t first = floorOrdinal(from_ns);
  const std::size_t last = std::min(floorOrdinal(to_ns) + 1, size_ - 1);
  const std::size_t count = last - first + 1;
  if (count > out.size()) {
    return 0;
  }
  for (std::size_t k = 0; k < count; ++k) {
    out[k] = rm_pose_sample{stamps_[at(first + k)], 0, io::toRmPose(poses_[at(first + k)])};
  }
  return count;
}

}  // namespace raymap::pipeline
