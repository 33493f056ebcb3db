// SPDX-License-Identifier: BSD-3-Clause
// decodeOdometry and decodeTfMessage on hand-built CDR, including damaged messages.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "src/msgs/pose.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

using test::encodeOdometry;
using test::encodeTfMessage;
using test::TestPose;

TEST(DecodeOdometry, ReadsPoseFramesAndStamp) {
  TestPose pose;
  pose.q[0] = 0.0;
  pose.q[1] = 0.0;
  pose.q[2] = 2.0;  // not normalised on purpose
  pose.q[3] = 0.0;
  for (const bool little : {true, false}) {
    auto result = decodeOdometry(encodeOdometry(pose, little));

    ASSERT_TRUE(result.has_value()) << little;
    EXPECT_EQ(result->stamp_ns, 100'000'000'005LL);
    EXPECT_STREQ(result->parent, "odom");
    EXPECT_STREQ(result->child, "base_link");
    EXPECT_EQ(result->tx, 1.0);
    EXPECT_EQ(result->ty, 2.0);
    EXPECT_EQ(result->tz, 3.0);
    EXPECT_EQ(result->qz, 1.0);
    EXPECT_EQ(result->qw, 0.0);
  }
}

TEST(DecodeOdometry, RefusesBadQuaternionsAndTranslations) {
  TestPose zero;
  zero.q[3] = 0.0;
  auto zero_result = decodeOdometry(encodeOdometry(zero));
  ASSERT_FALSE(zero_result.has_value());
  EXPECT_EQ(zero_result.error(), PoseError::kBadQuaternion);

  TestPose nan_q;
  nan_q.q[1] = std::numeric_limits<double>::quiet_NaN();
  auto nan_result = decodeOdometry(encodeOdometry(nan_q));
  ASSERT_FALSE(nan_result.has_value());
  EXPECT_EQ(nan_result.error(), PoseError::kBadQuaternion);

  TestPose inf_t;
  inf_t.t[2] = std::numeric_limits<double>::infinity();
  auto inf_result = decodeOdometry(encodeOdometry(inf_t));
  ASSERT_FALSE(inf_result.has_value());
  EXPECT_EQ(inf_result.error(), PoseError::kBadTranslation);

  TestPose long_frame;
  long_frame.child = std::string(64, 'c');
  auto long_result = decodeOdometry(encodeOdometry(long_frame));
  ASSERT_FALSE(long_result.has_value());
  EXPECT_EQ(long_result.error(), PoseError::kFrameIdTooLong);
}

TEST(DecodeOdometry, EveryTruncationIsRefused) {
  const std::vector<std::byte> full = encodeOdometry(TestPose{});
  for (std::size_t size = 0; size < full.size(); ++size) {
    const std::vector<std::byte> cut(full.begin(),
                                     full.begin() + static_cast<std::ptrdiff_t>(size));
    auto result = decodeOdometry(cut);
    ASSERT_FALSE(result.has_value()) << size;
    EXPECT_EQ(result.error(), size < 4 ? PoseError::kBadEncapsulation : PoseError::kTruncated);
  }
}

TEST(DecodeTfMessage, WritesWhatFitsAndChecksTheRest) {
  // NOTE: built by push_back, not by assigning to poses[i].child: GCC 12 at -O3 reports a false
  // -Wrestrict overlap inside std::string's assignment in the indexed form.
  std::vector<TestPose> poses;
  for (const char* child : {"a", "b", "c"}) {
    TestPose pose;
    pose.child = std::string(child);
    poses.push_back(pose);
  }
  poses[2].t[0] = -5.0;
  std::vector<StampedTransform> out(2);

  auto two = decodeTfMessage(encodeTfMessage(poses), out);

  ASSERT_TRUE(two.has_value());
  EXPECT_EQ(*two, 2U);
  EXPECT_STREQ(out[0].child, "a");
  EXPECT_STREQ(out[1].child, "b");

  std::vector<StampedTransform> room(4);
  auto three = decodeTfMessage(encodeTfMessage(poses, /*little=*/false), room);
  ASSERT_TRUE(three.has_value());
  EXPECT_EQ(*three, 3U);
  EXPECT_STREQ(room[2].child, "c");
  EXPECT_EQ(room[2].tx, -5.0);
  EXPECT_EQ(room[2].qw, 1.0);

  poses[2].q[3] = 0.0;  // one bad transform rejects the message
  auto bad = decodeTfMessage(encodeTfMessage(poses), room);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error(), PoseError::kBadQuaternion);
}

TEST(DecodeTfMessage, EmptyAndAbsurdCounts) {
  std::vector<StampedTransform> out(2);
  auto empty = decodeTfMessage(encodeTfMessage({}), out);
  ASSERT_TRUE(empty.has_value());
  EXPECT_EQ(*empty, 0U);

  std::vector<std::byte> absurd = encodeTfMessage({TestPose{}});
  absurd[4] = absurd[5] = absurd[6] = absurd[7] = std::byte{0xFF};
  auto result = decodeTfMessage(absurd, out);
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error(), PoseError::kTruncated);
}

TEST(DecodePoseFuzz, RandomMutationsNeverCrash) {
  const std::vector<std::byte> odometry = encodeOdometry(TestPose{});
  const std::vector<std::byte> tf = encodeTfMessage(std::vector<TestPose>(3));
  std::mt19937 rng(777);
  std::vector<StampedTransform> out(4);
  for (int round = 0; round < 4000; ++round) {
    std::vector<std::byte> bytes = (round % 2 == 0) ? odometry : tf;
    const int edits = 1 + static_cast<int>(rng() % 6);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % bytes.size();
      if (rng() % 5 == 0) {
        bytes.resize(at + 1);
      } else {
        bytes[at] = static_cast<std::byte>(rng() & 0xFFU);
      }
    }
    const std::vector<std::byte> exact(bytes.begin(), bytes.end());
    if (round % 2 == 0) {
      auto result = decodeOdometry(exact);
      if (result.has_value()) {
        const double norm = std::sqrt(result->qw * result->qw + result->qx * result->qx +
                                      result->qy * result->qy + result->qz * result->qz);
        ASSERT_NEAR(norm, 1.0, 1e-9);
      }
    } else {
      auto result = decodeTfMessage(exact, out);
      if (result.has_value()) {
        ASSERT_LE(*result, out.size());
      }
    }
  }
}

}  // namespace
}  // namespace raymap::dds
