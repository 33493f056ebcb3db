// SPDX-License-Identifier: BSD-3-Clause
// SystemdNotifier against a fake notify socket: the messages, the environment rules, no heap use
// per call and no blocking when nobody reads.
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "platform/clock.hpp"
#include "platform/notify.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/fake_notify_socket.hpp"

namespace raymap::platform {
namespace {

using std::chrono::milliseconds;
constexpr milliseconds kWait{2000};

/// Sets environment variables for one test and restores them afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) {
      old_ = old;
    }
    if (value != nullptr) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_.c_str(), old_->c_str(), 1);
    } else {
      unsetenv(name_.c_str());
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_;
  std::optional<std::string> old_;
};

TEST(SystemdNotifier, WithoutNotifySocketEveryCallIsANoOp) {
  ScopedEnv socket("NOTIFY_SOCKET", nullptr);
  ScopedEnv usec("WATCHDOG_USEC", nullptr);
  SystemdNotifier notifier;

  notifier.ready("up");
  notifier.watchdog();
  notifier.status("x");
  notifier.stopping();

  EXPECT_FALSE(notifier.active());
  EXPECT_EQ(notifier.watchdogIntervalNs(), 0);
}

TEST(SystemdNotifier, UnsupportedAddressesLeaveItInactive) {
  EXPECT_FALSE(SystemdNotifier("", 0).active());
  EXPECT_FALSE(SystemdNotifier("relative/path", 0).active());
  EXPECT_FALSE(SystemdNotifier("vsock:2:1234", 0).active());
  EXPECT_FALSE(SystemdNotifier("@", 0).active());
  EXPECT_FALSE(SystemdNotifier(("/" + std::string(200, 'a')).c_str(), 0).active());
  EXPECT_FALSE(SystemdNotifier(nullptr, 5).active());
}

