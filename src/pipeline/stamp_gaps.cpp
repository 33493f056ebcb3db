// SPDX-License-Identifier: BSD-3-Clause
// StampGaps: the period from the stream itself, gaps as whole missing periods.
#include "src/pipeline/stamp_gaps.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace raymap::pipeline {

std::uint32_t StampGaps::observe(std::int64_t stamp_ns) noexcept {
  if (!have_last_) {
    have_last_ = true;
    last_ns_ = stamp_ns;
    return 0;
  }
  const std::int64_t spacing = stamp_ns - last_ns_;
  if (spacing <= 0) {
    // Time went back (a loop, a simulation reset) or a duplicate stamp: start from here, with
    // the period learnt so far.
    last_ns_ = stamp_ns;
    return 0;
  }
  last_ns_ = stamp_ns;
  if (learnt_ < kLearnSpacings) {
    // The median of the first spacings: a loss while learning makes one spacing longer, jitter
    // makes some shorter and some longer; neither moves the median far.
    learning_[static_cast<std::size_t>(learnt_)] = spacing;
    if (++learnt_ == kLearnSpacings) {
      std::array<std::int64_t, kLearnSpacings> sorted = learning_;
      std::sort(sorted.begin(), sorted.end());
      period_ns_ = (sorted[kLearnSpacings / 2 - 1] + sorted[kLearnSpacings / 2]) / 2;
    }
    return 0;
  }
  const double periods = static_cast<double>(spacing) / static_cast<double>(period_ns_);
  if (periods < 0.75) {
    // Clearly shorter than the period learnt: losses while learning made it too long. The
    // gaps before this one were counted short, never long.
    period_ns_ = spacing;
    gaps_in_a_row_ = 0;
    return 0;
  }
  if (periods < 1.5) {
    gaps_in_a_row_ = 0;
    if (periods > 0.5) {
      period_ns_ += (spacing - period_ns_) / 16;  // follows a drifting clock slowly
    }
    return 0;
  }
  if (periods > kMaxGapPeriods) {
    gaps_in_a_row_ = 0;
    return 0;  // a pause, not a loss
  }
  const long whole = std::lround(periods);
  gaps_in_a_row_ = whole == last_gap_periods_ ? gaps_in_a_row_ + 1 : 1;
  last_gap_periods_ = whole;
  if (gaps_in_a_row_ >= kRelearnAfter) {
    // Every spacing the same gap: the sensor's rate changed (a camera that halved its frame
    // rate), where losses come in bursts of varying length.
    gaps_in_a_row_ = 0;
    learnt_ = 1;
    learning_[0] = spacing;
    return 0;
  }
  return static_cast<std::uint32_t>(whole - 1);
}

}  // namespace raymap::pipeline
