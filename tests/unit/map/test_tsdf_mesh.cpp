// SPDX-License-Identifier: BSD-3-Clause
// The TSDF mesh (marching cubes): the case table covers each case's crossed edges, a random
// field and a sphere give closed, consistently wound surfaces whose vertices are the zero
// crossings, a simulated sphere's mesh lies within a quarter voxel of the truth and faces
// outwards, and light voxels and saturated jumps are left out.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/marching_cubes.hpp"
#include "src/map/tsdf_mesh.hpp"
#include "src/map/tsdf_surface.hpp"
#include "tests/support/test_rays.hpp"
#include "tests/support/tsdf_scenes.hpp"

namespace raymap {
namespace {

constexpr double kMeshResolution = 0.1;
constexpr double kTau = 0.3;  // tsdfConfig()'s truncation, metres

Vec3d normalOf(const TsdfMesh& mesh, const std::array<std::uint32_t, 3>& t) {
  return (mesh.vertices[t[1]] - mesh.vertices[t[0]])
      .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
}

/// Writes a voxel's distance and weight straight into the map (creating its region).
void setVoxel(VoxelMap& map, Vec3i voxel, float distance, float weight) {
  const Vec3i region = map.regionOfVoxel(voxel);
  const auto slot = map.acquireRegion(region);
  ASSERT_TRUE(slot.has_value());
  const std::int32_t n = map.geometry().region_voxels;
  const Vec3i local = voxel - Vec3i{region.x * n, region.y * n, region.z * n};
  auto* tsdf = map.store().layerData<rm_tsdf_voxel>(*slot, map.tsdfLayer());
  tsdf[static_cast<std::uint32_t>(local.x + n * (local.y + n * local.z))] = {distance, weight};
}

/// Every voxel of the box [lo, hi] set from `field` (metres at the voxel centre), weight 1.
template <typename Field>
void fillBox(VoxelMap& map, Vec3i lo, Vec3i hi, Field field) {
  for (std::int32_t z = lo.z; z <= hi.z; ++z) {
    for (std::int32_t y = lo.y; y <= hi.y; ++y) {
      for (std::int32_t x = lo.x; x <= hi.x; ++x) {
        const Vec3i voxel{x, y, z};
        setVoxel(map, voxel, field(voxel), 1.0f);
      }
    }
  }
}

struct Topology {
  std::size_t open_edges = 0;      // used by one triangle only
  std::size_t overused_edges = 0;  // used by more than two
  std::size_t miswound_edges = 0;  // used twice in the same direction
  std::size_t degenerate = 0;      // triangles with a repeated vertex
};

Topology topologyOf(const TsdfMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> undirected;
  Topology topology;
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      ++topology.degenerate;
    }
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k];
      const std::uint32_t b = t[(k + 1) % 3];
      ++directed[{a, b}];
      ++undirected[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (const auto& [edge, count] : directed) {
    topology.miswound_edges += count > 1 ? 1u : 0u;
  }
  for (const auto& [edge, count] : undirected) {
    topology.open_edges += count == 1 ? 1u : 0u;
    topology.overused_edges += count > 2 ? 1u : 0u;
  }
  return topology;
}

TEST(MarchingCubesTable, EachCaseUsesExactlyItsCrossedEdges) {
  const auto& edges = cubeEdges();
  for (unsigned mask = 0; mask < 256u; ++mask) {
    std::set<int> crossed;
    for (int e = 0; e < kCubeEdges; ++e) {
      const CubeEdge& edge = edges[static_cast<std::size_t>(e)];
      if (((mask >> edge.lower) & 1u) != ((mask >> edge.upper()) & 1u)) {
        crossed.insert(e);
      }
    }
    const CubeCase& cube = marchingCubesCase(mask);
    std::set<int> used;
    for (std::uint8_t t = 0; t < cube.triangle_count; ++t) {
      const auto& tri = cube.triangles[t];
      EXPECT_TRUE(tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) << mask;
      used.insert(tri.begin(), tri.end());
    }
    EXPECT_EQ(used, crossed) << "case " << mask;
    // Triangles = crossed edges - 2 per loop, at least one loop when any edge is crossed.
    EXPECT_LE(cube.triangle_count + 2u, std::max<std::size_t>(crossed.size(), 2u)) << mask;
  }
}

TEST(MarchingCubesTable, ATriangleRoundOneInsideCornerFacesAwayFromIt) {
  const auto& edges = cubeEdges();
  for (unsigned corner = 0; corner < 8u; ++corner) {
    for (const unsigned mask : {1u << corner, 0xFFu & ~(1u << corner)}) {
      const CubeCase& cube = marchingCubesCase(mask);
      ASSERT_EQ(cube.triangle_count, 1u) << mask;
      std::array<Vec3d, 3> p{};
      for (std::size_t k = 0; k < 3; ++k) {
        const CubeEdge& e = edges[cube.triangles[0][k]];
        const auto at = [](unsigned c) {
          return Vec3d{double(c & 1u), double((c >> 1) & 1u), double((c >> 2) & 1u)};
        };
        p[k] = (at(e.lower) + at(e.upper())) * 0.5;
      }
      const Vec3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
      const Vec3d lone{double(corner & 1u), double((corner >> 1) & 1u), double((corner >> 2) & 1u)};
      // Inside corner alone: the normal points away from it; outside corner alone: towards it.
      const double towards = normal.dot(lone - p[0]);
      EXPECT_TRUE(mask == (1u << corner) ? towards < 0.0 : towards > 0.0) << mask;
    }
  }
}

TEST(TsdfMesh, ARandomFieldGivesAClosedConsistentlyWoundSurfaceThroughTheZeroCrossings) {
  VoxelMap map = test::makeMap(test::tsdfConfig());
  // A 30^3 block across region faces (16^3 regions) and the origin, every case of the table
  // many times over; its outer shell is positive, so the surface closes inside it.
  const Vec3i lo{-13, -7, -20};
  const Vec3i hi{16, 22, 9};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> value(-0.1f, 0.1f);
  fillBox(map, lo, hi, [&](Vec3i v) {
    const bool shell =
        v.x == lo.x || v.y == lo.y || v.z == lo.z || v.x == hi.x || v.y == hi.y || v.z == hi.z;
    const float d = value(rng);
    return shell ? 0.05f + std::fabs(d) : (d == 0.0f ? 0.01f : d);
  });
  const TsdfMesh mesh = tsdfMesh(map, 1.0f);
  ASSERT_GT(mesh.triangles.size(), 10000u);
  const Topology topology = topologyOf(mesh);
  EXPECT_EQ(topology.open_edges, 0u);
  EXPECT_EQ(topology.overused_edges, 0u);
  EXPECT_EQ(topology.miswound_edges, 0u);
  EXPECT_EQ(topology.degenerate, 0u);
  // The vertices are the zero crossings, each once.
  std::set<std::tuple<double, double, double>> crossings;
  for (const TsdfSurfacePoint& p : tsdfZeroCrossings(map, 1.0f)) {
    crossings.insert({p.p_world.x, p.p_world.y, p.p_world.z});
  }
  std::set<std::tuple<double, double, double>> vertices;
  for (const Vec3d& v : mesh.vertices) {
    vertices.insert({v.x, v.y, v.z});
  }
  EXPECT_EQ(vertices.size(), mesh.vertices.size());
  EXPECT_EQ(vertices, crossings);
  ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
  ASSERT_EQ(mesh.weights.size(), mesh.vertices.size());
}

// The exact signed distance of a sphere of radius 0.8 m off the grid, truncated.
struct Sphere {
  Vec3d centre{0.137, -0.211, 0.093};
  double radius = 0.8;
  float at(const VoxelMap& map, Vec3i v) const {
    const double d = (map.voxelCentre(v) - centre).norm() - radius;
    return static_cast<float>(std::clamp(d, -kTau, kTau));
  }
};

TEST(TsdfMesh, AnExactSpheresMeshIsClosedOnTheSphereAndFacesOutwards) {
  VoxelMap map = test::makeMap(test::tsdfConfig());
  const Sphere sphere;
  fillBox(map, {-12, -12, -12}, {12, 12, 12}, [&](Vec3i v) { return sphere.at(map, v); });
  const TsdfMesh mesh = tsdfMesh(map, 1.0f);
  const Topology topology = topologyOf(mesh);
  EXPECT_EQ(topology.open_edges, 0u);
  EXPECT_EQ(topology.overused_edges, 0u);
  EXPECT_EQ(topology.miswound_edges, 0u);
  double worst = 0.0;
  for (const Vec3d& v : mesh.vertices) {
    worst = std::max(worst, std::fabs((v - sphere.centre).norm() - sphere.radius));
  }
  double area = 0.0;
  std::size_t inward = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3d n = normalOf(mesh, t);
    area += 0.5 * n.norm();
    inward += n.dot(mesh.vertices[t[0]] - sphere.centre) <= 0.0 ? 1u : 0u;
  }
  double worst_normal = 1.0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3d radial = mesh.vertices[i] - sphere.centre;
    worst_normal = std::min(worst_normal, mesh.normals[i].dot(radial * (1.0 / radial.norm())));
  }
  const double true_area = 4.0 * std::numbers::pi * sphere.radius * sphere.radius;
  std::printf(
      "exact sphere: %zu triangles, %zu vertices, worst %.4f voxel off, area %.4f of "
      "the sphere's, worst vertex normal . radial %.3f\n",
      mesh.triangles.size(), mesh.vertices.size(), worst / kMeshResolution, area / true_area,
      worst_normal);
  EXPECT_LE(worst / kMeshResolution, 0.25);
  EXPECT_NEAR(area / true_area, 1.0, 0.02);
  EXPECT_EQ(inward, 0u);
  EXPECT_GT(worst_normal, 0.9);
}

