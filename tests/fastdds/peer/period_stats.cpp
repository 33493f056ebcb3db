// SPDX-License-Identifier: BSD-3-Clause
// Nearest-rank quantiles of the gaps between arrivals.
#include "tests/fastdds/peer/period_stats.hpp"

#include <algorithm>
#include <cmath>

namespace raymap::fastdds_peer {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

PeriodStats periodStats(std::span<const std::int64_t> arrivals_ns) {
  PeriodStats stats;
  if (arrivals_ns.size() < 2) {
    return stats;
  }
  std::vector<double> periods_ms;
  periods_ms.reserve(arrivals_ns.size() - 1);
  for (std::size_t i = 1; i < arrivals_ns.size(); ++i) {
    periods_ms.push_back(static_cast<double>(arrivals_ns[i] - arrivals_ns[i - 1]) * 1e-6);
  }
  stats.p50_ms = quantile(periods_ms, 0.5);
  stats.p99_ms = quantile(periods_ms, 0.99);
  stats.max_ms = *std::max_element(periods_ms.begin(), periods_ms.end());
  return stats;
}

double longestGapMs(std::span<const std::int64_t> arrivals_ns, std::int64_t from_ns,
                    std::int64_t to_ns) {
  std::int64_t longest = 0;
  std::int64_t previous = from_ns;
  for (const std::int64_t t : arrivals_ns) {
    if (t >= from_ns && t <= to_ns) {
      longest = std::max(longest, t - previous);
      previous = t;
    }
  }
  longest = std::max(longest, to_ns - previous);
  return static_cast<double>(longest) * 1e-6;
}

}  // namespace raymap::fastdds_peer
