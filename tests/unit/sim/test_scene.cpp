// SPDX-License-Identifier: BSD-3-Clause
// Scenes: castRay on every primitive against hand-computed distances, and the true height field
// (solidIntervals, trueSurface) on tables, stairs, ramps and ditches.
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/sim/scene.hpp"

namespace raymap::sim {
namespace {

constexpr double kSceneTolerance = 1e-9;
constexpr double kInf = std::numeric_limits<double>::infinity();

Vec3d unit(Vec3d v) { return v * (1.0 / v.norm()); }

/// A scene without ground holding one primitive.
Scene floating() {
  Scene scene;
  scene.has_ground = false;
  return scene;
}

/// Flat ground at z = 0 with a ditch 1 m wide (x 2..3), 6 m long (y -3..3) and 0.8 m deep.
Scene ditchScene() {
  Scene scene;
  scene.ditches.push_back({2.0, -3.0, 3.0, 3.0, 0.8});
  return scene;
}

// ---- castRay ----

TEST(CastRay, BoxFacesFromEachSide) {
  Scene scene = floating();
  scene.boxes.push_back({{1.0, -1.0, 0.0}, {2.0, 1.0, 1.0}});

  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 0.5}, {1.0, 0.0, 0.0}), 1.0, kSceneTolerance);   // -x face
  EXPECT_NEAR(castRay(scene, {5.0, 0.0, 0.5}, {-1.0, 0.0, 0.0}), 3.0, kSceneTolerance);  // +x face
  EXPECT_NEAR(castRay(scene, {1.5, 0.0, 3.0}, {0.0, 0.0, -1.0}), 2.0, kSceneTolerance);  // top
  EXPECT_NEAR(castRay(scene, {1.5, -4.0, 0.2}, {0.0, 1.0, 0.0}), 3.0, kSceneTolerance);  // -y face
  // Slanted: x = 1 is reached at t = sqrt(5) / 2 with y = 0.5, inside the face.
  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 0.5}, unit({2.0, 1.0, 0.0})), std::sqrt(5.0) / 2.0,
              kSceneTolerance);
}

TEST(CastRay, MissesAndRaysPointingAwayAreInfinite) {
  Scene scene = floating();
  scene.boxes.push_back({{1.0, -1.0, 0.0}, {2.0, 1.0, 1.0}});

  EXPECT_EQ(castRay(scene, {0.0, 0.0, 0.5}, {-1.0, 0.0, 0.0}), kInf);
  EXPECT_EQ(castRay(scene, {0.0, 0.0, 1.5}, {1.0, 0.0, 0.0}), kInf);    // passes over the top
  EXPECT_EQ(castRay(Scene{}, {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}), kInf);  // sky above the ground
}

TEST(CastRay, OriginInsideASolidIsZero) {
  Scene scene = floating();
  scene.boxes.push_back({{1.0, -1.0, 0.0}, {2.0, 1.0, 1.0}});

  EXPECT_EQ(castRay(scene, {1.5, 0.0, 0.5}, {1.0, 0.0, 0.0}), 0.0);
  EXPECT_EQ(castRay(Scene{}, {0.0, 0.0, -1.0}, {0.0, 0.0, 1.0}), 0.0);  // below the ground
}

TEST(CastRay, GroundPlaneAtItsHeight) {
  Scene scene;
  scene.ground_height = -0.5;

  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 1.5}, {0.0, 0.0, -1.0}), 2.0, kSceneTolerance);
  // 45 degrees down from 2 m above the ground: 2 sqrt(2).
  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 1.5}, unit({1.0, 0.0, -1.0})), 2.0 * std::sqrt(2.0),
              kSceneTolerance);
}