TEST(SystemdNotifier, SendsTheProtocolMessagesFromTheEnvironment) {
  test::FakeNotifySocket fake;
  const std::string pid = std::to_string(getpid());
  ScopedEnv socket("NOTIFY_SOCKET", fake.path().c_str());
  ScopedEnv usec("WATCHDOG_USEC", "2000000");
  ScopedEnv watchdog_pid("WATCHDOG_PID", pid.c_str());
  SystemdNotifier notifier;
  ASSERT_TRUE(notifier.active());
  EXPECT_EQ(notifier.watchdogIntervalNs(), 2'000'000'000);

  notifier.ready("mapping at 10 Hz");
  const auto ready = fake.receive(kWait);
  notifier.watchdog();
  const auto ping = fake.receive(kWait);
  notifier.status("degraded: SCHED_FIFO refused");
  const auto status = fake.receive(kWait);
  notifier.stopping();
  const auto stopping = fake.receive(kWait);

  ASSERT_TRUE(ready && ping && status && stopping);
  EXPECT_EQ(ready->text, "READY=1\nSTATUS=mapping at 10 Hz");
  EXPECT_TRUE(ready->hasLine("READY=1"));
  EXPECT_EQ(ready->value("STATUS"), "mapping at 10 Hz");
  EXPECT_EQ(ready->sender_pid, getpid());
  EXPECT_EQ(ping->text, "WATCHDOG=1");
  EXPECT_EQ(status->text, "STATUS=degraded: SCHED_FIFO refused");
  EXPECT_EQ(stopping->text, "STOPPING=1");
  EXPECT_EQ(fake.history().size(), 4u);
}

TEST(SystemdNotifier, ReadyWithoutStatusAndNewlinesCannotInjectAssignments) {
  test::FakeNotifySocket fake;
  SystemdNotifier notifier(fake.path().c_str(), 0);

  notifier.ready(nullptr);
  const auto ready = fake.receive(kWait);
  notifier.status("line one\nREADY=1");
  const auto status = fake.receive(kWait);
  notifier.status(nullptr);  // sends nothing
  const auto nothing = fake.receive(milliseconds(50));

  ASSERT_TRUE(ready && status);
  EXPECT_EQ(ready->text, "READY=1");
  EXPECT_EQ(status->text, "STATUS=line one");
  EXPECT_FALSE(nothing.has_value());
}

TEST(SystemdNotifier, WatchdogForAnotherPidOrWithoutUsecIsOff) {
  {
    ScopedEnv usec("WATCHDOG_USEC", "1000000");
    ScopedEnv watchdog_pid("WATCHDOG_PID", "1");
    EXPECT_EQ(SystemdNotifier().watchdogIntervalNs(), 0);
  }
  {
    ScopedEnv usec("WATCHDOG_USEC", "1000000");
    ScopedEnv watchdog_pid("WATCHDOG_PID", nullptr);
    EXPECT_EQ(SystemdNotifier().watchdogIntervalNs(), 1'000'000'000);
  }
  {
    ScopedEnv usec("WATCHDOG_USEC", "garbage");
    EXPECT_EQ(SystemdNotifier().watchdogIntervalNs(), 0);
  }
  {
    ScopedEnv usec("WATCHDOG_USEC", nullptr);
    EXPECT_EQ(SystemdNotifier().watchdogIntervalNs(), 0);
  }
}

TEST(SystemdNotifier, ReachesAnAbstractSocket) {
  test::FakeNotifySocket fake(test::FakeNotifySocket::Kind::kAbstract);
  ASSERT_EQ(fake.path().front(), '@');
  SystemdNotifier notifier(fake.path().c_str(), 0);

  notifier.watchdog();
  const auto ping = fake.waitFor("WATCHDOG=1", kWait);

  EXPECT_TRUE(notifier.active());
  ASSERT_TRUE(ping.has_value());
  EXPECT_EQ(ping->text, "WATCHDOG=1");
}

TEST(SystemdNotifier, CallsDoNotAllocate) {
  test::FakeNotifySocket fake;
  SystemdNotifier notifier(fake.path().c_str(), 1'000'000'000);
  if (!test::allocationCountingAvailable()) {
    GTEST_SKIP() << "sanitizer build: the sanitizer owns malloc";
  }
  std::uint64_t allocations = 0;
  {
    test::AllocationScope scope;  // malloc family, this thread
    for (int i = 0; i < 100; ++i) {
      notifier.ready("up");
      notifier.watchdog();
      notifier.status("status");
      notifier.stopping();
    }
    allocations = scope.count();
  }

  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(fake.waitFor("STOPPING=1", kWait).has_value());
}

TEST(SystemdNotifier, NeverBlocksWhenNobodyReads) {
  test::FakeNotifySocket fake;  // never read: its queue fills up
  SystemdNotifier notifier(fake.path().c_str(), 0);
  const std::int64_t start = monotonicNowNs();

  for (int i = 0; i < 20000; ++i) {
    notifier.watchdog();
  }

  // A call that blocked would wait for a reader that never comes. 20,000 that do not take tens
  // of milliseconds; the bound leaves a sanitizer build on a busy machine a wide margin.
  EXPECT_LT(monotonicNowNs() - start, std::int64_t{20'000'000'000});
}

TEST(SystemdNotifier, MovedFromIsInactiveAndMovedToStillSends) {
  test::FakeNotifySocket fake;
  SystemdNotifier first(fake.path().c_str(), 7);

  SystemdNotifier second(std::move(first));
  SystemdNotifier third;
  third = std::move(second);
  first.watchdog();  // NOLINT(bugprone-use-after-move): checking the moved-from state
  third.stopping();

  EXPECT_FALSE(first.active());  // NOLINT(bugprone-use-after-move): checking the moved-from state
  EXPECT_TRUE(third.active());
  EXPECT_EQ(third.watchdogIntervalNs(), 7);
  const auto message = fake.receive(kWait);
  ASSERT_TRUE(message.has_value());
  EXPECT_EQ(message->text, "STOPPING=1");
}

TEST(FakeNotifySocket, MaxGapMeasuresOnlyTheNamedLine) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0{};
  const std::vector<test::NotifyMessage> messages = {
      {"WATCHDOG=1", t0, 0},
      {"STATUS=x", t0 + milliseconds(500), 0},
      {"WATCHDOG=1", t0 + milliseconds(200), 0},
      {"WATCHDOG=1", t0 + milliseconds(450), 0},
  };

  EXPECT_EQ(test::FakeNotifySocket::maxGap(messages, "WATCHDOG=1"), milliseconds(250));
  EXPECT_EQ(test::FakeNotifySocket::maxGap(messages, "READY=1"), Clock::duration{0});
}

TEST(FakeNotifySocket, LongestSilenceCountsTheEndsOfTheInterval) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0{};
  const std::vector<test::NotifyMessage> messages = {
      {"WATCHDOG=1", t0 + milliseconds(100), 0},
      {"STATUS=x", t0 + milliseconds(900), 0},
      {"WATCHDOG=1", t0 + milliseconds(400), 0},
      {"WATCHDOG=1", t0 + milliseconds(700), 0},
  };
  const auto silence = [&](std::string_view line, int from_ms, int to_ms) {
    return test::FakeNotifySocket::longestSilence(messages, line, t0 + milliseconds(from_ms),
                                                  t0 + milliseconds(to_ms));
  };

  EXPECT_EQ(silence("WATCHDOG=1", 0, 1000), milliseconds(300));  // 400 to 700, 700 to the end
  EXPECT_EQ(silence("WATCHDOG=1", 0, 800), milliseconds(300));   // between the pings
  EXPECT_EQ(silence("WATCHDOG=1", 200, 1600), milliseconds(900));
  EXPECT_EQ(silence("WATCHDOG=1", 450, 650), milliseconds(200));  // none inside: all of it
  EXPECT_EQ(silence("READY=1", 0, 1000), milliseconds(1000));
}

}  // namespace
}  // namespace raymap::platform
