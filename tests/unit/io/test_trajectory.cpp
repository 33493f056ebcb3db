// SPDX-License-Identifier: BSD-3-Clause
// Trajectory files: parsing rules, line-numbered errors, and pose interpolation.
#include <cmath>
#include <numbers>
#include <ostream>
#include <string>

#include <gtest/gtest.h>

#include "src/io/trajectory.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

constexpr double kTrajectoryTolerance = 1e-12;

Result<Trajectory> loadText(const test::TempDir& dir, const std::string& text) {
  const std::string path = dir.file("trajectory.txt");
  test::writeBytes(path, text);
  return Trajectory::load(path);
}

Eigen::Quaterniond aboutZ(double angle_rad) {
  return {std::cos(angle_rad / 2.0), 0.0, 0.0, std::sin(angle_rad / 2.0)};  // w x y z
}

TEST(Trajectory, SkipsHeaderCommentsAndBlankLinesAndAcceptsCommas) {
  test::TempDir dir;

  const auto trajectory = loadText(dir,
                                   "time,x,y,z\n"
                                   "# recorded by hand\n"
                                   "\n"
                                   "0.0, 1, 2, 3   # the start\n"
                                   "1.0\t2\t4\t6\n"
                                   "2.5 3 6 9\n");

  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;
  EXPECT_FALSE(trajectory->hasOrientation());
  ASSERT_EQ(trajectory->samples().size(), 3u);
  EXPECT_EQ(trajectory->startTime(), 0.0);
  EXPECT_EQ(trajectory->endTime(), 2.5);
  EXPECT_EQ(trajectory->samples()[1].position, Eigen::Vector3d(2, 4, 6));
}

TEST(Trajectory, InterpolatesPositionLinearlyAndHitsSamplesExactly) {
  test::TempDir dir;
  const auto trajectory = loadText(dir, "0 0 0 0\n2 2 -4 0.1\n3 0.3 0.7 1e-3\n");
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;

  const auto quarter = trajectory->poseAt(0.5);
  const auto at_sample = trajectory->poseAt(3.0);
  const auto middle = trajectory->poseAt(2.0);

  ASSERT_TRUE(quarter && at_sample && middle);
  EXPECT_NEAR(quarter->position.x(), 0.5, kTrajectoryTolerance);
  EXPECT_NEAR(quarter->position.y(), -1.0, kTrajectoryTolerance);
  EXPECT_NEAR(quarter->position.z(), 0.025, kTrajectoryTolerance);
  EXPECT_EQ(at_sample->position, Eigen::Vector3d(0.3, 0.7, 1e-3));  // exactly, no rounding
  EXPECT_EQ(middle->position, Eigen::Vector3d(2, -4, 0.1));
}

TEST(Trajectory, TimesOutsideTheSamplesAreNotCovered) {
  test::TempDir dir;
  const auto trajectory = loadText(dir, "1 0 0 0\n2 1 1 1\n");
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;

  EXPECT_TRUE(trajectory->poseAt(1.0).has_value());
  EXPECT_TRUE(trajectory->poseAt(2.0).has_value());
  EXPECT_FALSE(trajectory->poseAt(0.999).has_value());
  EXPECT_FALSE(trajectory->poseAt(2.001).has_value());
  EXPECT_FALSE(trajectory->poseAt(std::nan("")).has_value());
}

TEST(Trajectory, SegmentHintGivesTheSameAnswersInAnyQueryOrder) {
  std::vector<TrajectorySample> samples;
  for (int i = 0; i <= 100; ++i) {
    samples.push_back({i * 0.1, {i * 1.0, i * i * 1.0, 0.0}});  // identity orientation
  }
  const auto trajectory = Trajectory::fromSamples(samples, false, "made");
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;
  std::size_t hint = 0;

  for (const double t : {0.05, 0.06, 0.15, 9.95, 0.0, 5.55, 5.56, 10.0, 3.0}) {
    const auto hinted = trajectory->poseAt(t, hint);
    const auto fresh = trajectory->poseAt(t);
    ASSERT_TRUE(hinted && fresh);
    EXPECT_EQ(hinted->position, fresh->position) << t;
  }
}

