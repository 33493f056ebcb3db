// SPDX-License-Identifier: BSD-3-Clause
// Messages missing from a periodic sensor stream, counted from the gaps in their header stamps.
#pragma once

#include <array>
#include <cstdint>

namespace raymap::pipeline {

/// @brief Counts the messages missing from a periodic sensor stream by the gaps in the header
/// stamps of those that arrive: a 10 Hz lidar whose next cloud is stamped 0.3 s after the last
/// lost two on the way (in a socket whose receive buffer overflowed, on the network, or in its
/// driver). Best-effort DDS readers are told of no such loss, so this is how raymapd names it.
///
/// The period is learnt from the stream (the median of the first kLearnSpacings (even) spacings,
/// then followed slowly; a spacing clearly shorter replaces it, when losses while learning made
/// it too long), so nothing is configured. Not counted: the first messages while learning,
/// a stamp at or before the last (time going back: a bag played in a loop), and a pause of more
/// than kMaxGapPeriods periods (a sensor that stopped, which the staleness check reports). A rate
/// that changed for good (kRelearnAfter gaps in a row of the same length) is learnt again; losses
/// come in bursts of varying length.
/// Thread-safety: a plain value; one thread. @rt allocates: no; O(1).
class StampGaps {
 public:
  static constexpr int kLearnSpacings = 4;
  static_assert(kLearnSpacings % 2 == 0, "the median is the mean of the middle two");
  static constexpr double kMaxGapPeriods = 20.0;
  static constexpr int kRelearnAfter = 8;

  /// @brief Takes the next message's header stamp (ns, any epoch).
  /// @return how many messages are missing between the previous one and this one
  std::uint32_t observe(std::int64_t stamp_ns) noexcept;

  /// @brief The period learnt so far (ns); 0 while learning.
  std::int64_t periodNs() const noexcept { return learnt_ >= kLearnSpacings ? period_ns_ : 0; }

 private:
  bool have_last_ = false;
  std::int64_t last_ns_ = 0;
  std::int64_t period_ns_ = 0;
  std::array<std::int64_t, kLearnSpacings> learning_{};  // the first spacings
  int learnt_ = 0;                                       // spacings seen while learning
  int gaps_in_a_row_ = 0;      // gaps in a row of the same whole number of periods
  long last_gap_periods_ = 0;  // that number
};

}  // namespace raymap::pipeline
