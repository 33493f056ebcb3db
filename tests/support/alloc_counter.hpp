// SPDX-License-Identifier: BSD-3-Clause
// Counts heap allocations (malloc family interposed in the test executables that link this):
// per thread inside an AllocationScope, and across all threads inside platform::RealtimeScope.
#pragma once

#include <cstdint>

namespace raymap::test {

/// @brief False in sanitizer builds, where the sanitizer owns malloc and nothing is counted.
bool allocationCountingAvailable() noexcept;

/// @brief Allocations made so far, on any thread, inside a platform::RealtimeScope (and not in a
/// ForeignScope): the steady-state loops of the service, which must make none.
std::uint64_t realtimeAllocations() noexcept;

/// @brief Counts malloc/calloc/realloc/memalign calls of this thread while alive.
class AllocationScope {
 public:
  AllocationScope() noexcept;
  ~AllocationScope();
  AllocationScope(const AllocationScope&) = delete;
  AllocationScope& operator=(const AllocationScope&) = delete;
  std::uint64_t count() const noexcept;

 private:
  std::uint64_t start_;
};

}  // namespace raymap::test
