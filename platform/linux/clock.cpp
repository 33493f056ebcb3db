// SPDX-License-Identifier: BSD-3-Clause
// Clocks and absolute sleeps on Linux (clock_gettime / clock_nanosleep).
#include "platform/clock.hpp"

#include <cerrno>
#include <ctime>

namespace raymap::platform {
namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

std::int64_t nowNs(clockid_t clock) noexcept {
  timespec ts{};
  // Cannot fail for these clock ids and a valid pointer.
  (void)clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond +
         static_cast<std::int64_t>(ts.tv_nsec);
}

}  // namespace

std::int64_t monotonicNowNs() noexcept { return nowNs(CLOCK_MONOTONIC); }

std::int64_t realtimeNowNs() noexcept { return nowNs(CLOCK_REALTIME); }

void sleepUntilMonotonicNs(std::int64_t deadline_ns) noexcept {
  if (deadline_ns < 0) {
    return;  // before boot: already passed (and a negative tv_nsec would be EINVAL)
  }
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(deadline_ns / kNsPerSecond);
  deadline.tv_nsec = static_cast<long>(deadline_ns % kNsPerSecond);
  // clock_nanosleep returns the error number (it does not set errno). With an absolute deadline
  // an interrupted sleep is simply restarted with the same deadline.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

}  // namespace raymap::platform
