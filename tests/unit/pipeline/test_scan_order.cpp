// SPDX-License-Identifier: BSD-3-Clause
// ScanOrder: every kept point exactly once, coarse to fine, so that a scan cut short anywhere is
// still spread over all of it.
#include <algorithm>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/pipeline/scan_order.hpp"

namespace raymap::pipeline {
namespace {

std::vector<std::uint32_t> visitAll(ScanOrder& order) {
  std::vector<std::uint32_t> out;
  std::uint32_t index = 0;
  while (order.next(&index)) {
    out.push_back(index);
  }
  return out;
}

TEST(ScanOrder, VisitsEveryKeptPointExactlyOnce) {
  for (std::uint32_t points : {0u, 1u, 7u, 8u, 9u, 1000u, 131072u}) {
    for (std::uint32_t stride : {1u, 2u, 3u, 8u}) {
      ScanOrder order;
      order.reset(points, stride);
      std::vector<std::uint32_t> seen = visitAll(order);
      std::sort(seen.begin(), seen.end());
      std::vector<std::uint32_t> expected;
      for (std::uint32_t i = 0; i < points; i += stride) {
        expected.push_back(i);
      }
      EXPECT_EQ(seen, expected) << points << " points, stride " << stride;
      EXPECT_TRUE(order.done());
      EXPECT_EQ(order.notVisited(), points - expected.size());
    }
  }
}

TEST(ScanOrder, AnyPrefixIsSpreadOverTheWholeScan) {
  // Cut after a quarter of the visits: the points taken are every fourth one, from the first
  // to the last stretch of the scan, not its first quarter.
  ScanOrder order;
  order.reset(1024, 1);
  std::vector<std::uint32_t> prefix;
  std::uint32_t index = 0;
  while (prefix.size() < 256 && order.next(&index)) {
    prefix.push_back(index);
  }
  std::sort(prefix.begin(), prefix.end());
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    EXPECT_EQ(prefix[i], 4 * i);
  }
  EXPECT_FALSE(order.done());
  EXPECT_EQ(order.notVisited(), 768u);
  // After one eighth, the largest gap between points taken is eight points anywhere in the scan.
  order.reset(1000, 1);
  prefix.clear();
  while (prefix.size() < 125 && order.next(&index)) {
    prefix.push_back(index);
  }
  std::sort(prefix.begin(), prefix.end());
  EXPECT_EQ(prefix.front(), 0u);
  EXPECT_EQ(prefix.back(), 992u);
  for (std::size_t i = 1; i < prefix.size(); ++i) {
    EXPECT_EQ(prefix[i] - prefix[i - 1], 8u);
  }
}

TEST(ScanOrder, ResetStartsOver) {
  ScanOrder order;
  order.reset(10, 1);
  std::uint32_t index = 0;
  ASSERT_TRUE(order.next(&index));
  order.reset(3, 2);
  EXPECT_EQ(visitAll(order), (std::vector<std::uint32_t>{0, 2}));
  EXPECT_EQ(order.visited(), 2u);
}

}  // namespace
}  // namespace raymap::pipeline
