// SPDX-License-Identifier: BSD-3-Clause
// RegionSpanGrouper: a batch's span records grouped by region for span work per region
// (kernels/device/device.h, RM_REGION_OWNED). Host code only; runs without a device.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/staging/span_grouping.hpp"

namespace raymap::gpu {
namespace {

rm_span_record spanIn(std::uint32_t slot, std::uint32_t ray) {
  rm_span_record span{};
  span.ray = ray;
  span.slot = slot;
  return span;
}

TEST(RegionSpanGrouper, EveryRegionGetsOneRunOfItsSpansInRayOrderLongestFirst) {
  // Arrange: rays crossing slots 7, 2 and 5 (slot 2 the most often), as a planned batch holds
  // them: each ray's spans together, in ray order.
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> planned = {
      {7, 0}, {2, 0}, {2, 1}, {5, 1}, {2, 2}, {7, 3}, {2, 3}, {5, 4}, {2, 4}};
  BatchArrays arrays;
  for (const auto& [slot, ray] : planned) {
    arrays.spans.push_back(spanIn(slot, ray));
  }
  RegionSpanGrouper grouper(8);
  grouper.reserve(arrays, BatchLimits{});

  // Act
  grouper.group(arrays);

  // Assert: slot 2 (5 spans) first, then 7 and 5 (2 each) in the order they first appear.
  ASSERT_EQ(arrays.span_runs.size(), 3u);
  const std::vector<std::uint32_t> expected_slots = {2, 7, 5};
  const std::vector<std::uint32_t> expected_counts = {5, 2, 2};
  std::uint32_t first = 0;
  for (std::size_t r = 0; r < 3; ++r) {
    const rm_span_run run = arrays.span_runs[r];
    EXPECT_EQ(run.first, first);
    EXPECT_EQ(run.count, expected_counts[r]);
    std::uint32_t previous_ray = 0;
    for (std::uint32_t k = 0; k < run.count; ++k) {
      const rm_span_record& span = arrays.region_spans[run.first + k];
      EXPECT_EQ(span.slot, expected_slots[r]) << "run " << r << ", span " << k;
      EXPECT_GE(span.ray, previous_ray) << "run " << r << ": not in ray order";
      previous_ray = span.ray;
    }
    first += run.count;
  }
  EXPECT_EQ(first, planned.size());
  EXPECT_EQ(&arrays.deviceSpans(), &arrays.region_spans);
}

TEST(RegionSpanGrouper, ANextBatchStartsFromNothing) {
  BatchArrays arrays;
  RegionSpanGrouper grouper(4);
  grouper.reserve(arrays, BatchLimits{});
  arrays.spans = {spanIn(3, 0), spanIn(1, 0), spanIn(3, 1)};
  grouper.group(arrays);
  ASSERT_EQ(arrays.span_runs.size(), 2u);

  arrays.clear();
  arrays.spans = {spanIn(1, 0)};
  grouper.group(arrays);

  ASSERT_EQ(arrays.span_runs.size(), 1u);
  EXPECT_EQ(arrays.span_runs[0].first, 0u);
  EXPECT_EQ(arrays.span_runs[0].count, 1u);
  EXPECT_EQ(arrays.region_spans.size(), 1u);
  EXPECT_EQ(arrays.region_spans[0].slot, 1u);
}

TEST(RegionSpanGrouper, ABatchWithoutSpansHasNoRuns) {
  BatchArrays arrays;
  RegionSpanGrouper grouper(4);
  grouper.reserve(arrays, BatchLimits{});
  grouper.group(arrays);
  EXPECT_TRUE(arrays.span_runs.empty());
  EXPECT_TRUE(arrays.deviceSpans().empty());
}

}  // namespace
}  // namespace raymap::gpu
