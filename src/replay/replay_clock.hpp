// SPDX-License-Identifier: BSD-3-Clause
// Replay time: when each recorded instant is published, and the stamp it carries.
#pragma once

#include <cstdint>

#include "platform/signals.hpp"

namespace raymap::replay {

/// @brief Maps replay time (seconds of recorded data since the replay started, across files and
/// loops) to the monotonic instant it is published and to the ROS stamp it carries.
/// Stamps advance with the data (stamp = wall clock at the start + replay time), whatever the
/// rate, so per-point times and poses stay consistent at any --rate; at rate 1 they follow the
/// wall clock like a live driver. Waiting is done on the shutdown signals, so Ctrl-C and SIGTERM
/// interrupt it. Not thread-safe.
class ReplayClock {
 public:
  /// @param rate data seconds per wall-clock second; 0 = no pacing (as fast as allowed)
  ReplayClock(double rate, platform::ShutdownSignals signals);
  /// @brief Time zero: now, on the monotonic clock and the wall clock.
  void start();
  /// @brief The stamp (nanoseconds since the epoch) of replay time `replay_s`.
  std::int64_t stampAt(double replay_s) const noexcept;
  /// @brief Sleeps until replay time `replay_s` is due (returns at once when unpaced).
  /// @return false when a shutdown signal arrived (stop replaying).
  bool waitUntil(double replay_s);
  /// @brief Sleeps `seconds` of wall-clock time; false on a shutdown signal.
  bool sleepFor(double seconds);
  bool stopped() const noexcept { return stopped_; }
  double rate() const noexcept { return rate_; }
  /// @brief The largest delay between an instant being due and waitUntil() returning for it
  /// (milliseconds; how far the replay fell behind the recording at its worst).
  double maxLateMs() const noexcept { return max_late_ms_; }
  /// @brief Monotonic seconds since start().
  double elapsed() const noexcept;

 private:
  double rate_;
  platform::ShutdownSignals signals_;
  std::int64_t monotonic_zero_ns_ = 0;
  std::int64_t stamp_zero_ns_ = 0;
  double max_late_ms_ = 0.0;
  bool stopped_ = false;
};

}  // namespace raymap::replay
