// SPDX-License-Identifier: BSD-3-Clause
// Durations in nanoseconds, the unit of raymap's monotonic and header-stamp clocks, for the tests'
// arithmetic on times.
#pragma once

#include <cstdint>

namespace raymap::test {

inline constexpr std::int64_t kMs = 1'000'000;  ///< one millisecond, in nanoseconds

}  // namespace raymap::test
