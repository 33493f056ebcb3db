// SPDX-License-Identifier: BSD-3-Clause
// Property tests of the shared line walk (kernels/common/line_walk.h) on millions of random and
// adversarial rays: endpoints, face adjacency, step counts, geometric truth of every voxel,
// termination; and the region-split walk the integrators use.
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/line_walk.h"
#include "kernels/common/ray.h"
#include "src/map/ray_preparer.hpp"
#include "src/map/ray_region_walk.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

struct Visit {
  Vec3i voxel;
  float t_enter;
  float t_exit;
};

/// True when the segment a-b (voxel units, global) passes within eps of voxel v's box.
bool touches(Vec3d a, Vec3d b, Vec3i v, double eps) {
  double t0 = 0.0;
  double t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = v[axis] - eps;
    const double hi = v[axis] + 1.0 + eps;
    const double d = b[axis] - a[axis];
    if (std::abs(d) < 1e-300) {
      if (a[axis] < lo || a[axis] > hi) {
        return false;
      }
      continue;
    }
    double ta = (lo - a[axis]) / d;
    double tb = (hi - a[axis]) / d;
    if (ta > tb) {
      std::swap(ta, tb);
    }
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) {
      return false;
    }
  }
  return true;
}

std::vector<Visit> walkWhole(const PreparedRay& ray) {
  const rm_ray_walk_frame f = rm_ray_walk_frame_make(ray);
  rm_line_walk w;
  rm_line_walk_init(&w, f.start, f.end, f.end_voxel);
  std::vector<Visit> visits;
  const Vec3i s{f.start_voxel.x, f.start_voxel.y, f.start_voxel.z};
  for (;;) {
    visits.push_back({s + Vec3i{w.x, w.y, w.z}, rm_line_walk_t_enter(&w), rm_line_walk_t_exit(&w)});
    if (rm_line_walk_next(&w) < 0) {
      break;
    }
    if (visits.size() > 100000000u) {
      ADD_FAILURE() << "walk does not terminate";
      break;
    }
  }
  return visits;
}

std::vector<Vec3i> walkByRegion(const PreparedRay& ray, int region_voxels) {
  RayRegionWalk regions(ray, region_voxels);
  const rm_ray_walk_frame& f = regions.frame();
  const Vec3i s{f.start_voxel.x, f.start_voxel.y, f.start_voxel.z};
  std::vector<Vec3i> voxels;
  RaySpan span;
  while (regions.next(&span)) {
    rm_line_walk w;
    rm_line_walk_init_span(&w, &regions.voxelRay(), span.t0, span.t1, span.box_lo, span.box_hi,
                           span.first ? 1 : 0, span.last ? 1 : 0);
    for (;;) {
      const Vec3i v = s + Vec3i{w.x, w.y, w.z};
      const rm_vec3i r = rm_region_of_voxel(rm_vec3i{v.x, v.y, v.z}, region_voxels);
      EXPECT_EQ((Vec3i{r.x, r.y, r.z}), span.region) << "a span left its region";
      voxels.push_back(v);
      if (rm_line_walk_next(&w) < 0) {
        break;
      }
    }
  }
  return voxels;
}

/// Test fixture: a map at a resolution that is a power of two, so voxel faces are exact doubles.
class LineWalk : public ::testing::Test {
 protected:
  static constexpr double kResolution = 0.125;

  LineWalk() : map_(test::makeMap(config())) {}
  static MapConfig config() {
    MapConfig c;
    c.geometry.resolution = kResolution;
    c.geometry.region_voxels = 8;
    c.memory_budget_bytes = 8u << 20;
    return c;
  }

  PreparedRay prepare(Vec3d origin, Vec3d sample, bool reverse = false) {
    RayFilter filter;
    filter.reverse = reverse;
    filter.max_length_m = 0.0;  // the walk of any length the key range allows
    RayPreparer preparer(map_, filter);
    const Ray ray = test::makeRay(origin, sample);
    PreparedRay out{};
    const auto p = preparer.prepare(std::span<const Ray>(&ray, 1), std::span<PreparedRay>(&out, 1));
    EXPECT_EQ(p.written, 1u) << "ray was rejected";
    return out;
  }

