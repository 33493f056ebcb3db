// SPDX-License-Identifier: BSD-3-Clause
// The latency bound's arithmetic: when a scan goes in whole, subsampled or not at all.
#include <cstdint>

#include <gtest/gtest.h>

#include "src/pipeline/load_shedding.hpp"
#include "tests/support/nanoseconds.hpp"

namespace raymap::pipeline {
namespace {

using test::kMs;
constexpr std::int64_t kSheddingNow = 10000 * kMs;
constexpr std::int64_t kBound = 250 * kMs;  // queues.max_latency_s
constexpr std::uint32_t kMaxStride = 8;
constexpr bool kSaturated = true;  // the integrator is overloaded: the bound applies

/// Maps every 200 ms; the next one at kSheddingNow + `next_in_ms`, generated 15 ms before each.
PublishSchedule schedule(std::int64_t next_in_ms) {
  PublishSchedule s;
  s.next_publish_ns = kSheddingNow + next_in_ms * kMs;
  s.period_ns = 200 * kMs;
  s.lead_ns = 15 * kMs;
  return s;
}

TEST(LoadShedding, AScanThatMakesTheNextMapGoesInWhole) {
  // Arrived now; 50 ms of rays; the next map is generated in 85 ms and published in 100.
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow, 0.0, 50000.0, 1000.0, schedule(100),
                                  kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 1u);
}

TEST(LoadShedding, AScanThatMissesTheNextMapButMakesTheOneAfterWithinTheBoundGoesInWhole) {
  // Arrived now; 50 ms of rays but the next generation is in 5 ms: the map after, 220 ms from
  // the arrival, is still within 250 ms.
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow, 0.0, 50000.0, 1000.0, schedule(20),
                                  kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 1u);
}

TEST(LoadShedding, AScanDelayedPastTheBoundIsSubsampledToMakeIt) {
  // Arrived 50 ms ago with 100 ms of rays: starting now it would wait for the map 300 ms from
  // now, 350 after the arrival, beyond 250; every second point makes the map in 100 ms
  // (generated in 85: 100 / 85 -> 2).
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow - 50 * kMs, 0.0, 100000.0, 1000.0,
                                  schedule(100), kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 2u);
}

TEST(LoadShedding, BelowSaturationEveryScanIsKeptWhole) {
  // The same scan while the integrator is not saturated: it merely waited behind its
  // predecessor, and the latency is not accumulating, so nothing is thinned.
  ShedDecision d = planScan(kSheddingNow, kSheddingNow - 50 * kMs, 0.0, 100000.0, 1000.0,
                            schedule(100), kBound, kMaxStride, false);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 1u);
  // Nor one that no map within the bound could hold any more.
  d = planScan(kSheddingNow, kSheddingNow - 300 * kMs, 0.0, 1000.0, 1000.0, schedule(100), kBound,
               kMaxStride, false);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 1u);
}

TEST(LoadShedding, AScanTooLargeForTheBoundIsThinnedByTheFactorItExceedsIt) {
  // Arrived 100 ms ago with 200 ms of rays: every third point makes the map in 100 ms (200 / 85
  // -> 3), the last within 250 ms of the arrival.
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow - 100 * kMs, 0.0, 200000.0, 1000.0,
                                  schedule(100), kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 3u);
}

TEST(LoadShedding, RaysAlreadyQueuedAheadCountAgainstTheTimeLeft) {
  // 85 ms before the generation; 60 ms of rays queued ahead leave 25 ms for a 50 ms scan.
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow - 100 * kMs, 60000.0, 50000.0, 1000.0,
                                  schedule(100), kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 2u);
}

TEST(LoadShedding, AScanNoMapWithinTheBoundCanHoldIsDropped) {
  // Arrived 300 ms ago: even the next map is beyond the bound.
  ShedDecision d = planScan(kSheddingNow, kSheddingNow - 300 * kMs, 0.0, 1000.0, 1000.0,
                            schedule(100), kBound, kMaxStride, kSaturated);
  EXPECT_TRUE(d.drop);
  // Arrived 140 ms ago: the next map (240 ms after it) is the last within the bound, and the
  // 90 ms of rays queued ahead outlast the 85 ms before its generation.
  d = planScan(kSheddingNow, kSheddingNow - 140 * kMs, 90000.0, 1000.0, 1000.0, schedule(100),
               kBound, kMaxStride, kSaturated);
  EXPECT_TRUE(d.drop);
}

TEST(LoadShedding, AScanThatWouldNeedMoreThanTheLargestStrideIsDropped) {
  // Arrived now with 50 ms of rays behind 80 ms queued: 5 ms are left before the next map's
  // generation and the one after is beyond 250 ms; a stride of 10 would be needed.
  ShedDecision d = planScan(kSheddingNow, kSheddingNow, 80000.0, 50000.0, 1000.0, schedule(100),
                            kBound, kMaxStride, kSaturated);
  EXPECT_TRUE(d.drop);
  // With subsampling off (largest stride 1) a scan that does not fit whole is dropped.
  d = planScan(kSheddingNow, kSheddingNow - 100 * kMs, 60000.0, 50000.0, 1000.0, schedule(100),
               kBound, 1, kSaturated);
  EXPECT_TRUE(d.drop);
}

TEST(LoadShedding, WithoutABoundOrAScheduleNothingIsShed) {
  EXPECT_FALSE(planScan(kSheddingNow, kSheddingNow - 900 * kMs, 0.0, 1e9, 1000.0, schedule(100), 0,
                        kMaxStride, kSaturated)
                   .drop);
  EXPECT_FALSE(planScan(kSheddingNow, kSheddingNow - 900 * kMs, 0.0, 1e9, 1000.0, PublishSchedule{},
                        kBound, kMaxStride, kSaturated)
                   .drop);
}

TEST(LoadShedding, APublishInstantAlreadyPastIsAdvancedByWholePeriods) {
  // The publisher's "next" is 30 ms in the past (it is about to store the next one): the next
  // generation is then 155 ms away; the scan arrived now, so it goes in whole.
  const ShedDecision d = planScan(kSheddingNow, kSheddingNow, 0.0, 50000.0, 1000.0, schedule(-30),
                                  kBound, kMaxStride, kSaturated);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.stride, 1u);
}

TEST(LoadShedding, TheDeadlineIsTheGenerationOfTheLastMapWithinTheBound) {
  // Next map at +100 ms, then +300, +500. Arrived now: +300 is 50 ms past the bound, so the
  // last map within it is +100, generated 15 ms before.
  EXPECT_EQ(latestGenerationWithin(kSheddingNow, schedule(100), kBound), kSheddingNow + 85 * kMs);
  // Arrived 60 ms from now: +300 is within 250 ms of it.
  EXPECT_EQ(latestGenerationWithin(kSheddingNow + 60 * kMs, schedule(100), kBound),
            kSheddingNow + 285 * kMs);
  // Arrived long ago: the instant lies before the next one, whole periods back.
  EXPECT_EQ(latestGenerationWithin(kSheddingNow - 500 * kMs, schedule(100), kBound),
            kSheddingNow - 315 * kMs);
  // Exactly on the bound counts as within it.
  EXPECT_EQ(latestGenerationWithin(kSheddingNow - 150 * kMs, schedule(100), kBound),
            kSheddingNow + 85 * kMs);
  // No bound, no schedule: no deadline.
  EXPECT_EQ(latestGenerationWithin(kSheddingNow, schedule(100), 0), 0);
  EXPECT_EQ(latestGenerationWithin(kSheddingNow, PublishSchedule{}, kBound), 0);
}

}  // namespace
}  // namespace raymap::pipeline
