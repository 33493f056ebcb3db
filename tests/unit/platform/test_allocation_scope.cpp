// SPDX-License-Identifier: BSD-3-Clause
// RealtimeScope / ForeignScope and the registered real-time allocation counter (the tests'
// malloc hook registers itself; raymapd_counted reports it for tools/soak.sh).
#include <cstdlib>
#include <memory>

#include <gtest/gtest.h>

#include "platform/allocation_scope.hpp"
#include "tests/support/alloc_counter.hpp"

namespace raymap::platform {
namespace {

// Keeps the allocation from being optimised away.
void allocateOnce() {
  auto block = std::make_unique<volatile char[]>(64);
  block[0] = 1;
}

TEST(AllocationScope, CountsOnlyInsideARealtimeScopeAndNotInAForeignOne) {
  if (!test::allocationCountingAvailable()) {
    GTEST_SKIP() << "a sanitizer owns malloc in this build";
  }
  EXPECT_FALSE(inRealtimeScope());
  const std::uint64_t start = test::realtimeAllocations();
  allocateOnce();
  EXPECT_EQ(test::realtimeAllocations(), start);
  {
    RealtimeScope steady;
    EXPECT_TRUE(inRealtimeScope());
    allocateOnce();
    {
      ForeignScope library;
      EXPECT_FALSE(inRealtimeScope());
      allocateOnce();
      RealtimeScope callback;  // called back by the library: ours again
      allocateOnce();
    }
    EXPECT_TRUE(inRealtimeScope());
  }
  EXPECT_FALSE(inRealtimeScope());
  EXPECT_EQ(test::realtimeAllocations(), start + 2);
}

TEST(AllocationScope, TheCountingMallocRegistersItsCounterForTheDiagnostics) {
  if (!test::allocationCountingAvailable()) {
    GTEST_SKIP() << "a sanitizer owns malloc in this build";
  }
  const RealtimeAllocationCounter counter = realtimeAllocationCounter();
  ASSERT_NE(counter, nullptr);
  const std::uint64_t before = counter();
  {
    RealtimeScope steady;
    allocateOnce();
  }
  EXPECT_EQ(counter(), before + 1);
  EXPECT_EQ(counter(), test::realtimeAllocations());
}

}  // namespace
}  // namespace raymap::platform
