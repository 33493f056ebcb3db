// SPDX-License-Identifier: BSD-3-Clause
// ShutdownSignals on Linux: a blocked signal set drained with sigtimedwait.
#include "platform/signals.hpp"

#include <cerrno>
#include <ctime>

#include <pthread.h>

#include "platform/clock.hpp"

namespace raymap::platform {
namespace {
constexpr std::int64_t kNsPerSecond = 1'000'000'000;
}  // namespace

ShutdownSignals ShutdownSignals::install() noexcept {
  ShutdownSignals signals;
  sigemptyset(&signals.set_);
  sigaddset(&signals.set_, SIGTERM);
  sigaddset(&signals.set_, SIGINT);
  sigaddset(&signals.set_, SIGHUP);
  (void)pthread_sigmask(SIG_BLOCK, &signals.set_, nullptr);
  return signals;
}

int ShutdownSignals::waitNs(std::int64_t timeout_ns) noexcept {
  const std::int64_t deadline_ns = monotonicNowNs() + (timeout_ns > 0 ? timeout_ns : 0);
  for (;;) {
    const std::int64_t left_ns = deadline_ns - monotonicNowNs();
    timespec timeout{};
    if (left_ns > 0) {
      timeout.tv_sec = static_cast<time_t>(left_ns / kNsPerSecond);
      timeout.tv_nsec = static_cast<long>(left_ns % kNsPerSecond);
    }
    const int signal_number = sigtimedwait(&set_, nullptr, &timeout);
    if (signal_number > 0) {
      return signal_number;
    }
    if (errno != EINTR || left_ns <= 0) {
      return 0;  // EAGAIN: the timeout passed
    }
  }
}

}  // namespace raymap::platform