TEST(CastRay, RampSlopeFromEveryDirectionItRises) {
  // A ramp over x 0..4, y -1..1 (or the same rotated), rising 1 m.
  struct Case {
    RampAxis axis;
    Vec3d above;  // a point 3 m up, over a place where the top is at `top`
    double top;
  };
  const Case cases[] = {{RampAxis::kPlusX, {1.0, 0.0, 3.0}, 0.25},
                        {RampAxis::kMinusX, {1.0, 0.0, 3.0}, 0.75},
                        {RampAxis::kPlusY, {2.0, 0.5, 3.0}, 0.75},
                        {RampAxis::kMinusY, {2.0, 0.5, 3.0}, 0.25}};
  for (const Case& c : cases) {
    Scene scene = floating();
    scene.ramps.push_back({{0.0, -1.0, 0.0}, {4.0, 1.0, 1.0}, c.axis});

    EXPECT_NEAR(castRay(scene, c.above, {0.0, 0.0, -1.0}), 3.0 - c.top, kSceneTolerance)
        << "axis " << static_cast<int>(c.axis);
  }
}

TEST(CastRay, RampHitOnTheSlopeAndOnTheHighFace) {
  Scene scene = floating();
  scene.ramps.push_back({{0.0, -1.0, 0.0}, {4.0, 1.0, 1.0}, RampAxis::kPlusX});

  // Level at z = 0.5 towards +x: the slope is at 0.5 where x = 2.
  EXPECT_NEAR(castRay(scene, {-1.0, 0.0, 0.5}, {1.0, 0.0, 0.0}), 3.0, kSceneTolerance);
  // From beyond the high end towards -x: the vertical face at x = 4.
  EXPECT_NEAR(castRay(scene, {5.0, 0.0, 0.5}, {-1.0, 0.0, 0.0}), 1.0, kSceneTolerance);
  // Above the ramp's top everywhere: a miss.
  EXPECT_EQ(castRay(scene, {-1.0, 0.0, 1.1}, {1.0, 0.0, 0.0}), kInf);
}

TEST(CastRay, PoleSideAndTop) {
  Scene scene = floating();
  scene.poles.push_back({0.0, 0.0, 0.5, 0.0, 2.0});

  EXPECT_NEAR(castRay(scene, {-3.0, 0.0, 1.0}, {1.0, 0.0, 0.0}), 2.5, kSceneTolerance);
  // Off centre by 0.3: the side is at x = -sqrt(0.25 - 0.09) = -0.4.
  EXPECT_NEAR(castRay(scene, {-3.0, 0.3, 1.0}, {1.0, 0.0, 0.0}), 2.6, kSceneTolerance);
  EXPECT_NEAR(castRay(scene, {0.1, 0.1, 5.0}, {0.0, 0.0, -1.0}), 3.0, kSceneTolerance);
  EXPECT_EQ(castRay(scene, {-3.0, 0.0, 2.5}, {1.0, 0.0, 0.0}), kInf);  // over it
  EXPECT_EQ(castRay(scene, {-3.0, 0.6, 1.0}, {1.0, 0.0, 0.0}), kInf);  // beside it
}

TEST(CastRay, DitchBottomAndGroundBesideIt) {
  const Scene scene = ditchScene();

  EXPECT_NEAR(castRay(scene, {2.5, 0.0, 1.2}, {0.0, 0.0, -1.0}), 2.0, kSceneTolerance);
  EXPECT_NEAR(castRay(scene, {1.5, 0.0, 1.2}, {0.0, 0.0, -1.0}), 1.2, kSceneTolerance);
  // Steep: the opening at x = 2.4, the bottom (z = -0.8) at x = 2.8.
  EXPECT_NEAR(castRay(scene, {1.8, 0.0, 1.2}, unit({1.0, 0.0, -2.0})), std::sqrt(5.0),
              kSceneTolerance);
}

