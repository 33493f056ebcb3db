// SPDX-License-Identifier: BSD-3-Clause
// Canary: in a sanitizer build, proves that AddressSanitizer and UndefinedBehaviorSanitizer (the
// asan preset) or ThreadSanitizer (the tsan preset) really stop the program on a bug, so that a
// green sanitizer run means something. Skipped in other builds.
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

__attribute__((noinline)) void raceOnAnInt() {
  std::thread other([] { g_racy = g_racy + 1; });
  g_racy = g_racy + 1;
  other.join();
}
#endif

TEST(SanitizerCanaryDeathTest, ThreadSanitizerCatchesADataRace) {
#if defined(RAYMAP_TSAN_BUILD)
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
