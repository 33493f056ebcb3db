// SPDX-License-Identifier: BSD-3-Clause
// Simulated scans of shapes with an exact signed distance.
#include "tests/support/tsdf_scenes.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Unit gradient of `truth` at p by central differences (the outward surface normal).
Vec3d gradient(const std::function<double(Vec3d)>& truth, Vec3d p) {
  constexpr double h = 1e-6;
  Vec3d g{truth(p + Vec3d{h, 0, 0}) - truth(p - Vec3d{h, 0, 0}),
          truth(p + Vec3d{0, h, 0}) - truth(p - Vec3d{0, h, 0}),
          truth(p + Vec3d{0, 0, h}) - truth(p - Vec3d{0, 0, h})};
  const double norm = g.norm();
  return norm > 0.0 ? g * (1.0 / norm) : g;
}

}  // namespace

MapConfig tsdfConfig(double max_weight) {
  MapConfig config = smallConfig(Semantics::kPerRay, 16).forTsdf();
  config.tsdf.max_weight = max_weight;
  config.memory_budget_bytes = std::uint64_t{1} << 30;
  return config;
}

TsdfComparison compareTsdf(const VoxelMap& a, const VoxelMap& b, double distance_m,
                           double weight_relative) {
  TsdfComparison result;
  std::set<std::tuple<int, int, int>> regions;
  a.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  b.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  for (const auto& [x, y, z] : regions) {
    for (std::uint32_t i = 0; i < a.store().voxelsPerRegion(); ++i) {
      const Vec3i voxel = a.voxelAt({x, y, z}, i);
      const rm_tsdf_voxel va = a.tsdf(voxel);
      const rm_tsdf_voxel vb = b.tsdf(voxel);
      if (va.weight == 0.0f && vb.weight == 0.0f) {
        continue;
      }
      ++result.updated;
      const double dd = std::fabs(double(va.distance) - double(vb.distance));
      const double dw = std::fabs(double(va.weight) - double(vb.weight));
      result.max_distance_difference = std::max(result.max_distance_difference, dd);
      result.max_weight_difference = std::max(result.max_weight_difference, dw);
      const double larger = std::max(double(va.weight), double(vb.weight));
      result.within += dd <= distance_m && dw <= weight_relative * larger + 1e-6 ? 1u : 0u;
    }
  }
  return result;
}

void shootAt(const std::function<double(Vec3d)>& truth, Vec3d origin, Vec3d lo, Vec3d hi, int rays,
             std::uint64_t seed, std::vector<Ray>* out) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < rays; ++i) {
    const Vec3d target{lo.x + (hi.x - lo.x) * unit(rng), lo.y + (hi.y - lo.y) * unit(rng),
                       lo.z + (hi.z - lo.z) * unit(rng)};
    Vec3d dir = target - origin;
    dir = dir * (1.0 / dir.norm());
    // Sphere tracing: each step is at most the distance to the surface, so it never passes it.
    double t = 0.0;
    bool hit = false;
    for (int step = 0; step < 2000 && t < 20.0; ++step) {
      const double d = truth(origin + dir * t);
      if (d < 1e-10) {
        hit = true;
        break;
      }
      t += d;
    }
    if (!hit) {
      continue;
    }
    const Vec3d sample = origin + dir * t;
    const Vec3d normal = gradient(truth, sample);
    const double cos_incidence = -(normal.x * dir.x + normal.y * dir.y + normal.z * dir.z);
    if (cos_incidence < 0.5) {
      continue;  // grazing: beyond 60 degrees
    }
    Ray ray;
    ray.origin = origin;
    ray.sample = sample;
    out->push_back(ray);
  }
}

TsdfScene planeScene(int rays_per_sensor, std::uint64_t seed) {
  TsdfScene scene;
  scene.name = "plane";
  constexpr double kHeight = 0.537;
  scene.truth = [](Vec3d p) { return p.z - kHeight; };
  int k = 0;
  for (const Vec3d origin : {Vec3d{-0.4, -0.3, 2.0}, Vec3d{0.45, -0.35, 2.1}, Vec3d{0.35, 0.4, 1.9},
                             Vec3d{-0.3, 0.45, 2.05}}) {
    shootAt(scene.truth, origin, {-1.0, -1.0, kHeight - 0.2}, {1.0, 1.0, kHeight - 0.1},
            rays_per_sensor, seed * 100 + static_cast<std::uint64_t>(k++), &scene.rays);
  }
  return scene;
}

TsdfScene sphereScene(int rays_per_sensor, std::uint64_t seed) {
  TsdfScene scene;
  scene.name = "sphere";
  const Vec3d centre{0.113, -0.047, 0.071};
  constexpr double kRadius = 0.8;
  scene.truth = [centre](Vec3d p) { return (p - centre).norm() - kRadius; };
  for (int k = 0; k < 8; ++k) {
    const double a = 2.0 * kPi * k / 8.0;
    const Vec3d origin = centre + Vec3d{2.5 * std::cos(a), 2.5 * std::sin(a), k % 2 ? 1.0 : -0.6};
    shootAt(scene.truth, origin, centre - Vec3d{1, 1, 1}, centre + Vec3d{1, 1, 1}, rays_per_sensor,
            seed * 100 + static_cast<std::uint64_t>(k), &scene.rays);
  }
  return scene;
}

TsdfScene boxScene(int rays_per_sensor, double edge_margin_m, std::uint64_t seed) {
  TsdfScene scene;
  scene.name = "box";
  const Vec3d centre{0.071, 0.033, 0.317};
  const Vec3d half{1.0, 0.8, 0.6};
  scene.truth = [centre, half](Vec3d p) {
    const Vec3d q{std::fabs(p.x - centre.x) - half.x, std::fabs(p.y - centre.y) - half.y,
                  std::fabs(p.z - centre.z) - half.z};
    const Vec3d outside{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
    return outside.norm() + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
  };
  scene.checked = [centre, half, edge_margin_m](Vec3d p) {
    // Near an edge: within the margin of the box's extent on two axes or more.
    int near = 0;
    for (int axis = 0; axis < 3; ++axis) {
      near += std::fabs(p[axis] - centre[axis]) > half[axis] - edge_margin_m ? 1 : 0;
    }
    return near < 2;
  };
  for (int k = 0; k < 8; ++k) {
    const double a = 2.0 * kPi * (k + 0.5) / 8.0;
    const Vec3d origin = centre + Vec3d{3.5 * std::cos(a), 3.5 * std::sin(a), k % 2 ? 2.0 : 0.9};
    shootAt(scene.truth, origin, centre - half * 1.2, centre + half * 1.2, rays_per_sensor,
            seed * 100 + static_cast<std::uint64_t>(k), &scene.rays);
  }
  return scene;
}

}  // namespace raymap::test
