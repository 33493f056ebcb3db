// SPDX-License-Identifier: BSD-3-Clause
// Clocks and sleepUntilMonotonicNs: monotonic, close to std::chrono, never early.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>

#include "platform/clock.hpp"
#include "tests/support/nanoseconds.hpp"

namespace raymap::platform {
namespace {

using test::kMs;

TEST(Clock, MonotonicNeverGoesBack) {
  std::int64_t previous = monotonicNowNs();
  for (int i = 0; i < 10000; ++i) {
    const std::int64_t now = monotonicNowNs();
    ASSERT_GE(now, previous);
    previous = now;
  }
}

TEST(Clock, MatchesStdChronoClocks) {
  const auto steady = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now().time_since_epoch())
                          .count();
  const auto system = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();

  // The same clocks: read one after the other, apart only by a preemption (long on a loaded
  // machine); another clock would be off by far more (CLOCK_REALTIME vs TAI: 37 s).
  EXPECT_NEAR(static_cast<double>(monotonicNowNs()), static_cast<double>(steady), 1000.0 * kMs);
  EXPECT_NEAR(static_cast<double>(realtimeNowNs()), static_cast<double>(system), 1000.0 * kMs);
}

TEST(SleepUntil, NeverReturnsBeforeTheDeadline) {
  for (int i = 0; i < 20; ++i) {
    const std::int64_t deadline = monotonicNowNs() + 2 * kMs;
    sleepUntilMonotonicNs(deadline);
    ASSERT_GE(monotonicNowNs(), deadline) << "iteration " << i;
  }
}

TEST(SleepUntil, PastDeadlineReturnsAtOnce) {
  const std::int64_t start = monotonicNowNs();

  sleepUntilMonotonicNs(start - 10 * kMs);
  sleepUntilMonotonicNs(0);
  sleepUntilMonotonicNs(-1);

  // No sleep at all: microseconds, or a preemption on a loaded machine; a past deadline taken
  // for a relative or unsigned one would sleep far longer.
  EXPECT_LT(monotonicNowNs() - start, 1000 * kMs);
}

std::atomic<int> g_handled{0};
void countSignal(int /*signal*/) { g_handled.fetch_add(1, std::memory_order_relaxed); }

TEST(SleepUntil, ResumesAfterASignalHandlerRan) {
  struct sigaction action {};
  action.sa_handler = countSignal;  // no SA_RESTART: the sleep sees EINTR
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  g_handled = 0;
  std::atomic<bool> done{false};
  std::int64_t deadline = 0;
  std::int64_t woke = 0;
  std::thread sleeper([&] {
    deadline = monotonicNowNs() + 100 * kMs;
    sleepUntilMonotonicNs(deadline);
    woke = monotonicNowNs();
    done = true;
  });
  const pthread_t target = sleeper.native_handle();

  while (!done) {
    pthread_kill(target, SIGUSR1);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  sleeper.join();
  sigaction(SIGUSR1, &previous, nullptr);

  EXPECT_GT(g_handled.load(), 0);
  EXPECT_GE(woke, deadline);
}

}  // namespace
}  // namespace raymap::platform
