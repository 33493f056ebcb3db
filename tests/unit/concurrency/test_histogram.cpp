// SPDX-License-Identifier: BSD-3-Clause
// DurationHistogram: bucket arithmetic, quantiles, maxima and differences of snapshots; a
// snapshot taken while the writer records.
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

#include "src/pipeline/histogram.hpp"

namespace raymap::pipeline {
namespace {

using Histogram = DurationHistogram;

TEST(DurationHistogram, SmallValuesHaveExactBuckets) {
  for (std::uint64_t v = 0; v < Histogram::kSub; ++v) {
    EXPECT_EQ(Histogram::bucketOf(v), static_cast<int>(v));
    EXPECT_EQ(Histogram::bucketUpper(static_cast<int>(v)), v);
  }
}

TEST(DurationHistogram, BucketsTileTheRangeWithSmallRelativeWidth) {
  // Every value lies in its bucket (upper edge >= value > previous bucket's upper edge), buckets
  // are contiguous, and their width is at most 1/64 of their lower edge.
  std::uint64_t previous_upper = 0;
  for (int b = 1; b < Histogram::kBuckets; ++b) {
    const std::uint64_t lower = previous_upper + 1;
    const std::uint64_t upper = Histogram::bucketUpper(b);
    ASSERT_GE(upper, lower) << "bucket " << b;
    EXPECT_EQ(Histogram::bucketOf(lower), b) << "bucket " << b;
    EXPECT_EQ(Histogram::bucketOf(upper), b) << "bucket " << b;
    EXPECT_LE(static_cast<double>(upper - lower + 1), static_cast<double>(lower) / 64.0 + 1.0)
        << "bucket " << b;
    previous_upper = upper;
  }
  EXPECT_EQ(previous_upper, (std::uint64_t{1} << 37) - 1);
}

TEST(DurationHistogram, HugeValuesSaturateInTheLastBucket) {
  EXPECT_EQ(Histogram::bucketOf(std::uint64_t{1} << 37), Histogram::kBuckets - 1);
  EXPECT_EQ(Histogram::bucketOf(~std::uint64_t{0}), Histogram::kBuckets - 1);
}

TEST(DurationHistogram, EmptySnapshotHasZeroQuantiles) {
  const auto histogram = std::make_unique<Histogram>();
  Histogram::Snapshot s;

  histogram->snapshot(&s);

  EXPECT_EQ(s.total, 0u);
  EXPECT_EQ(s.max_us, 0u);
  EXPECT_EQ(s.quantileUs(0.5), 0.0);
  EXPECT_EQ(s.quantileUs(1.0), 0.0);
}

TEST(DurationHistogram, QuantilesOfExactValues) {
  const auto histogram = std::make_unique<Histogram>();
  for (std::uint64_t v = 1; v <= 100; ++v) {  // <= 127: buckets of width 1
    histogram->record(v);
  }
  Histogram::Snapshot s;

  histogram->snapshot(&s);

  EXPECT_EQ(s.total, 100u);
  EXPECT_EQ(s.max_us, 100u);
  EXPECT_EQ(s.quantileUs(0.0), 1.0);
  EXPECT_EQ(s.quantileUs(0.5), 50.0);
  EXPECT_EQ(s.quantileUs(0.99), 99.0);
  EXPECT_EQ(s.quantileUs(1.0), 100.0);
}

TEST(DurationHistogram, QuantileIsWithinTheBucketWidthAndNeverAboveTheMaximum) {
  const auto histogram = std::make_unique<Histogram>();
  histogram->record(10000);
  histogram->record(10001);
  histogram->record(250000);
  Histogram::Snapshot s;

  histogram->snapshot(&s);

  EXPECT_EQ(s.max_us, 250000u);
  EXPECT_GE(s.quantileUs(0.5), 10001.0);
  EXPECT_LE(s.quantileUs(0.5), 10001.0 * (1.0 + 1.0 / 64.0));
  EXPECT_EQ(s.quantileUs(1.0), 250000.0) << "clipped to the largest value recorded";
}

TEST(DurationHistogram, SinceCountsOnlyTheNewValues) {
  const auto histogram = std::make_unique<Histogram>();
  for (int i = 0; i < 10; ++i) {
    histogram->record(5);
  }
  Histogram::Snapshot before;
  histogram->snapshot(&before);
  histogram->record(40);
  histogram->record(41);
  Histogram::Snapshot after;
  histogram->snapshot(&after);

  const Histogram::Snapshot d = after.since(before);

  EXPECT_EQ(d.total, 2u);
  EXPECT_EQ(d.counts[5], 0u);
  EXPECT_EQ(d.counts[40], 1u);
  EXPECT_EQ(d.counts[41], 1u);
  EXPECT_EQ(d.quantileUs(0.5), 40.0);
  EXPECT_EQ(d.quantileUs(1.0), 41.0);
  EXPECT_EQ(d.max_us, 41u);
}

TEST(DurationHistogramStress, ASnapshotsMaximumIsNeverBelowAValueItCounted) {
  // The writer records 1, 2, 3 ... (each a new maximum) while the reader snapshots: the highest
  // bucket a snapshot counts must not start above the maximum it read with it.
  constexpr std::uint64_t kValues = 300000;
  Histogram histogram;
  std::atomic<bool> recorded_all{false};
  std::thread writer([&] {
    for (std::uint64_t v = 1; v <= kValues; ++v) {
      histogram.record(v);
    }
    recorded_all.store(true, std::memory_order_release);
  });
  auto snapshot = std::make_unique<Histogram::Snapshot>();
  std::uint64_t snapshots = 0;
  std::uint64_t below = 0;
  bool last_round = false;
  while (!last_round) {
    last_round = recorded_all.load(std::memory_order_acquire);
    histogram.snapshot(snapshot.get());
    ++snapshots;
    int highest = -1;
    for (int b = Histogram::kBuckets - 1; b >= 0 && highest < 0; --b) {
      highest = snapshot->counts[static_cast<std::size_t>(b)] > 0 ? b : -1;
    }
    // The bucket's lowest value: one above the previous bucket's highest.
    const std::uint64_t lowest = highest <= 0 ? 0U : Histogram::bucketUpper(highest - 1) + 1U;
    below += highest >= 0 && snapshot->max_us < lowest ? 1U : 0U;
  }
  writer.join();
  EXPECT_EQ(below, 0U) << "of " << snapshots << " snapshots";
  EXPECT_EQ(snapshot->total, kValues);
  EXPECT_EQ(snapshot->max_us, kValues);
}

}  // namespace
}  // namespace raymap::pipeline