TEST(Trajectory, InterpolatesOrientationOnTheShortArc) {
  test::TempDir dir;
  const Eigen::Quaterniond start = aboutZ(0.0);
  const Eigen::Quaterniond end = aboutZ(std::numbers::pi / 2.0);
  // The end written with the opposite sign: the same rotation, which nlerp must not unwind.
  const std::string text = "0 0 0 0 1 0 0 0\n1 0 0 0 " + std::to_string(-end.w()) + " 0 0 " +
                           std::to_string(-end.z()) + "\n";
  const auto trajectory = loadText(dir, text);
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;
  ASSERT_TRUE(trajectory->hasOrientation());
  EXPECT_EQ(trajectory->samples()[0].orientation.w(), start.w());

  const auto halfway = trajectory->poseAt(0.5);

  ASSERT_TRUE(halfway.has_value());
  const Eigen::Vector3d x_axis = halfway->orientation * Eigen::Vector3d::UnitX();
  const double angle = std::atan2(x_axis.y(), x_axis.x());
  EXPECT_NEAR(angle, std::numbers::pi / 4.0, 1e-6);  // midpoint of nlerp = midpoint of slerp
  EXPECT_NEAR(std::sqrt(halfway->orientation.dot(halfway->orientation)), 1.0, kTrajectoryTolerance);
}

TEST(Trajectory, NormalisesQuaternionsAndTransformsPoints) {
  test::TempDir dir;
  // qw = qz = 2: a 90-degree turn about z, written unnormalised.
  const auto trajectory = loadText(dir, "0 10 20 30 2 0 0 2\n");
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;

  const auto pose = trajectory->poseAt(0.0);

  ASSERT_TRUE(pose.has_value());
  const Eigen::Vector3d p_world = pose->transform({1, 0, 0});
  EXPECT_NEAR(p_world.x(), 10.0, kTrajectoryTolerance);
  EXPECT_NEAR(p_world.y(), 21.0, kTrajectoryTolerance);
  EXPECT_NEAR(p_world.z(), 30.0, kTrajectoryTolerance);
}

TEST(PoseMaths, InterpolationIsNlerpOnTheShortArcAndExactAtItsEnds) {
  const Pose a{{1.0, 2.0, 3.0}, aboutZ(0.2)};
  const double turn = std::numbers::pi / 2.0;
  // b's quaternion on the far hemisphere: the same rotation, which must not be unwound.
  const Pose b{{3.0, 2.0, -1.0}, Eigen::Quaterniond(-aboutZ(0.2 + turn).coeffs())};

  const Pose at_a = interpolate(a, b, 0.0);
  const Pose quarter = interpolate(a, b, 0.25);
  const Pose at_b = interpolate(a, b, 1.0);

  EXPECT_EQ(at_a.position, a.position);  // exactly
  EXPECT_EQ(at_a.orientation.coeffs(), a.orientation.coeffs());
  EXPECT_NEAR(quarter.position.x(), 1.5, kTrajectoryTolerance);
  EXPECT_NEAR(quarter.position.z(), 2.0, kTrajectoryTolerance);
  // nlerp's angle at f: 2 atan2(f sin(turn / 2), 1 - f + f cos(turn / 2)) past a's; slerp's
  // would be f * turn, about 0.0157 rad more here.
  const double f = 0.25;
  const double nlerp =
      2.0 * std::atan2(f * std::sin(turn / 2.0), 1.0 - f + f * std::cos(turn / 2.0));
  const Eigen::Vector3d x_axis = quarter.orientation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(x_axis.y(), x_axis.x()), 0.2 + nlerp, 1e-12);
  EXPECT_GT(f * turn - nlerp, 0.01) << "this is slerp, not nlerp";
  EXPECT_NEAR(quarter.orientation.norm(), 1.0, kTrajectoryTolerance);
  EXPECT_NEAR(std::abs(at_b.orientation.dot(b.orientation)), 1.0, kTrajectoryTolerance);
}

TEST(PoseMaths, ComposeTransformAndIsometriesAgree) {
  const Pose a_b{{0.5, -1.0, 2.0},
                 Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()))};
  const Pose b_c{
      {-0.3, 0.2, 1.1},
      Eigen::Quaterniond(Eigen::AngleAxisd(-1.9, Eigen::Vector3d(0, 1, -1).normalized()))};
  const Eigen::Vector3d p_c(0.4, -2.5, 7.0);

  const Pose a_c = compose(a_b, b_c);
  const Eigen::Isometry3d t_a_c = a_b.toIsometry() * b_c.toIsometry();
  const Pose back = Pose::fromIsometry(t_a_c);

  EXPECT_NEAR((a_c.transform(p_c) - a_b.transform(b_c.transform(p_c))).norm(), 0.0,
              kTrajectoryTolerance);
  EXPECT_NEAR((a_c.transform(p_c) - t_a_c * p_c).norm(), 0.0, kTrajectoryTolerance);
  EXPECT_NEAR((back.position - a_c.position).norm(), 0.0, kTrajectoryTolerance);
  EXPECT_NEAR(std::abs(back.orientation.dot(a_c.orientation)), 1.0,
              kTrajectoryTolerance);  // q or -q
  EXPECT_NEAR(back.orientation.norm(), 1.0, kTrajectoryTolerance);
  EXPECT_TRUE(Pose{}.toIsometry().isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(Pose{}.transform(p_c), p_c);  // the default pose is the identity, exactly
}

