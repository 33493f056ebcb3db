// SPDX-License-Identifier: BSD-3-Clause
// Test helpers for maps and rays.
#include "tests/support/test_rays.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "kernels/common/decay.h"
#include "kernels/common/occupancy.h"
#include "src/io/ray_cloud_writer.hpp"
#include "src/map/cpu_backend.hpp"

namespace raymap::test {

Ray makeRay(Vec3d origin, Vec3d sample, std::uint32_t flags, std::uint64_t scan) {
  Ray ray;
  ray.origin = origin;
  ray.sample = sample;
  ray.flags = flags;
  ray.scan = scan;
  return ray;
}

VoxelMap makeMap(const MapConfig& config) {
  auto map = VoxelMap::create(config);
  if (!map) {
    ADD_FAILURE() << "map creation failed: " << map.error().message;
    std::abort();
  }
  return std::move(map).value();
}

std::unique_ptr<Backend> cpuBackend(VoxelMap& map, unsigned threads) {
  CpuBackendOptions options;
  options.threads = threads;
  auto backend = createCpuBackend(map, options);
  if (!backend) {
    ADD_FAILURE() << "backend creation failed: " << backend.error().message;
    std::abort();
  }
  return std::move(backend).value();
}

RayCounters integrate(VoxelMap& map, Backend& backend, std::span<const Ray> rays,
                      const RayFilter& filter) {
  RayPreparer preparer(map, filter);
  // Room for rays cut into up to 16 pieces each (segmentation in tests).
  std::vector<PreparedRay> prepared(rays.size() * 16 + 64);
  std::size_t begin = 0;
  while (begin < rays.size()) {
    std::size_t end = rays.size();
    if (map.semantics() == Semantics::kPerScan) {
      end = begin;
      while (end < rays.size() && rays[end].scan == rays[begin].scan) {
        ++end;
      }
    }
    const auto progress = preparer.prepare(rays.subspan(begin, end - begin), prepared);
    EXPECT_EQ(progress.consumed, end - begin);
    auto ok = backend.integrate(std::span<const PreparedRay>(prepared.data(), progress.written));
    EXPECT_TRUE(ok.has_value()) << toString(ok.error());
    begin = end;
  }
  return preparer.counters();
}

std::vector<Ray> cubeRoomRays(double resolution, int half) {
  // Sensor at the centre of voxel (0,0,0); targets at the centres of wall voxels with one
  // coordinate at +-half and the others strictly inside (-half, half). From the centre, such a
  // ray moves less than half a voxel sideways while it crosses the last half voxel of the wall
  // layer, so the wall voxel is the only wall voxel it touches.
  const Vec3d origin{0.5 * resolution, 0.5 * resolution, 0.5 * resolution};
  std::vector<Ray> rays;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side : {-half, half}) {
      for (int u = -half + 1; u <= half - 1; ++u) {
        for (int v = -half + 1; v <= half - 1; ++v) {
          int c[3];
          c[axis] = side;
          c[(axis + 1) % 3] = u;
          c[(axis + 2) % 3] = v;
          const Vec3d sample{(c[0] + 0.5) * resolution, (c[1] + 0.5) * resolution,
                             (c[2] + 0.5) * resolution};
          rays.push_back(makeRay(origin, sample));
        }
      }
    }
  }
  return rays;
}

void writeRayCloud(const std::string& path, const std::vector<Ray>& rays) {
  auto writer = io::RayCloudWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  ASSERT_TRUE((*writer)->write(rays).has_value());
  ASSERT_TRUE((*writer)->finish().has_value());
}

namespace {

constexpr double kHalfWidth = 3.0;  // corridor walls at y = +-3 m
constexpr double kCeiling = 2.5;    // floor at z = 0, ceiling at 2.5 m
constexpr double kMaxRange = 4.0;   // metres; farther: a no-return ray

}  // namespace

