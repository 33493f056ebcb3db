// SPDX-License-Identifier: BSD-3-Clause
// PoseHistory: lookups inside, before and after the history, interpolation, the ring's overflow
// and lookups in any order (LatestPosition: tests/unit/concurrency/test_pose_update.cpp).
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "src/pipeline/pose_history.hpp"
#include "tests/support/nanoseconds.hpp"

namespace raymap::pipeline {
namespace {

constexpr double kTolerance = 1e-12;
using test::kMs;

/// A pose at (x, 2x, -x) with a yaw of `yaw` radians.
io::Pose pose(double x, double yaw = 0.0) {
  io::Pose p;
  p.position = {x, 2.0 * x, -x};
  p.orientation = {std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw)};
  return p;
}

void expectPoseNear(const io::Pose& actual, const io::Pose& expected, double tolerance) {
  EXPECT_NEAR(actual.position.x(), expected.position.x(), tolerance);
  EXPECT_NEAR(actual.position.y(), expected.position.y(), tolerance);
  EXPECT_NEAR(actual.position.z(), expected.position.z(), tolerance);
  // q and -q are one rotation.
  EXPECT_NEAR(std::abs(actual.orientation.dot(expected.orientation)), 1.0, tolerance);
}

TEST(PoseHistory, EmptyHistoryHasNoPose) {
  const PoseHistory history(4);
  io::Pose out;

  EXPECT_EQ(history.lookup(0, 0, &out), PoseLookup::kEmpty);
  EXPECT_EQ(history.lookup(123, kMs, &out), PoseLookup::kEmpty);
  EXPECT_EQ(history.size(), 0u);
  EXPECT_EQ(history.newestStamp(), 0);
  EXPECT_EQ(history.oldestStamp(), 0);
}

TEST(PoseHistory, OnePoseCoversItsStampAndTheHoldAfterIt) {
  PoseHistory history(4);
  ASSERT_TRUE(history.push(1000 * kMs, pose(1.0)));
  io::Pose out;

  EXPECT_EQ(history.lookup(1000 * kMs, 0, &out), PoseLookup::kOk);
  expectPoseNear(out, pose(1.0), 0.0);
  EXPECT_EQ(history.lookup(1020 * kMs, 20 * kMs, &out), PoseLookup::kOk);
  expectPoseNear(out, pose(1.0), 0.0);
  EXPECT_EQ(history.lookup(1020 * kMs + 1, 20 * kMs, &out), PoseLookup::kNotYet);
  EXPECT_EQ(history.lookup(1000 * kMs - 1, 20 * kMs, &out), PoseLookup::kTooOld);
}

TEST(PoseHistory, InterpolatesBetweenBracketingPoses) {
  PoseHistory history(8);
  ASSERT_TRUE(history.push(0, pose(0.0, 0.0)));
  ASSERT_TRUE(history.push(100 * kMs, pose(1.0, std::numbers::pi / 2)));
  io::Pose out;

  ASSERT_EQ(history.lookup(50 * kMs, 0, &out), PoseLookup::kOk);

  // Half way: position linear; nlerp at one half is exactly the half-angle rotation.
  expectPoseNear(out, pose(0.5, std::numbers::pi / 4), 1e-12);
  ASSERT_EQ(history.lookup(25 * kMs, 0, &out), PoseLookup::kOk);
  EXPECT_NEAR(out.position.x(), 0.25, kTolerance);
  EXPECT_NEAR(out.position.y(), 0.5, kTolerance);
}

TEST(PoseHistory, LookupAtASampleStampGivesThatSample) {
  PoseHistory history(8);
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(history.push(i * 10 * kMs, pose(i, 0.1 * i)));
  }
  io::Pose out;

  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(history.lookup(i * 10 * kMs, 0, &out), PoseLookup::kOk) << i;
    expectPoseNear(out, pose(i, 0.1 * i), kTolerance);
  }
}

TEST(PoseHistory, StampsMustIncrease) {
  PoseHistory history(4);
  ASSERT_TRUE(history.push(100, pose(1.0)));

  EXPECT_FALSE(history.push(100, pose(2.0)));
  EXPECT_FALSE(history.push(99, pose(3.0)));

  EXPECT_EQ(history.size(), 1u);
  io::Pose out;
  ASSERT_EQ(history.lookup(100, 0, &out), PoseLookup::kOk);
  expectPoseNear(out, pose(1.0), 0.0);
}

TEST(PoseHistory, FullRingForgetsTheOldestPoses) {
  PoseHistory history(4);

  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(history.push(i * kMs, pose(i)));
  }

  EXPECT_EQ(history.size(), 4u);
  EXPECT_EQ(history.oldestStamp(), 6 * kMs);
  EXPECT_EQ(history.newestStamp(), 9 * kMs);
  io::Pose out;
  EXPECT_EQ(history.lookup(6 * kMs - 1, 0, &out), PoseLookup::kTooOld);
  ASSERT_EQ(history.lookup(6 * kMs + kMs / 2, 0, &out), PoseLookup::kOk);
  EXPECT_NEAR(out.position.x(), 6.5, kTolerance);
  ASSERT_EQ(history.lookup(8 * kMs + kMs / 4, 0, &out), PoseLookup::kOk);
  EXPECT_NEAR(out.position.x(), 8.25, kTolerance);
}

// The lookup remembers its last bracket; lookups in any order, interleaved with pushes that wrap
// the ring, must still find the right bracket.
TEST(PoseHistory, LookupsInAnyOrderMatchLinearInterpolation) {
  constexpr std::size_t kCapacity = 16;
  PoseHistory history(kCapacity);
  std::mt19937_64 rng(7);
  std::int64_t stamp = 0;
  int pushed = 0;

  for (int round = 0; round < 200; ++round) {
    // Poses on x = stamp / 1 ms at irregular steps, so that x is linear in time.
    stamp += 1 + static_cast<std::int64_t>(rng() % (3 * kMs));
    io::Pose p;
    p.position = {static_cast<double>(stamp) / kMs, 0.0, 0.0};
    ASSERT_TRUE(history.push(stamp, p));
    ++pushed;
    for (int q = 0; q < 8; ++q) {
      const std::int64_t lo = history.oldestStamp();
      const std::int64_t hi = history.newestStamp();
      const std::int64_t t =
          lo + static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(hi - lo + 1));
      io::Pose out;
      ASSERT_EQ(history.lookup(t, 0, &out), PoseLookup::kOk) << "round " << round;
      EXPECT_NEAR(out.position.x(), static_cast<double>(t) / kMs, 1e-9)
          << "round " << round << " t " << t;
    }
  }
  EXPECT_EQ(history.size(), kCapacity);
  EXPECT_EQ(pushed, 200);
}

TEST(PoseHistory, LookupNamesAreStable) {
  EXPECT_STREQ(toString(PoseLookup::kOk), "ok");
  EXPECT_STREQ(toString(PoseLookup::kNotYet), "not yet");
  EXPECT_STREQ(toString(PoseLookup::kTooOld), "too old");
  EXPECT_STREQ(toString(PoseLookup::kEmpty), "no pose");
}

}  // namespace
}  // namespace raymap::pipeline
