// SPDX-License-Identifier: BSD-3-Clause
// PendingScans: first in first out, the oldest dropped when full, nothing held at capacity 0.
// (Held DDS buffers themselves: DdsLoopback.HeldSamplesStayReadableAfterTheirTakeUntilGivenBack.)
#include <gtest/gtest.h>

#include "src/service/pending_scans.hpp"

namespace raymap::service {
namespace {

TEST(PendingScans, ScansComeOutInArrivalOrder) {
  PendingScans pending(3);
  EXPECT_EQ(pending.capacity(), 3U);
  EXPECT_EQ(pending.size(), 0U);
  EXPECT_FALSE(pending.push(0, 100, dds::HeldSample{}));
  EXPECT_FALSE(pending.push(1, 200, dds::HeldSample{}));
  EXPECT_EQ(pending.size(), 2U);
  PendingScans::Entry first = pending.pop();
  EXPECT_EQ(first.sensor, 0U);
  EXPECT_EQ(first.arrival_ns, 100);
  EXPECT_FALSE(pending.push(2, 300, dds::HeldSample{}));
  EXPECT_EQ(pending.pop().arrival_ns, 200);
  EXPECT_EQ(pending.pop().arrival_ns, 300);
  EXPECT_EQ(pending.size(), 0U);
}

TEST(PendingScans, AFullRingDropsItsOldestScanForTheNewest) {
  PendingScans pending(2);
  EXPECT_FALSE(pending.push(0, 1, dds::HeldSample{}));
  EXPECT_FALSE(pending.push(0, 2, dds::HeldSample{}));
  EXPECT_TRUE(pending.push(0, 3, dds::HeldSample{}));  // 1 goes
  EXPECT_TRUE(pending.push(0, 4, dds::HeldSample{}));  // 2 goes
  EXPECT_EQ(pending.size(), 2U);
  EXPECT_EQ(pending.pop().arrival_ns, 3);
  EXPECT_FALSE(pending.push(0, 5, dds::HeldSample{}));
  EXPECT_EQ(pending.pop().arrival_ns, 4);
  EXPECT_EQ(pending.pop().arrival_ns, 5);
}

TEST(PendingScans, ClearEmptiesTheRingAndItIsUsableAgain) {
  PendingScans pending(2);
  pending.push(0, 1, dds::HeldSample{});
  pending.push(0, 2, dds::HeldSample{});
  pending.clear();
  EXPECT_EQ(pending.size(), 0U);
  EXPECT_FALSE(pending.push(1, 7, dds::HeldSample{}));
  EXPECT_EQ(pending.pop().sensor, 1U);
}

TEST(PendingScans, CapacityZeroHoldsNothing) {
  // queues.scan_slots: 1 -- every scan is decoded on arrival, as before.
  const PendingScans pending(0);
  EXPECT_EQ(pending.capacity(), 0U);
  EXPECT_EQ(pending.size(), 0U);
}

}  // namespace
}  // namespace raymap::service