std::vector<Ray> corridorDrive(double length, double step) {
  std::vector<Ray> rays;
  std::uint64_t scan = 0;
  for (double x = 0.0; x <= length; x += step, ++scan) {
    const Vec3d origin{x, 0.05, 1.0};
    for (int e = 0; e < 8; ++e) {
      const double elevation = (-40.0 + 80.0 * e / 7.0) * M_PI / 180.0;
      for (int a = 0; a < 32; ++a) {
        const double azimuth = (2.0 * M_PI * a) / 32.0 + 0.013 * static_cast<double>(scan % 7);
        const Vec3d d{std::cos(elevation) * std::cos(azimuth),
                      std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
        double t = kMaxRange;
        if (d.y != 0.0) {
          t = std::min(t, ((d.y > 0 ? kHalfWidth : -kHalfWidth) - origin.y) / d.y);
        }
        if (d.z < 0.0) {
          t = std::min(t, -origin.z / d.z);
        } else if (d.z > 0.0) {
          t = std::min(t, (kCeiling - origin.z) / d.z);
        }
        // Crates: 1 m cubes against the walls every 10 m.
        const double next_crate = std::floor(x / 10.0) * 10.0 + 5.0;
        const double crate_y = static_cast<long>(next_crate / 10.0) % 2 == 0 ? 2.0 : -3.0;
        if (d.x != 0.0) {
          const double tc = (next_crate - origin.x) / d.x;
          const Vec3d p = origin + d * tc;
          if (tc > 0.0 && tc < t && p.y >= crate_y && p.y <= crate_y + 1.0 && p.z <= 1.0) {
            t = tc;
          }
        }
        Ray ray = makeRay(origin, origin + d * t, t >= kMaxRange ? kRayNoReturn : 0u, scan);
        ray.intensity = static_cast<float>(0.2 + 0.1 * (a % 5));
        rays.push_back(ray);
      }
    }
  }
  return rays;
}

void integrateEachScan(VoxelMap& map, Backend& backend, const std::vector<Ray>& rays) {
  std::size_t begin = 0;
  while (begin < rays.size()) {
    std::size_t end = begin;
    while (end < rays.size() && rays[end].scan == rays[begin].scan) {
      ++end;
    }
    integrate(map, backend, std::span<const Ray>(rays).subspan(begin, end - begin));
    begin = end;
  }
  ASSERT_TRUE(backend.synchronise().has_value());
}

MapConfig withTiers(MapConfig config, std::uint64_t regions, std::uint64_t compressed_bytes,
                    const std::string& spill_dir) {
  config.memory_budget_bytes =
      regions * config.schema().bytesPerRegion(config.geometry.voxelsPerRegion());
  config.tiers.enabled = true;
  config.tiers.compressed_bytes = compressed_bytes;
  config.tiers.spill_dir = spill_dir;
  return config;
}

Expected<void, IntegrateError> integrateUntilFailure(VoxelMap& map, Backend& backend,
                                                     const std::vector<Ray>& rays) {
  RayPreparer preparer(map, RayFilter{});
  std::vector<PreparedRay> prepared(rays.size() + 64);
  for (std::size_t begin = 0; begin < rays.size(); begin += 256) {
    const std::size_t n = std::min<std::size_t>(256, rays.size() - begin);
    const auto p = preparer.prepare(std::span<const Ray>(rays).subspan(begin, n), prepared);
    auto status = backend.integrate(std::span<const PreparedRay>(prepared.data(), p.written));
    if (!status) {
      return status;
    }
    (void)map.drainTiers();  // its failure is the next batch's
  }
  return {};
}

MapConfig smallConfig(Semantics semantics, std::int32_t region_voxels) {
  MapConfig c;
  c.semantics = semantics;
  c.geometry.region_voxels = region_voxels;
  c.memory_budget_bytes = 256u << 20;
  return c;
}

MapConfig decayConfig(Semantics semantics, MapMode mode, std::int32_t region_voxels) {
  MapConfig config = smallConfig(semantics, region_voxels);
  config.mode = mode;
  config.decay_rate = true;
  config.memory_budget_bytes = std::uint64_t{2} << 30;
  return config;
}

float decayRate(const VoxelMap& map, Vec3i voxel) {
  return rm_decay_rate(map.mean(voxel).count, map.traversal(voxel));
}

std::vector<Ray> randomScans(std::uint64_t seed, int scans, int rays_per_scan) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> range(0.2, 12.0);
  std::vector<Ray> rays;
  for (int s = 0; s < scans; ++s) {
    const Vec3d origin{u(rng) * 2, u(rng) * 2, u(rng) * 0.5};
    for (int i = 0; i < rays_per_scan; ++i) {
      Vec3d d{u(rng), u(rng), u(rng) * 0.4};
      d = d * (range(rng) / d.norm());
      rays.push_back(makeRay(origin, origin + d, (i % 17 == 0) ? kRayNoReturn : 0u,
                             static_cast<std::uint64_t>(s)));
    }
  }
  return rays;
}

