// SPDX-License-Identifier: BSD-3-Clause
// The latency bound: how much of a scan the integrator can take so that the first height map
// containing it is published within queues.max_latency_s of the scan's arrival.
#pragma once

#include <cstdint>

namespace raymap::pipeline {

/// @brief The publisher's timetable as the integrator sees it (monotonic nanoseconds).
struct PublishSchedule {
  std::int64_t next_publish_ns = 0;  ///< the next publish instant; 0 = none planned (no shedding)
  std::int64_t period_ns = 0;        ///< between publish instants
  std::int64_t lead_ns = 0;          ///< generation starts this long before each instant
};

/// @brief What to do with one scan.
struct ShedDecision {
  bool drop = false;  ///< shed the whole scan: no publish instant within the bound is reachable
  std::uint32_t stride = 1;  ///< take every stride-th point (1 = all)
};

/// @brief Decides how much of a scan fits the latency bound.
///
/// Only while `overloaded` (the backend has been busy nearly all the time lately, so the input
/// exceeds what it integrates; or the bound is to apply always): otherwise every scan is kept,
/// since a scan that merely waits behind its predecessor would be thinned for latency the
/// system is not accumulating. A map generated at P - lead (P a publish instant) contains the
/// scans integrated by then, so a scan taken now, behind `queued_rays` rays already waiting, is
/// complete at now + (queued + scan) * ns_per_ray and first published at the first instant whose
/// generation follows that. Within `max_latency_ns` of its arrival the scan goes in whole.
/// Otherwise it is subsampled uniformly so that it completes before the generation of the latest
/// instant still within the bound (stride = the factor it must shrink by), or dropped whole when
/// that takes a stride above `max_stride` or no such instant is still ahead. `max_latency_ns`
/// <= 0, or no schedule yet, never sheds.
/// @rt allocates: no; pure.
/// @brief When generation starts for the latest publish instant within `max_latency_ns` of
/// `arrival_ns`: the scan's deadline (monotonic ns). A scan whose last ray is in the map by then
/// is published within the bound. 0 when there is no bound (`max_latency_ns` <= 0) or no
/// schedule yet. The instant may already be past. @rt allocates: no; pure.
std::int64_t latestGenerationWithin(std::int64_t arrival_ns, const PublishSchedule& schedule,
                                    std::int64_t max_latency_ns) noexcept;

ShedDecision planScan(std::int64_t now_ns, std::int64_t arrival_ns, double queued_rays,
                      double scan_rays, double ns_per_ray, const PublishSchedule& schedule,
                      std::int64_t max_latency_ns, std::uint32_t max_stride,
                      bool overloaded) noexcept;

}  // namespace raymap::pipeline
