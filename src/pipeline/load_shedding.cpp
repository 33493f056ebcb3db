// SPDX-License-Identifier: BSD-3-Clause
// planScan: the latency bound's arithmetic (see the header).
#include "src/pipeline/load_shedding.hpp"

#include <algorithm>
#include <cmath>

namespace raymap::pipeline {

std::int64_t latestGenerationWithin(std::int64_t arrival_ns, const PublishSchedule& schedule,
                                    std::int64_t max_latency_ns) noexcept {
  if (max_latency_ns <= 0 || schedule.next_publish_ns == 0 || schedule.period_ns <= 0) {
    return 0;
  }
  const std::int64_t bound = arrival_ns + max_latency_ns;
  const std::int64_t ahead = bound - schedule.next_publish_ns;
  // floor division: the instant may lie before next_publish_ns
  std::int64_t periods = ahead / schedule.period_ns;
  if (ahead % schedule.period_ns != 0 && ahead < 0) {
    --periods;
  }
  return schedule.next_publish_ns + periods * schedule.period_ns - schedule.lead_ns;
}

ShedDecision planScan(std::int64_t now_ns, std::int64_t arrival_ns, double queued_rays,
                      double scan_rays, double ns_per_ray, const PublishSchedule& schedule,
                      std::int64_t max_latency_ns, std::uint32_t max_stride,
                      bool overloaded) noexcept {
  ShedDecision keep;
  if (!overloaded || max_latency_ns <= 0 || schedule.next_publish_ns == 0 ||
      schedule.period_ns <= 0) {
    return keep;
  }
  const auto period = static_cast<double>(schedule.period_ns);
  const auto lead = static_cast<double>(schedule.lead_ns);
  const auto next = static_cast<double>(schedule.next_publish_ns);
  // The first publish instant (of the whole timetable, past ones included) whose generation
  // starts at or after `t`.
  const auto firstAfter = [&](double t) {
    return next + std::ceil((t - (next - lead)) / period) * period;
  };
  const double start = static_cast<double>(now_ns) + queued_rays * ns_per_ray;
  const double work = scan_rays * ns_per_ray;
  const double first = firstAfter(start + work);
  const double bound = static_cast<double>(arrival_ns + max_latency_ns);  // latest instant
  if (first <= bound) {
    return keep;
  }
  ShedDecision shed;
  // The latest instant within the bound that is still to be generated, and the time left.
  const double upcoming = firstAfter(static_cast<double>(now_ns));
  if (upcoming > bound) {
    shed.drop = true;  // even the next map comes too late
    return shed;
  }
  const double left =
      static_cast<double>(latestGenerationWithin(arrival_ns, schedule, max_latency_ns)) - start;
  if (left <= 0.0) {
    shed.drop = true;
    return shed;
  }
  const double stride = std::ceil(work / left);
  if (stride > static_cast<double>(max_stride)) {
    shed.drop = true;
    return shed;
  }
  shed.stride = static_cast<std::uint32_t>(std::max(stride, 1.0));
  return shed;
}

}  // namespace raymap::pipeline