TEST(CastRay, RayIntoTheDitchEndsOnTheFarWall) {
  const Scene scene = ditchScene();
  // Shallow: the opening at x = 2.4, then the wall x = 3 at z = -0.3 (above the bottom).
  const Vec3d dir = unit({1.0, 0.0, -0.5});

  const double range = castRay(scene, {0.0, 0.0, 1.2}, dir);

  EXPECT_NEAR(range, 3.0 * std::sqrt(1.25), kSceneTolerance);
  const Vec3d hit = Vec3d{0.0, 0.0, 1.2} + dir * range;
  EXPECT_NEAR(hit.x, 3.0, kSceneTolerance);
  EXPECT_NEAR(hit.z, -0.3, kSceneTolerance);
}

TEST(CastRay, RayPassingOverTheDitchMeetsTheGroundBeyond) {
  const Scene scene = ditchScene();
  const Vec3d dir = unit({1.0, 0.0, -0.2});  // the ground at x = 6

  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 1.2}, dir), 6.0 * std::sqrt(1.04), kSceneTolerance);
}

TEST(CastRay, FromInsideTheDitch) {
  const Scene scene = ditchScene();
  const Vec3d inside{2.5, 0.0, -0.4};

  EXPECT_NEAR(castRay(scene, inside, {-1.0, 0.0, 0.0}), 0.5, kSceneTolerance);  // a wall
  EXPECT_NEAR(castRay(scene, inside, {0.0, 0.0, -1.0}), 0.4, kSceneTolerance);  // the bottom
  EXPECT_EQ(castRay(scene, inside, {0.0, 0.0, 1.0}), kInf);           // out through the opening
  EXPECT_EQ(castRay(scene, {2.5, 0.0, -1.0}, {0.0, 0.0, 1.0}), 0.0);  // below the bottom
}

TEST(CastRay, NearestOfSeveralSolids) {
  Scene scene;
  scene.boxes.push_back({{3.0, -1.0, 0.0}, {4.0, 1.0, 2.0}});
  scene.poles.push_back({1.5, 0.0, 0.1, 0.0, 2.0});

  EXPECT_NEAR(castRay(scene, {0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}), 1.4, kSceneTolerance);
}

// ---- solidIntervals and trueSurface ----

/// A table as the scene file builds it: a 2 m x 1 m top from 0.71 to 0.75 m on four legs.
Scene tableScene() {
  Scene scene;
  scene.boxes.push_back({{-1.0, -0.5, 0.71}, {1.0, 0.5, 0.75}});
  for (const double x : {-1.0, 0.94}) {
    for (const double y : {-0.5, 0.44}) {
      scene.boxes.push_back({{x, y, 0.0}, {x + 0.06, y + 0.06, 0.71}});
    }
  }
  return scene;
}

TEST(SolidIntervals, TableTopAboveTheGround) {
  const auto intervals = solidIntervals(tableScene(), 0.0, 0.0);

  ASSERT_EQ(intervals.size(), 2u);
  EXPECT_EQ(intervals[0].first, -kInf);
  EXPECT_EQ(intervals[0].second, 0.0);
  EXPECT_EQ(intervals[1], std::make_pair(0.71, 0.75));
}

TEST(SolidIntervals, TouchingSolidsMergeIntoOne) {
  // At a leg, the ground, the leg and the top are one solid up to 0.75.
  const auto intervals = solidIntervals(tableScene(), -0.97, -0.47);

  ASSERT_EQ(intervals.size(), 1u);
  EXPECT_EQ(intervals[0].second, 0.75);
}

TEST(SolidIntervals, EmptyColumnWithoutGround) {
  EXPECT_TRUE(solidIntervals(floating(), 0.0, 0.0).empty());
  EXPECT_FALSE(trueSurface(floating(), 0.0, 0.0, 0.0, 0.5).has_value());
}

TEST(TrueSurface, UnderATableTheGroundWithTheTablesClearance) {
  const auto surface = trueSurface(tableScene(), 0.0, 0.0, 0.0, 0.5);

  ASSERT_TRUE(surface.has_value());
  EXPECT_EQ(surface->height, 0.0);
  EXPECT_NEAR(surface->clearance, 0.71, kSceneTolerance);
}

