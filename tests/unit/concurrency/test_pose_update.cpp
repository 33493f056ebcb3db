// SPDX-License-Identifier: BSD-3-Clause
// The integrator's pose hand-overs: LatestPosition's sequence lock (integrator -> publisher) and
// the ingest thread's PoseQueue (Boost.Lockfree's single-producer single-consumer ring), each
// under a writer and a reader on two threads.
#include <atomic>
#include <cstdint>
#include <thread>

#include <gtest/gtest.h>

#include "src/pipeline/pose_update.hpp"

namespace raymap::pipeline {
namespace {

TEST(PipelineLatestPosition, EmptyUntilTheFirstStore) {
  LatestPosition latest;
  std::int64_t stamp = -1;
  Vec3d position{9.0, 9.0, 9.0};

  EXPECT_FALSE(latest.load(&stamp, &position));

  latest.store(77, {1.0, 2.0, 3.0});
  ASSERT_TRUE(latest.load(&stamp, &position));
  EXPECT_EQ(stamp, 77);
  EXPECT_EQ(position, (Vec3d{1.0, 2.0, 3.0}));
  latest.store(78, {4.0, 5.0, 6.0});
  ASSERT_TRUE(latest.load(&stamp, &position));
  EXPECT_EQ(stamp, 78);
  EXPECT_EQ(position, (Vec3d{4.0, 5.0, 6.0}));
}

// A reader never sees fields of two different stores (bounded by a count, not by time).
TEST(PipelineLatestPosition, ReaderNeverSeesATornPosition) {
  LatestPosition latest;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::int64_t i = 1; i <= 200000; ++i) {
      const double v = static_cast<double>(i);
      latest.store(i, {v, 2.0 * v, -v});
    }
    done.store(true);
  });
  std::uint64_t torn = 0;
  std::uint64_t reads = 0;
  std::int64_t previous = 0;
  std::uint64_t backwards = 0;
  while (!done.load()) {
    std::int64_t stamp = 0;
    Vec3d p;
    if (!latest.load(&stamp, &p)) {
      continue;
    }
    ++reads;
    const double v = static_cast<double>(stamp);
    torn += (p.x != v || p.y != 2.0 * v || p.z != -v) ? 1u : 0u;
    backwards += stamp < previous ? 1u : 0u;
    previous = stamp;
  }
  writer.join();

  EXPECT_EQ(torn, 0u) << "of " << reads << " reads";
  EXPECT_EQ(backwards, 0u);
  std::int64_t stamp = 0;
  Vec3d p;
  ASSERT_TRUE(latest.load(&stamp, &p));
  EXPECT_EQ(stamp, 200000);
}

TEST(PoseQueueStress, EveryUpdateArrivesIntactInOrderOrIsCountedDropped) {
  // The ingest thread pushes (dropping the update when the ring is full, as raymapd counts
  // poses_dropped); the integrator pops. boost::lockfree::spsc_queue publishes an element with
  // a release store of its write index and reads it after an acquire load of it: a popped update
  // must be whole (no field from an older one in the slot) and later than the one before.
  constexpr std::int64_t kUpdates = 200000;
  PoseQueue queue(16);
  std::int64_t dropped = 0;
  std::atomic<bool> pushed_all{false};
  std::thread ingest([&] {
    for (std::int64_t i = 1; i <= kUpdates; ++i) {
      PoseUpdate u;
      u.stamp_ns = i;
      const double v = static_cast<double>(i);
      u.pose.position = {v, 2.0 * v, -v};
      u.pose.orientation = {1.0, 0.0, 0.0, 0.0};
      dropped += queue.push(u) ? 0 : 1;
    }
    pushed_all.store(true, std::memory_order_release);
  });
  std::int64_t popped = 0;
  std::int64_t torn = 0;
  std::int64_t backwards = 0;
  std::int64_t previous = 0;
  // Bounded by the updates' count, not by time: the reader stops once every push was made and
  // the ring is empty.
  for (;;) {
    const bool last_round = pushed_all.load(std::memory_order_acquire);
    PoseUpdate u;
    if (!queue.pop(u)) {
      if (last_round) {
        break;
      }
      std::this_thread::yield();
      continue;
    }
    ++popped;
    const double v = static_cast<double>(u.stamp_ns);
    torn +=
        (u.pose.position.x() != v || u.pose.position.y() != 2.0 * v || u.pose.position.z() != -v)
            ? 1
            : 0;
    backwards += u.stamp_ns > previous ? 0 : 1;
    previous = u.stamp_ns;
  }
  ingest.join();
  EXPECT_EQ(torn, 0) << "of " << popped << " updates";
  EXPECT_EQ(backwards, 0);
  EXPECT_EQ(popped + dropped, kUpdates);
}

}  // namespace
}  // namespace raymap::pipeline