TEST(TsdfMesh, ASimulatedSpheresMeshIsWithinAQuarterVoxelAndFacesOutwards) {
  const test::TsdfScene scene = test::sphereScene(12000);
  VoxelMap map = test::makeMap(test::tsdfConfig());
  auto backend = test::cpuBackend(map, 2);
  test::integrate(map, *backend, scene.rays);
  // The weight the surface checks of test_tsdf_map.cpp use: single rays' distances are off by
  // the voxel's offset from the ray times the incidence's tangent, and average out.
  const TsdfMesh mesh = tsdfMesh(map, 50.0f);
  ASSERT_GT(mesh.triangles.size(), 500u);
  double worst = 0.0;
  for (const Vec3d& v : mesh.vertices) {
    worst = std::max(worst, std::fabs(scene.truth(v)));
  }
  std::size_t outward = 0;
  for (const auto& t : mesh.triangles) {
    // Outwards: along the gradient of the true distance at the triangle's first vertex.
    const Vec3d p = mesh.vertices[t[0]];
    const double h = 1e-4;
    const Vec3d gradient{scene.truth(p + Vec3d{h, 0, 0}) - scene.truth(p - Vec3d{h, 0, 0}),
                         scene.truth(p + Vec3d{0, h, 0}) - scene.truth(p - Vec3d{0, h, 0}),
                         scene.truth(p + Vec3d{0, 0, h}) - scene.truth(p - Vec3d{0, 0, h})};
    outward += normalOf(mesh, t).dot(gradient) > 0.0 ? 1u : 0u;
  }
  std::printf("simulated sphere: %zu triangles, worst vertex %.3f voxel off, %zu outward\n",
              mesh.triangles.size(), worst / kMeshResolution, outward);
  EXPECT_LE(worst / kMeshResolution, 0.25);
  EXPECT_GE(outward, mesh.triangles.size() * 99 / 100);
}