struct BadTrajectory {
  const char* name;
  std::string text;
  std::string message;  // after "PATH: "

  friend void PrintTo(const BadTrajectory& bad, std::ostream* os) { *os << bad.name; }
};

class TrajectoryErrors : public ::testing::TestWithParam<BadTrajectory> {};

TEST_P(TrajectoryErrors, NameTheLineAndTheProblem) {
  test::TempDir dir;

  const auto trajectory = loadText(dir, GetParam().text);

  ASSERT_FALSE(trajectory.has_value());
  EXPECT_EQ(trajectory.error().code, ErrorCode::kFormat);
  EXPECT_EQ(trajectory.error().message, dir.file("trajectory.txt") + ": " + GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, TrajectoryErrors,
    ::testing::Values(
        BadTrajectory{"RepeatedTime", "0 0 0 0\n1 0 0 0\n1 1 1 1\n",
                      "line 3: time 1 does not come after the previous sample's time (times must "
                      "increase strictly)"},
        BadTrajectory{"DecreasingTime", "# t x y z\n5 0 0 0\n4 0 0 0\n",
                      "line 3: time 4 does not come after the previous sample's time (times must "
                      "increase strictly)"},
        BadTrajectory{
            "WrongColumns", "0 0 0 0 1\n",
            "line 1: expected 4 values (time x y z) or 8 (time x y z qw qx qy qz), found 5"},
        BadTrajectory{"MixedColumns", "0 0 0 0 1 0 0 0\n1 0 0 0\n",
                      "line 2: expected 8 values like the first sample, found 4"},
        BadTrajectory{"TextInData", "time x y z\n0 0 0 0\n1 0 zero 0\n",
                      "line 3: 'zero' is not a number"},
        BadTrajectory{"ZeroQuaternion", "0 0 0 0 0 0 0 0\n",
                      "line 1: the quaternion (qw qx qy qz) is not a rotation"},
        BadTrajectory{"Infinite", "0 inf 0 0\n",
                      "line 1: time and position must be finite numbers"},
        BadTrajectory{"Empty", "# nothing\n\n", "the trajectory has no samples"}),
    [](const ::testing::TestParamInfo<BadTrajectory>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(Trajectory, MissingFileNamesThePath) {
  test::TempDir dir;

  const auto trajectory = Trajectory::load(dir.file("none.txt"));

  ASSERT_FALSE(trajectory.has_value());
  EXPECT_EQ(trajectory.error().code, ErrorCode::kIo);
  EXPECT_EQ(trajectory.error().message.rfind(dir.file("none.txt") + ": ", 0), 0u);
}

TEST(Trajectory, SavedTrajectoriesLoadBackExactly) {
  test::TempDir dir;
  const std::string path = dir.file("saved.txt");
  auto original = Trajectory::fromSamples(
      {{0.1, {1.0 / 3.0, -2e5, 1e-7}, aboutZ(0.3)}, {0.1 + 1e-9, {2.0, 0.0, -1.5}, aboutZ(-2.0)}},
      true, "original");
  ASSERT_TRUE(original.has_value()) << original.error().message;

  ASSERT_TRUE(saveTrajectory(*original, path).has_value());
  const auto loaded = Trajectory::load(path);

  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  ASSERT_TRUE(loaded->hasOrientation());
  ASSERT_EQ(loaded->samples().size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const TrajectorySample& a = original->samples()[i];
    const TrajectorySample& b = loaded->samples()[i];
    EXPECT_EQ(a.time_s, b.time_s);
    EXPECT_EQ(a.position, b.position);
    EXPECT_NEAR(a.orientation.dot(b.orientation), 1.0, kTrajectoryTolerance);
  }
}

TEST(Trajectory, SavesPositionsOnlyWithoutOrientation) {
  test::TempDir dir;
  const std::string path = dir.file("positions.txt");
  auto original =
      Trajectory::fromSamples({{0.0, {1.0, 2.0, 3.0}}, {1.0, {4.0, 5.0, 6.0}}}, false, "p");
  ASSERT_TRUE(original.has_value());

  ASSERT_TRUE(saveTrajectory(*original, path).has_value());
  const auto loaded = Trajectory::load(path);

  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_FALSE(loaded->hasOrientation());
  EXPECT_EQ(loaded->samples()[1].position, Eigen::Vector3d(4.0, 5.0, 6.0));
}

}  // namespace
}  // namespace raymap::io