TEST(TrueSurface, TheTableTopWhenTheClearanceNeededIsLarger) {
  const auto surface = trueSurface(tableScene(), 0.0, 0.0, 0.0, 1.0);

  ASSERT_TRUE(surface.has_value());
  EXPECT_EQ(surface->height, 0.75);
  EXPECT_EQ(surface->clearance, kInf);
}

TEST(TrueSurface, NearestToTheReferenceTiesGoToTheLower) {
  Scene scene;
  scene.boxes.push_back({{-1.0, -1.0, 1.0}, {1.0, 1.0, 1.5}});  // a floating slab

  EXPECT_EQ(trueSurface(scene, 0.0, 0.0, 0.0, 0.5)->height, 0.0);
  EXPECT_EQ(trueSurface(scene, 0.0, 0.0, 1.4, 0.5)->height, 1.5);
  EXPECT_EQ(trueSurface(scene, 0.0, 0.0, 0.75, 0.5)->height, 0.0);  // 0.75 from both
}

TEST(TrueSurface, StairTreads) {
  // Six steps of 0.17 m rise and 0.3 m run from x = 2 along +x, as the scene file builds them.
  Scene scene;
  for (int k = 1; k <= 6; ++k) {
    scene.boxes.push_back({{2.0 + 0.3 * (k - 1), -0.6, 0.0}, {2.0 + 0.3 * k, 0.6, 0.17 * k}});
  }

  for (int k = 1; k <= 6; ++k) {
    const double x = 2.0 + 0.3 * (k - 0.5);
    const auto surface = trueSurface(scene, x, 0.0, 0.0, 0.5);
    ASSERT_TRUE(surface.has_value());
    EXPECT_NEAR(surface->height, 0.17 * k, kSceneTolerance) << "step " << k;
  }
  EXPECT_EQ(trueSurface(scene, 1.5, 0.0, 0.0, 0.5)->height, 0.0);
}

TEST(TrueSurface, RampHeightIsLinear) {
  Scene scene;
  scene.ramps.push_back({{-2.0, -5.0, 0.0}, {2.0, -3.0, 0.8}, RampAxis::kPlusX});

  EXPECT_NEAR(trueSurface(scene, 0.0, -4.0, 0.0, 0.5)->height, 0.4, kSceneTolerance);
  EXPECT_NEAR(trueSurface(scene, 1.5, -4.0, 0.0, 0.5)->height, 0.7, kSceneTolerance);
  EXPECT_NEAR(trueSurface(scene, -1.9, -4.0, 0.0, 0.5)->height, 0.02, kSceneTolerance);
}

TEST(TrueSurface, DitchBottomAndItsSides) {
  const Scene scene = ditchScene();

  EXPECT_EQ(trueSurface(scene, 2.5, 0.0, 0.0, 0.5)->height, -0.8);
  EXPECT_EQ(trueSurface(scene, 1.95, 0.0, 0.0, 0.5)->height, 0.0);
  EXPECT_EQ(trueSurface(scene, 3.05, 0.0, 0.0, 0.5)->height, 0.0);
  EXPECT_EQ(trueSurface(scene, 2.5, 3.05, 0.0, 0.5)->height, 0.0);
}

TEST(ObjectBounds, CoversEveryObjectButNotTheGround) {
  Scene scene = ditchScene();
  scene.poles.push_back({-1.0, 0.0, 0.5, 0.0, 2.0});

  const auto bounds = objectBounds(scene);

  ASSERT_TRUE(bounds.has_value());
  EXPECT_EQ(bounds->min, (Vec3d{-1.5, -3.0, -0.8}));
  EXPECT_EQ(bounds->max, (Vec3d{3.0, 3.0, 2.0}));
  EXPECT_FALSE(objectBounds(Scene{}).has_value());
}

}  // namespace
}  // namespace raymap::sim
