// SPDX-License-Identifier: BSD-3-Clause
// StampGaps: missing messages of a periodic stream from the gaps in their stamps.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/pipeline/stamp_gaps.hpp"

namespace raymap::pipeline {
namespace {

constexpr std::int64_t kPeriod = 100'000'000;  // 10 Hz
constexpr std::int64_t kStart = 1'700'000'000'000'000'000;

/// Feeds scans k of `ks` (stamped kStart + k periods, with `jitter_ns` alternating) and returns
/// the total counted missing.
std::uint64_t missingOf(const std::vector<int>& ks, std::int64_t jitter_ns = 0) {
  StampGaps gaps;
  std::uint64_t missing = 0;
  for (std::size_t i = 0; i < ks.size(); ++i) {
    const std::int64_t jitter = (i % 2 == 0) ? jitter_ns : -jitter_ns;
    missing += gaps.observe(kStart + ks[i] * kPeriod + jitter);
  }
  return missing;
}

std::vector<int> range(int from, int to) {
  std::vector<int> ks;
  for (int k = from; k < to; ++k) {
    ks.push_back(k);
  }
  return ks;
}

TEST(StampGaps, AStreamWithoutLossesMissesNothingAndLearnsItsPeriod) {
  StampGaps gaps;
  for (int k = 0; k < 50; ++k) {
    EXPECT_EQ(gaps.observe(kStart + k * kPeriod + (k % 3) * 2'000'000), 0u) << k;
  }
  EXPECT_NEAR(static_cast<double>(gaps.periodNs()), static_cast<double>(kPeriod), 3e6);
}

TEST(StampGaps, CountsEachMissingMessageOfAGap) {
  std::vector<int> ks = range(0, 10);
  for (int k : {12, 13, 17, 18, 19, 20}) {  // 10 and 11 missing, then 14, 15 and 16
    ks.push_back(k);
  }
  EXPECT_EQ(missingOf(ks), 5u);
  EXPECT_EQ(missingOf(ks, 8'000'000), 5u) << "stamps jittering by 8 % of a period";
}

TEST(StampGaps, ALossWhileLearningDoesNotSkewThePeriod) {
  // The second spacing is two periods: the median spacing is the period.
  std::vector<int> ks = {0, 1, 3, 4, 5, 6, 7, 9, 10};
  EXPECT_EQ(missingOf(ks), 1u) << "8 is missing (2 was missed while learning)";
}

TEST(StampGaps, APeriodLearntTooLongFromALossyStartIsCorrected) {
  // Every spacing while learning is two or three periods (half the clouds lost): the period
  // learnt is too long until a spacing of one period shows it.
  std::vector<int> ks = {0, 2, 5, 7, 10, 11, 12, 13, 15, 16};
  EXPECT_EQ(missingOf(ks), 1u) << "14 is missing; the losses while learning are not counted";
}

TEST(StampGaps, TimeGoingBackAndPausesAreNotLosses) {
  std::vector<int> ks = range(0, 10);
  for (int k : range(0, 10)) {  // a bag played again from its start
    ks.push_back(k);
  }
  for (int k : range(100, 110)) {  // the sensor stopped for 9 s
    ks.push_back(k);
  }
  EXPECT_EQ(missingOf(ks), 0u);
}

TEST(StampGaps, ARateThatHalvedForGoodIsLearntAgainButBurstsAreCounted) {
  std::vector<int> ks = range(0, 10);
  for (int k = 10; k < 60; k += 2) {  // 5 Hz from here on
    ks.push_back(k);
  }
  // Counted until kRelearnAfter gaps of the same length came in a row, then the new period.
  EXPECT_EQ(missingOf(ks), static_cast<std::uint64_t>(StampGaps::kRelearnAfter - 1));

  std::vector<int> bursts = range(0, 10);
  int k = 9;
  for (int i = 0; i < 30; ++i) {  // losses of 1, 2, 1, 2, ... clouds: never one length in a row
    k += 2 + i % 2;
    bursts.push_back(k);
  }
  EXPECT_EQ(missingOf(bursts), 45u);
}

}  // namespace
}  // namespace raymap::pipeline
