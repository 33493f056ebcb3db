// SPDX-License-Identifier: BSD-3-Clause
// Counts heap allocations made by the calling thread (malloc family interposed in this test
// executable), to check the "allocates: no" contracts of src/dds.
#pragma once

#include <cstdint>

namespace raymap::dds::test {

/// @brief False in sanitizer builds, where the sanitizer owns malloc and nothing is counted.
bool allocationCountingAvailable() noexcept;

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

}  // namespace raymap::dds::test