  /// Checks every walk property for the segment origin -> sample (world metres); returns visits.
  std::vector<Visit> checkWalk(Vec3d origin, Vec3d sample, bool reverse = false) {
    const PreparedRay ray = prepare(origin, sample, reverse);
    const std::vector<Visit> visits = walkWhole(ray);
    const Vec3d a = (reverse ? sample : origin) * (1.0 / kResolution);
    const Vec3d b = (reverse ? origin : sample) * (1.0 / kResolution);
    const Vec3i ka = map_.voxelOf(reverse ? sample : origin);
    const Vec3i kb = map_.voxelOf(reverse ? origin : sample);
    EXPECT_FALSE(visits.empty());
    if (visits.empty()) {
      return visits;
    }
    EXPECT_EQ(visits.front().voxel, ka);
    EXPECT_EQ(visits.back().voxel, kb);
    const Vec3i d = kb - ka;
    EXPECT_EQ(visits.size(),
              static_cast<std::size_t>(std::abs(d.x) + std::abs(d.y) + std::abs(d.z)) + 1u);
    const double length = (b - a).norm();
    const double eps = 4e-6 * (length + 1.0) + 1e-6;
    float last_t = 0.0f;
    for (std::size_t i = 0; i < visits.size(); ++i) {
      const Visit& v = visits[i];
      EXPECT_TRUE(touches(a, b, v.voxel, eps))
          << "voxel " << v.voxel.x << "," << v.voxel.y << "," << v.voxel.z << " (step " << i
          << ") does not touch the segment";
      EXPECT_LE(last_t, v.t_enter);
      EXPECT_LE(v.t_enter, v.t_exit);
      EXPECT_GE(v.t_enter, 0.0f);
      EXPECT_LE(v.t_exit, 1.0f);
      last_t = v.t_enter;
      if (i > 0) {
        const Vec3i step = v.voxel - visits[i - 1].voxel;
        EXPECT_EQ(std::abs(step.x) + std::abs(step.y) + std::abs(step.z), 1)
            << "step " << i << " is not to a face-adjacent voxel";
      }
      if (::testing::Test::HasFailure()) {
        break;
      }
    }
    return visits;
  }

  VoxelMap map_;
};

TEST_F(LineWalk, MillionRandomRays) {
  std::mt19937_64 rng(5489);
  std::uniform_real_distribution<double> pos(-40.0, 40.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::exponential_distribution<double> length(1.0 / 3.0);  // metres
  for (int i = 0; i < 1000000 && !HasFailure(); ++i) {
    const Vec3d o{pos(rng), pos(rng), pos(rng)};
    Vec3d dir{unit(rng), unit(rng), unit(rng)};
    dir = dir * (1.0 / std::max(dir.norm(), 1e-9));
    checkWalk(o, o + dir * std::min(length(rng), 30.0), (i & 1) != 0);
  }
}

TEST_F(LineWalk, RaysBetweenFacesEdgesAndCorners) {
  // Endpoints on a lattice of quarter voxels: corners, edge points, face points and centres,
  // all exact in double at this resolution.
  std::mt19937_64 rng(77);
  std::uniform_int_distribution<int> q(-24, 24);
  for (int i = 0; i < 200000 && !HasFailure(); ++i) {
    const Vec3d o{q(rng) * 0.25 * kResolution, q(rng) * 0.25 * kResolution,
                  q(rng) * 0.25 * kResolution};
    const Vec3d s{q(rng) * 0.25 * kResolution, q(rng) * 0.25 * kResolution,
                  q(rng) * 0.25 * kResolution};
    checkWalk(o, s, (i & 1) != 0);
  }
}

TEST_F(LineWalk, AxisAlignedFromCornersInEveryDirection) {
  // OHM's OpenCL walk spins forever on these; ours must end on the right voxel.
  const Vec3d corner{2 * kResolution, -3 * kResolution, 5 * kResolution};
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      for (double length :
           {0.0, 0.5 * kResolution, kResolution, 7 * kResolution, 7.3 * kResolution}) {
        Vec3d end = corner;
        end[axis] += sign * length;
        for (bool reverse : {false, true}) {
          const auto visits = checkWalk(corner, end, reverse);
          EXPECT_LE(visits.size(), 9u);
        }
      }
    }
  }
}

TEST_F(LineWalk, DiagonalsThroughCorners) {
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      for (int sz : {-1, 1}) {
        const Vec3d o{0.0, 0.0, 0.0};
        const Vec3d s{sx * 6 * kResolution, sy * 6 * kResolution, sz * 6 * kResolution};
        const auto visits = checkWalk(o, s);
        EXPECT_EQ(visits.size(), 6u * 3u + 1u);
      }
    }
  }
}

