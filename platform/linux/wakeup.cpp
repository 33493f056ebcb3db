// SPDX-License-Identifier: BSD-3-Clause
// Wakeup on a Linux futex (FUTEX_WAIT_BITSET takes an absolute CLOCK_MONOTONIC deadline).
#include "platform/wakeup.hpp"

#include <cerrno>
#include <climits>
#include <ctime>

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace raymap::platform {
namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

// Private futexes: the word is never shared with another process.
long futexWaitUntil(std::atomic<std::uint32_t>* word, std::uint32_t expected,
                    const timespec* deadline) noexcept {
  // Without FUTEX_CLOCK_REALTIME, FUTEX_WAIT_BITSET measures the absolute timeout on
  // CLOCK_MONOTONIC, which is exactly our deadline's clock.
  return syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word),  // futex ABI
                 FUTEX_WAIT_BITSET | FUTEX_PRIVATE_FLAG, expected, deadline, nullptr,
                 FUTEX_BITSET_MATCH_ANY);
}

void futexWakeOne(std::atomic<std::uint32_t>* word) noexcept {
  (void)syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word),  // futex ABI
                FUTEX_WAKE | FUTEX_PRIVATE_FLAG, 1, nullptr, nullptr, 0);
}

}  // namespace

void Wakeup::notify() noexcept {
  if (state_.exchange(kNotified, std::memory_order_acq_rel) == kSleeping) {
    futexWakeOne(&state_);
  }
}

bool Wakeup::waitUntilMonotonicNs(std::int64_t deadline_ns) noexcept {
  timespec deadline{};
  if (deadline_ns > 0) {
    deadline.tv_sec = static_cast<time_t>(deadline_ns / kNsPerSecond);
    deadline.tv_nsec = static_cast<long>(deadline_ns % kNsPerSecond);
  }
  for (;;) {
    std::uint32_t seen = state_.load(std::memory_order_acquire);
    if (seen == kNotified) {
      // Only the waiter clears a notification, and only the notifier sets one, so the exchange
      // consumes exactly what was seen (a new notify() in between would write 1 again).
      state_.exchange(kEmpty, std::memory_order_acquire);
      return true;
    }
    if (seen == kEmpty &&
        !state_.compare_exchange_strong(seen, kSleeping, std::memory_order_acquire)) {
      continue;  // notified meanwhile (seen is now 1)
    }
    // state_ is kSleeping here (set by us; only notify() changes it, to kNotified).
    const long rc = futexWaitUntil(&state_, kSleeping, &deadline);
    if (rc != 0 && errno != EAGAIN && errno != EINTR) {
      // ETIMEDOUT (any other error cannot happen with a valid word and deadline; treating it as
      // a timeout keeps the waiter from spinning).
      std::uint32_t expected = kSleeping;
      if (state_.compare_exchange_strong(expected, kEmpty, std::memory_order_acquire)) {
        return false;
      }
      // A notify() raced with the timeout: it counts.
      state_.exchange(kEmpty, std::memory_order_acquire);
      return true;
    }
    // Woken (rc 0), the word changed before we slept (EAGAIN) or a signal (EINTR): look again.
  }
}

}  // namespace raymap::platform