TEST(TsdfMesh, CubesWithALightVoxelAreLeftOut) {
  VoxelMap map = test::makeMap(test::tsdfConfig());
  const Sphere sphere;
  fillBox(map, {-12, -12, -12}, {12, 12, 12}, [&](Vec3i v) { return sphere.at(map, v); });
  const std::size_t whole = tsdfMesh(map, 1.0f).triangles.size();
  // A voxel next to the surface, lighter than the minimum weight: the 8 cubes it is a corner of
  // are left out, which opens a hole round it.
  const Vec3i light = map.voxelOf(sphere.centre + Vec3d{sphere.radius, 0.0, 0.0});
  setVoxel(map, light, sphere.at(map, light), 0.5f);
  const TsdfMesh mesh = tsdfMesh(map, 1.0f);
  EXPECT_LT(mesh.triangles.size(), whole);
  const Topology topology = topologyOf(mesh);
  EXPECT_GT(topology.open_edges, 0u);
  EXPECT_EQ(topology.miswound_edges, 0u);
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t v : t) {
      // No vertex on an edge that ends at the light voxel: every such vertex is a full voxel
      // or more from the light voxel's centre, or not on one of its six edges' lines.
      const Vec3d d = mesh.vertices[v] - map.voxelCentre(light);
      const int off_axes =
          (std::fabs(d.x) > 1e-9) + (std::fabs(d.y) > 1e-9) + (std::fabs(d.z) > 1e-9);
      EXPECT_FALSE(off_axes <= 1 && d.norm() < kMeshResolution - 1e-9);
    }
  }
  // With the light voxel's weight accepted, the hole closes.
  EXPECT_EQ(tsdfMesh(map, 0.5f).triangles.size(), whole);
}

TEST(TsdfMesh, AJumpBetweenSaturatedDistancesIsNoSurface) {
  VoxelMap map = test::makeMap(test::tsdfConfig());
  const auto tau = static_cast<float>(kTau);
  // +tau above z = 0, -tau below: a sign change no ray measured (a thin wall seen from one side
  // and free space from the other).
  fillBox(map, {-4, -4, -4}, {4, 4, 4}, [&](Vec3i v) { return v.z >= 0 ? tau : -tau; });
  EXPECT_TRUE(tsdfMesh(map, 1.0f).triangles.empty());
  EXPECT_TRUE(tsdfZeroCrossings(map, 1.0f).empty());
  // The same step inside the band is a surface.
  fillBox(map, {-4, -4, -4}, {4, 4, 4}, [&](Vec3i v) { return v.z >= 0 ? 0.05f : -0.05f; });
  const TsdfMesh mesh = tsdfMesh(map, 1.0f);
  EXPECT_EQ(mesh.triangles.size(), 8u * 8u * 2u);
  for (const Vec3d& n : mesh.normals) {
    EXPECT_NEAR(n.z, 1.0, 1e-9);
  }
}

}  // namespace
}  // namespace raymap
