// SPDX-License-Identifier: BSD-3-Clause
// Wakeup: notifications are consumed once, never lost, and timeouts are never early.
#include <atomic>
#include <cstdint>
#include <thread>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "platform/wakeup.hpp"
#include "tests/support/nanoseconds.hpp"

namespace raymap::platform {
namespace {

using test::kMs;

TEST(Wakeup, TimesOutWithoutNotificationAndNotEarly) {
  Wakeup wakeup;
  const std::int64_t deadline = monotonicNowNs() + 30 * kMs;

  const bool notified = wakeup.waitUntilMonotonicNs(deadline);

  EXPECT_FALSE(notified);
  EXPECT_GE(monotonicNowNs(), deadline);
}

TEST(Wakeup, NotificationBeforeTheWaitIsKeptAndConsumedOnce) {
  Wakeup wakeup;
  wakeup.notify();
  wakeup.notify();  // collapses with the first

  // At once, not at the deadline: half of it apart leaves a loaded machine seconds.
  const std::int64_t start = monotonicNowNs();
  EXPECT_TRUE(wakeup.waitUntilMonotonicNs(start + 10000 * kMs));
  EXPECT_LT(monotonicNowNs() - start, 5000 * kMs);
  EXPECT_FALSE(wakeup.waitUntilMonotonicNs(monotonicNowNs() + 5 * kMs));
}

TEST(Wakeup, PastDeadlineOnlyPolls) {
  Wakeup wakeup;
  EXPECT_FALSE(wakeup.waitUntilMonotonicNs(0));
  wakeup.notify();
  EXPECT_TRUE(wakeup.waitUntilMonotonicNs(0));
  EXPECT_FALSE(wakeup.waitUntilMonotonicNs(monotonicNowNs() - kMs));
}

TEST(Wakeup, NotifyFromAnotherThreadWakesASleepingWaiter) {
  Wakeup wakeup;
  bool notified = false;
  std::int64_t waited_ns = 0;
  std::thread waiter([&] {
    const std::int64_t start = monotonicNowNs();
    notified = wakeup.waitUntilMonotonicNs(start + 5000 * kMs);
    waited_ns = monotonicNowNs() - start;
  });

  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  wakeup.notify();
  waiter.join();

  EXPECT_TRUE(notified);
  EXPECT_LT(waited_ns, 2000 * kMs);
}

TEST(Wakeup, PingPongPublishesDataAndLosesNothing) {
  constexpr int kRounds = 20000;
  Wakeup ping;
  Wakeup pong;
  int payload = 0;  // plain memory: published by notify(), seen after a true wait
  std::atomic<int> failures{0};
  std::thread responder([&] {
    for (int round = 1; round <= kRounds; ++round) {
      if (!ping.waitUntilMonotonicNs(monotonicNowNs() + 5000 * kMs) || payload != round) {
        failures.fetch_add(1);
        return;
      }
      payload = -round;
      pong.notify();
    }
  });

  for (int round = 1; round <= kRounds && failures.load() == 0; ++round) {
    payload = round;
    ping.notify();
    ASSERT_TRUE(pong.waitUntilMonotonicNs(monotonicNowNs() + 5000 * kMs)) << "round " << round;
    ASSERT_EQ(payload, -round);
  }
  responder.join();

  EXPECT_EQ(failures.load(), 0);
}

TEST(Wakeup, NotificationsRacingShortTimeoutsAreNeverLost) {
  // The waiter uses 50 us deadlines so notify() often lands while it times out.
  constexpr int kRounds = 3000;
  Wakeup event;
  Wakeup ack;
  std::atomic<int> timeouts{0};
  std::atomic<int> wrong{0};
  std::atomic<int> published{0};
  std::thread waiter([&] {
    for (int round = 1; round <= kRounds; ++round) {
      const std::int64_t give_up = monotonicNowNs() + 5000 * kMs;
      while (!event.waitUntilMonotonicNs(monotonicNowNs() + kMs / 20)) {
        timeouts.fetch_add(1, std::memory_order_relaxed);
        if (monotonicNowNs() > give_up) {
          wrong.fetch_add(1);
          return;
        }
      }
      if (published.load(std::memory_order_relaxed) != round) {
        wrong.fetch_add(1);
      }
      ack.notify();
    }
  });

  for (int round = 1; round <= kRounds; ++round) {
    // Vary the moment of notify() (0..450 us) against the waiter's 50 us timeouts.
    const std::int64_t notify_at = monotonicNowNs() + (round % 10) * 50'000;
    while (monotonicNowNs() < notify_at) {
    }
    published.store(round, std::memory_order_relaxed);
    event.notify();
    ASSERT_TRUE(ack.waitUntilMonotonicNs(monotonicNowNs() + 6000 * kMs)) << "round " << round;
  }
  waiter.join();

  EXPECT_EQ(wrong.load(), 0);
  std::printf("%d timeouts interleaved with %d notifications\n", timeouts.load(), kRounds);
}

}  // namespace
}  // namespace raymap::platform