TEST_F(LineWalk, ZeroLengthAndTinyRays) {
  for (const Vec3d p :
       {Vec3d{0.0, 0.0, 0.0}, Vec3d{0.0625, 0.0625, 0.0625}, Vec3d{1.0, -2.0, 3.0}}) {
    EXPECT_EQ(checkWalk(p, p).size(), 1u);
    checkWalk(p, p + Vec3d{1e-9, -1e-9, 1e-12});
    checkWalk(p, p - Vec3d{1e-12, 0.0, 0.0});
  }
}

TEST_F(LineWalk, KilometreRaysFarFromTheOrigin) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const Vec3d base :
       {Vec3d{0.0, 0.0, 0.0}, Vec3d{5000.0, -7000.0, 300.0}, Vec3d{-20000.0, 15000.0, -40.0}}) {
    for (int i = 0; i < 40 && !HasFailure(); ++i) {
      Vec3d dir{unit(rng), unit(rng), unit(rng)};
      dir = dir * (1.0 / dir.norm());
      const Vec3d o = base + Vec3d{unit(rng), unit(rng), unit(rng)};
      checkWalk(o, o + dir * (1000.0 + 500.0 * unit(rng)), (i & 1) != 0);
    }
  }
  // Axis-aligned 1.5 km from a corner far away.
  checkWalk({6000.0, 6000.0, 6000.0}, {6000.0, 6000.0, 7500.0});
}

TEST_F(LineWalk, RegionSplitWalkMatchesTheWholeWalk) {
  // The integrators walk a ray region by region. Each piece must stay in its region, the pieces
  // must join up and cover the same voxels as the whole walk (up to float ties at region faces).
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> pos(-10.0, 10.0);
  int differing = 0;  // among rays with random (off-lattice) endpoints
  const int rays = 100000;
  std::uniform_int_distribution<int> lattice(-40, 40);  // quarter voxels: faces, edges, corners
  for (int i = 0; i < rays && !HasFailure(); ++i) {
    Vec3d o{pos(rng), pos(rng), pos(rng)};
    Vec3d s{pos(rng), pos(rng), pos(rng)};
    if (i % 4 == 0) {
      // Endpoints exactly on region faces, edges and corners (a region is 8 voxels = 1 m).
      auto lat = [&] { return static_cast<double>(lattice(rng)); };
      o = Vec3d{lat(), lat(), lat()} * 0.25;  // a quarter region: often on region faces
      s = Vec3d{lat(), lat(), lat()} * (0.25 * kResolution);
    }
    const bool reverse = (i & 1) != 0;
    const PreparedRay ray = prepare(o, s, reverse);
    const std::vector<Vec3i> pieces = walkByRegion(ray, 8);
    const std::vector<Visit> whole = walkWhole(ray);
    ASSERT_FALSE(pieces.empty());
    EXPECT_EQ(pieces.front(), whole.front().voxel);
    EXPECT_EQ(pieces.back(), whole.back().voxel);
    const Vec3d a = (reverse ? s : o) * (1.0 / kResolution);
    const Vec3d b = (reverse ? o : s) * (1.0 / kResolution);
    const double eps = 4e-6 * ((b - a).norm() + 1.0) + 1e-6;
    std::set<std::tuple<int, int, int>> seen;
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      const Vec3i& v = pieces[k];
      EXPECT_TRUE(seen.insert({v.x, v.y, v.z}).second) << "voxel visited twice";
      EXPECT_TRUE(touches(a, b, v, eps));
      if (k > 0) {
        const Vec3i d = v - pieces[k - 1];
        EXPECT_LE(std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}), 1);
      }
    }
    bool same = pieces.size() == whole.size();
    for (std::size_t k = 0; same && k < pieces.size(); ++k) {
      same = pieces[k] == whole[k].voxel;
    }
    // Lattice rays cross region edges exactly, where either neighbour is a correct choice.
    differing += (same || i % 4 == 0) ? 0 : 1;
  }
  // A random ray differs only if it crosses a region face within float rounding of an edge.
  EXPECT_LT(differing, rays / 1000) << differing << " of " << rays << " rays differ";
}

}  // namespace
}  // namespace raymap
