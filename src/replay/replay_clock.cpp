// SPDX-License-Identifier: BSD-3-Clause
// ReplayClock: pacing on the monotonic clock, interruptible by the shutdown signals.
#include "src/replay/replay_clock.hpp"

#include <algorithm>
#include <cmath>

#include "platform/clock.hpp"

namespace raymap::replay {

ReplayClock::ReplayClock(double rate, platform::ShutdownSignals signals)
    : rate_(rate), signals_(signals) {}

void ReplayClock::start() {
  monotonic_zero_ns_ = platform::monotonicNowNs();
  stamp_zero_ns_ = platform::realtimeNowNs();
}

std::int64_t ReplayClock::stampAt(double replay_s) const noexcept {
  return stamp_zero_ns_ + std::llround(replay_s * 1e9);
}

double ReplayClock::elapsed() const noexcept {
  return static_cast<double>(platform::monotonicNowNs() - monotonic_zero_ns_) * 1e-9;
}

bool ReplayClock::waitUntil(double replay_s) {
  if (stopped_) {
    return false;
  }
  if (rate_ <= 0.0) {
    if (signals_.waitNs(0) != 0) {
      stopped_ = true;
    }
    return !stopped_;
  }
  const std::int64_t due = monotonic_zero_ns_ + std::llround(replay_s / rate_ * 1e9);
  std::int64_t now = platform::monotonicNowNs();
  while (now < due) {
    if (signals_.waitNs(due - now) != 0) {
      stopped_ = true;
      return false;
    }
    now = platform::monotonicNowNs();
  }
  max_late_ms_ = std::max(max_late_ms_, static_cast<double>(now - due) * 1e-6);
  if (signals_.waitNs(0) != 0) {
    stopped_ = true;
  }
  return !stopped_;
}

bool ReplayClock::sleepFor(double seconds) {
  if (stopped_) {
    return false;
  }
  if (signals_.waitNs(std::llround(seconds * 1e9)) != 0) {
    stopped_ = true;
  }
  return !stopped_;
}

}  // namespace raymap::replay
