// SPDX-License-Identifier: BSD-3-Clause
// Canary: in a sanitizer build, proves that AddressSanitizer and UndefinedBehaviorSanitizer (the
// asan preset) or ThreadSanitizer (the tsan preset) really stop the program on a bug, so that a
// green sanitizer run means something. Skipped in other builds.
#include <atomic>
#include <climits>
#include <cstdlib>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

namespace {

#if defined(RAYMAP_ASAN_BUILD)
// Inputs the optimiser cannot see through, so the bugs below really happen at run time.
volatile int g_index = 4;
volatile int g_large = INT_MAX;
volatile int g_sink = 0;  // results go here, so the calls cannot be dropped as unused

__attribute__((noinline)) int readPastTheEnd() {
  auto values = std::make_unique<int[]>(4);
  return values[static_cast<std::size_t>(g_index)];
}

__attribute__((noinline)) int overflowSigned() {
  const int value = g_large;
  return value + 1;
}
#endif

#if defined(RAYMAP_TSAN_BUILD)
// Every report stops the program, whatever TSAN_OPTIONS the caller set (the tsan test preset
// sets the same): a race must fail the test that caused it, not only print a warning.
extern "C" const char* __tsan_default_options() { return "halt_on_error=1"; }

int g_racy = 0;  // written by two threads without synchronisation: the race the canary wants

// Both threads write while the other is running: a relaxed flag (no happens-before for
// ThreadSanitizer) holds the second until the first has started, and each writes many times, so
// the accesses overlap whatever the scheduler does on a busy machine (one write each once missed
// the race in CI).
__attribute__((noinline)) void raceOnAnInt() {
  std::atomic<bool> started{false};
  std::thread other([&] {
    started.store(true, std::memory_order_relaxed);
    for (int i = 0; i < 100000; ++i) {
      g_racy = g_racy + 1;
    }
  });
  while (!started.load(std::memory_order_relaxed)) {
  }
  for (int i = 0; i < 100000; ++i) {
    g_racy = g_racy + 1;
  }
  other.join();
}
#endif

TEST(SanitizerCanaryDeathTest, ThreadSanitizerCatchesADataRace) {
#if defined(RAYMAP_TSAN_BUILD)
  // The child re-executes the test instead of a bare fork(): ThreadSanitizer's runtime has
  // threads of its own, and a fork of a threaded process is where its detection is unreliable.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(raceOnAnInt(), "ThreadSanitizer: data race");
#else
  GTEST_SKIP() << "not a ThreadSanitizer build";
#endif
}

TEST(SanitizerCanaryDeathTest, AddressSanitizerCatchesAHeapOverflow) {
#if defined(RAYMAP_ASAN_BUILD)
  EXPECT_DEATH(g_sink = readPastTheEnd(), "AddressSanitizer: heap-buffer-overflow");
#else
  GTEST_SKIP() << "not an AddressSanitizer build";
#endif
}

TEST(SanitizerCanaryDeathTest, UndefinedBehaviorSanitizerCatchesSignedOverflow) {
#if defined(RAYMAP_ASAN_BUILD)
  EXPECT_DEATH(g_sink = overflowSigned(), "runtime error: signed integer overflow");
#else
  GTEST_SKIP() << "not an AddressSanitizer build";
#endif
}

}  // namespace
