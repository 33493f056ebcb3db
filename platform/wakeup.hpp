// SPDX-License-Identifier: BSD-3-Clause
// Wakeup: a binary event from one notifier thread to one waiter thread, on a Linux futex.
#pragma once

#include <atomic>
#include <cstdint>

namespace raymap::platform {

/// @brief A binary event between exactly one notifier and one waiter: notify() sets it, the
/// waiter's waitUntilMonotonicNs() consumes it. Notifications before the wait are not lost;
/// several notifications before one wait collapse into one.
///
/// Design: one 32-bit futex word, state_ (the waiter owns the 0 -> 2 and 2 -> 0 transitions,
/// the notifier only ever stores 1):
///
///        notify(): exchange(1); FUTEX_WAKE only if it was 2 (a waiter sleeps)
///    +-------------------------------------------------+
///    v                                                 |
///   [1 notified] --wait: exchange(0)--> [0 empty] --wait: CAS 0->2--> [2 waiter asleep]
///                                          ^                           |
///                                          +--timeout: CAS 2->0--------+
///
/// Orderings: notify() is a release exchange and the waiter consumes with acquire exchanges, so
/// what the notifier wrote before notify() is visible to the waiter after it returns true.
/// Overflow policy: none needed (a binary state). Not copyable or movable (the futex is the
/// object's address).
/// Thread-safety: notify() may be called from any thread (several notifiers are safe but
/// indistinguishable); waitUntilMonotonicNs() from exactly one thread at a time.
class Wakeup {
 public:
  Wakeup() noexcept = default;
  ~Wakeup() = default;
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  /// @brief Sets the event and wakes the waiter if it sleeps.
  /// @rt wait-free; never blocks; allocates: no; syscalls: futex wake only when a waiter sleeps;
  /// thread: the notifier.
  void notify() noexcept;

  /// @brief Waits until notified or until CLOCK_MONOTONIC reaches `deadline_ns`.
  /// @param[in] deadline_ns absolute monotonic time (platform::monotonicNowNs()); a past deadline
  /// only polls.
  /// @return true when a notification was consumed; false once the deadline has passed (never
  /// before it). Spurious returns are not possible: true always means a notify() happened.
  /// @rt blocks until notified or the deadline; allocates: no; syscalls: futex wait; thread: the
  /// single waiter.
  bool waitUntilMonotonicNs(std::int64_t deadline_ns) noexcept;

 private:
  static constexpr std::uint32_t kEmpty = 0;
  static constexpr std::uint32_t kNotified = 1;
  static constexpr std::uint32_t kSleeping = 2;
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
  static_assert(sizeof(std::atomic<std::uint32_t>) == 4, "the futex word is 32 bits");

  std::atomic<std::uint32_t> state_{kEmpty};
};

}  // namespace raymap::platform
