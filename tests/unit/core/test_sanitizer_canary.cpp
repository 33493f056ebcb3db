// SPDX-License-Identifier: BSD-3-Clause
// Canary: in a sanitizer build, proves that AddressSanitizer and UndefinedBehaviorSanitizer really
// stop the program on a bug (so a green sanitizer run means something). Skipped in other builds.
#include <climits>
#include <cstdlib>
#include <memory>

#include <gtest/gtest.h>

namespace {

#if defined(RAYMAP_SANITIZED_BUILD)
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

TEST(SanitizerCanaryDeathTest, AddressSanitizerCatchesAHeapOverflow) {
#if defined(RAYMAP_SANITIZED_BUILD)
  EXPECT_DEATH(g_sink = readPastTheEnd(), "AddressSanitizer: heap-buffer-overflow");
#else
  GTEST_SKIP() << "not a sanitizer build";
#endif
}

TEST(SanitizerCanaryDeathTest, UndefinedBehaviorSanitizerCatchesSignedOverflow) {
#if defined(RAYMAP_SANITIZED_BUILD)
  EXPECT_DEATH(g_sink = overflowSigned(), "runtime error: signed integer overflow");
#else
  GTEST_SKIP() << "not a sanitizer build";
#endif
}

}  // namespace
