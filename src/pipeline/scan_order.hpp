// SPDX-License-Identifier: BSD-3-Clause
// The order in which the integrator visits a scan's points: coarse to fine, so that a scan cut
// short at its latency deadline is still spread uniformly over the sensor's field of view.
#pragma once

#include <array>
#include <cstdint>

namespace raymap::pipeline {

/// @brief Visits every `stride`-th point of a scan of `points` points in kPasses interleaved
/// passes: pass p takes the kept points whose rank modulo kPasses is kOffsets[p] (0, 4, 2, 6, 1,
/// 5, 3, 7: each pass halves the gaps the earlier ones left). After any number of visits the
/// points taken so far are close to a uniform subsample of the scan, so stopping early (the
/// latency deadline) thins the whole scan instead of cutting off its last rows or columns.
///
/// Thread-safety: a plain value; one thread. @rt allocates: no; O(1) per visit.
class ScanOrder {
 public:
  static constexpr std::uint32_t kPasses = 8;

  /// @brief Starts over for a scan of `points` points, keeping every `stride`-th (stride >= 1).
  void reset(std::uint32_t points, std::uint32_t stride) noexcept {
    points_ = points;
    stride_ = stride < 1u ? 1u : stride;
    kept_ = (std::uint64_t{points} + stride_ - 1u) / stride_;
    visited_ = 0;
    pass_ = 0;
    next_ = 0;
  }

  /// @brief The next point to visit; false once every kept point has been visited.
  bool next(std::uint32_t* index) noexcept {
    while (pass_ < kPasses) {
      if (next_ < points_) {
        *index = static_cast<std::uint32_t>(next_);
        next_ += std::uint64_t{stride_} * kPasses;
        ++visited_;
        return true;
      }
      if (++pass_ < kPasses) {
        next_ = std::uint64_t{kOffsets[pass_]} * stride_;
      }
    }
    return false;
  }

  bool done() const noexcept { return visited_ == kept_; }
  /// @brief Points visited so far.
  std::uint64_t visited() const noexcept { return visited_; }
  /// @brief Points of the scan this order does not (or did not yet) visit.
  std::uint64_t notVisited() const noexcept { return std::uint64_t{points_} - visited_; }

 private:
  static constexpr std::array<std::uint32_t, kPasses> kOffsets{0, 4, 2, 6, 1, 5, 3, 7};

  std::uint32_t points_ = 0;
  std::uint32_t stride_ = 1;
  std::uint64_t kept_ = 0;
  std::uint64_t visited_ = 0;
  std::uint32_t pass_ = 0;
  std::uint64_t next_ = 0;
};

}  // namespace raymap::pipeline
