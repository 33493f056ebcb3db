// SPDX-License-Identifier: BSD-3-Clause
// The period of a stream of messages from their arrival times: median, 99th percentile, maximum.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace raymap::fastdds_peer {

/// @brief Periods between consecutive arrivals, milliseconds (all 0 with fewer than two).
struct PeriodStats {
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double max_ms = 0.0;
};

/// @brief The q-quantile (0..1) of `values` by nearest rank; 0 when empty.
double quantile(std::vector<double> values, double q);

/// @brief PeriodStats of `arrivals_ns` (monotonic nanoseconds, in arrival order).
PeriodStats periodStats(std::span<const std::int64_t> arrivals_ns);

/// @brief The longest time without an arrival within [from_ns, to_ns], milliseconds: the gaps
/// between arrivals, and from `from_ns` to the first and from the last to `to_ns` (what a
/// subscriber waited; the whole window when nothing arrived).
double longestGapMs(std::span<const std::int64_t> arrivals_ns, std::int64_t from_ns,
                    std::int64_t to_ns);

}  // namespace raymap::fastdds_peer