std::vector<Ray> latticeRays(std::uint64_t seed, int count, double step, int stretch) {
  std::vector<Ray> rays;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> lattice(-40, 40);
  for (int i = 0; i < count; ++i) {
    const Vec3d a{lattice(rng) * step, lattice(rng) * step, lattice(rng) * step};
    const Vec3d b{lattice(rng) * stretch * step, lattice(rng) * stretch * step,
                  lattice(rng) * step};
    rays.push_back(makeRay(a, b));
  }
  return rays;
}

namespace {

/// The occupancy values of one region of `map`, or nullptr where the map has no such region (or no
/// occupancy layer). The point query first brings a spilled region of a tiered map back; the
/// pointer then stays valid until the next query to that map.
const float* regionOccupancy(const VoxelMap& map, const std::tuple<int, int, int>& region) {
  const auto& [rx, ry, rz] = region;
  const int n = map.geometry().region_voxels;
  // On a tiered map the query restores a spilled region; on any other it is one lookup.
  static_cast<void>(map.occupancyValue(Vec3i{rx * n, ry * n, rz * n}));
  const std::uint32_t slot = map.store().find(Vec3i{rx, ry, rz});
  if (slot == RegionStore::kNoSlot || map.occupancyLayer() < 0) {
    return nullptr;
  }
  return map.store().layerData<float>(slot, map.occupancyLayer());
}

}  // namespace

MapComparison compareMaps(const VoxelMap& a, const VoxelMap& b) {
  MapComparison result;
  const int n = a.geometry().region_voxels;
  if (n != b.geometry().region_voxels) {
    ADD_FAILURE() << "compareMaps compares maps of one region size (" << n << " and "
                  << b.geometry().region_voxels << " voxels)";
    return result;
  }
  std::set<std::tuple<int, int, int>> regions;
  a.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  b.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  // Region by region over the occupancy layers: a hash lookup per region, not per voxel (per
  // voxel, the lookups were most of these tests' time under the sanitizers).
  const std::size_t voxels =
      static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  for (const auto& region : regions) {
    const float* la = regionOccupancy(a, region);
    const float* lb = regionOccupancy(b, region);
    for (std::size_t i = 0; i < voxels; ++i) {
      const float va = la != nullptr ? la[i] : RM_OCC_UNOBSERVED;
      const float vb = lb != nullptr ? lb[i] : RM_OCC_UNOBSERVED;
      const VoxelState sa = a.stateOfValue(va);
      const VoxelState sb = b.stateOfValue(vb);
      if (sa == VoxelState::kUnobserved && sb == VoxelState::kUnobserved) {
        continue;
      }
      ++result.compared;
      result.same_state += sa == sb ? 1u : 0u;
      result.exact_value += std::memcmp(&va, &vb, sizeof(float)) == 0 ? 1u : 0u;
    }
  }
  return result;
}

}  // namespace raymap::test
