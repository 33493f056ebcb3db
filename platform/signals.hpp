// SPDX-License-Identifier: BSD-3-Clause
// ShutdownSignals: SIGTERM, SIGINT and SIGHUP taken synchronously (sigtimedwait), no handlers.
#pragma once

#include <csignal>
#include <cstdint>

namespace raymap::platform {

/// @brief The shutdown signals (SIGTERM, SIGINT, SIGHUP), blocked and then received on demand
/// with sigtimedwait, so no asynchronous handler ever interrupts a real-time thread.
///
/// Design: install() blocks the three signals in the calling thread. Threads created afterwards
/// inherit the mask, so when install() runs in main before any thread starts, no thread accepts
/// them asynchronously and a process-directed signal stays pending until some thread calls
/// waitNs(). SIGHUP is treated as a shutdown request too (no configuration reload).
/// Thread-safety: waitNs() may be called from any thread that has the signals blocked; normally
/// one (main). Value type (the set of signals), cheap to copy.
class ShutdownSignals {
 public:
  /// @brief Blocks SIGTERM, SIGINT and SIGHUP in the calling thread (pthread_sigmask).
  /// @pre Call in main before any thread is created.
  /// @rt allocates: no; syscalls: rt_sigprocmask; thread: main, start-up only. Never fails (the
  /// set is valid, so pthread_sigmask cannot fail).
  static ShutdownSignals install() noexcept;

  /// @brief Waits for one of the shutdown signals.
  /// @param[in] timeout_ns how long to wait; <= 0 only polls.
  /// @return the signal number (SIGTERM, SIGINT or SIGHUP), or 0 when none arrived in time.
  /// EINTR (another signal's handler ran) is retried with the remaining time.
  /// @rt blocks up to the timeout; allocates: no; syscalls: rt_sigtimedwait; thread: any with the
  /// signals blocked.
  int waitNs(std::int64_t timeout_ns) noexcept;

  /// @brief The blocked set (for callers that also want to restore or extend the mask).
  /// @rt wait-free; allocates: no; thread: any.
  const sigset_t& set() const noexcept { return set_; }

 private:
  ShutdownSignals() noexcept = default;
  sigset_t set_{};
};

}  // namespace raymap::platform
