// SPDX-License-Identifier: BSD-3-Clause
// ShutdownSignals: a raised SIGTERM is received synchronously; threads inherit the mask. Each
// test runs in a child process so the blocked mask never leaks into other tests.
#include <cstdint>
#include <thread>

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include "platform/clock.hpp"
#include "platform/signals.hpp"
#include "tests/support/nanoseconds.hpp"
#include "tests/unit/platform/child_process.hpp"

namespace raymap::platform {
namespace {

using test::kMs;

TEST(ShutdownSignals, ReceivesARaisedSigterm) {
  const int code = test::runInChild([] {
    ShutdownSignals signals = ShutdownSignals::install();
    kill(getpid(), SIGTERM);  // process-directed, as systemd sends it
    const int first = signals.waitNs(1000 * kMs);
    const int second = signals.waitNs(10 * kMs);  // consumed: nothing left
    if (first != SIGTERM) {
      return 10;
    }
    return second == 0 ? 0 : 11;
  });

  EXPECT_EQ(code, 0) << "10 SIGTERM not received, 11 received twice; 143 = killed by it";
}

TEST(ShutdownSignals, ReceivesSigintAndSighupToo) {
  const int code = test::runInChild([] {
    ShutdownSignals signals = ShutdownSignals::install();
    raise(SIGINT);
    const int first = signals.waitNs(1000 * kMs);
    raise(SIGHUP);
    const int second = signals.waitNs(1000 * kMs);
    return first == SIGINT && second == SIGHUP ? 0 : 10;
  });

  EXPECT_EQ(code, 0);
}

TEST(ShutdownSignals, TimesOutWithZeroAndNotEarly) {
  const int code = test::runInChild([] {
    ShutdownSignals signals = ShutdownSignals::install();
    if (signals.waitNs(0) != 0 || signals.waitNs(-5) != 0) {
      return 10;
    }
    const std::int64_t start = monotonicNowNs();
    if (signals.waitNs(50 * kMs) != 0) {
      return 11;
    }
    return monotonicNowNs() - start >= 50 * kMs ? 0 : 12;
  });

  EXPECT_EQ(code, 0) << "10 poll, 11 spurious signal, 12 returned early";
}

TEST(ShutdownSignals, LaterThreadsInheritTheMaskAndAnyThreadMayWait) {
  const int code = test::runInChild([] {
    ShutdownSignals signals = ShutdownSignals::install();
    bool blocked_in_thread = false;
    int received = 0;
    std::thread worker([&] {
      sigset_t mask;
      sigemptyset(&mask);
      pthread_sigmask(SIG_BLOCK, nullptr, &mask);
      blocked_in_thread = sigismember(&mask, SIGTERM) == 1 && sigismember(&mask, SIGINT) == 1 &&
                          sigismember(&mask, SIGHUP) == 1;
      received = signals.waitNs(2000 * kMs);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(getpid(), SIGTERM);
    worker.join();
    if (!blocked_in_thread) {
      return 10;
    }
    return received == SIGTERM ? 0 : 11;
  });

  EXPECT_EQ(code, 0) << "10 mask not inherited, 11 not received by the worker";
}

TEST(ShutdownSignals, SigtermFromAnotherProcessEndsTheWait) {
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShutdownSignals signals = ShutdownSignals::install();
    const char byte = 'r';
    (void)!write(ready[1], &byte, 1);
    _exit(signals.waitNs(5000 * kMs) == SIGTERM ? 0 : 10);
  }
  close(ready[1]);
  char byte = 0;
  ASSERT_EQ(read(ready[0], &byte, 1), 1);
  close(ready[0]);

  ASSERT_EQ(kill(child, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);

  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace raymap::platform
