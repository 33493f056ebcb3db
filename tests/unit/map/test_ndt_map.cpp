// SPDX-License-Identifier: BSD-3-Clause
// NDT-OM / NDT-TM maps on the CPU backend: a floor seen at grazing angles survives in NDT-OM and
// erodes in plain occupancy; a floor that has gone erodes in both; one worker or several give the
// same map bit for bit.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/cpu_backend.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

constexpr double kRes = 0.1;
constexpr double kFloorZ = 0.05;  // the middle of voxel layer z = 0
constexpr double kSensorZ = 0.3;

MapConfig configFor(MapMode mode) {
  MapConfig config = test::smallConfig(Semantics::kPerRay, 16);
  config.mode = mode;
  config.memory_budget_bytes = std::uint64_t{2} << 30;
  return config;
}

/// One scan of a sensor `kSensorZ` above a flat floor, moving along x: rays 1.5-3 degrees below
/// the horizon, so each crosses 10-19 floor voxels before it meets the floor (a surface seen at a
/// grazing angle). With `floor` false the floor has gone (a transient object, say a tarpaulin),
/// and the rays end 2 m further down instead.
std::vector<Ray> grazingScan(std::mt19937_64& rng, double sensor_x, bool floor) {
  std::uniform_real_distribution<double> elevation(-3.0, -1.5);
  std::uniform_real_distribution<double> azimuth(-10.0, 10.0);
  const Vec3d origin{sensor_x, 0.0, kSensorZ};
  std::vector<Ray> rays;
  for (int i = 0; i < 500; ++i) {
    const double el = elevation(rng) * M_PI / 180.0;
    const double az = azimuth(rng) * M_PI / 180.0;
    const Vec3d d{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
    const double t = ((floor ? kFloorZ : kFloorZ - 2.0) - origin.z) / d.z;
    rays.push_back(test::makeRay(origin, origin + d * t));
  }
  return rays;
}

/// Occupied voxels of the floor layer (z = 0) in the band the rays reach, x in [6, 10] m.
int occupiedFloor(const VoxelMap& map) {
  int occupied = 0;
  for (int x = 60; x < 100; ++x) {
    for (int y = -20; y <= 20; ++y) {
      occupied += map.state({x, y, 0}) == VoxelState::kOccupied ? 1 : 0;
    }
  }
  return occupied;
}

TEST(NdtMap, AFloorSeenAtGrazingAnglesSurvivesInNdtAndErodesInOccupancy) {
  VoxelMap occupancy = test::makeMap(configFor(MapMode::kOccupancy));
  VoxelMap ndt = test::makeMap(configFor(MapMode::kNdtOm));
  auto occupancy_backend = test::cpuBackend(occupancy, 1);
  auto ndt_backend = test::cpuBackend(ndt, 1);
  std::mt19937_64 rng(42);
  for (int scan = 0; scan < 40; ++scan) {
    const std::vector<Ray> rays = grazingScan(rng, 0.05 * scan, true);
    test::integrate(occupancy, *occupancy_backend, rays);
    test::integrate(ndt, *ndt_backend, rays);
  }
  // Same rays, same probabilities: each floor voxel takes about 10 plain misses per hit, which
  // wins over the hit in occupancy; in NDT-OM the rays pass above the floor's surfels.
  const int occ = occupiedFloor(occupancy);
  const int om = occupiedFloor(ndt);
  std::printf("occupied floor voxels: occupancy %d, NDT-OM %d of %d\n", occ, om, 40 * 41);
  EXPECT_GT(om, 400) << "NDT-OM keeps the floor";
  EXPECT_LT(occ * 2, om) << "plain occupancy erodes it (" << occ << " vs " << om << ")";
  // The floor's Gaussians are flat and at the floor's height.
  int flat = 0;
  int with_gaussian = 0;
  for (int x = 60; x < 100; ++x) {
    const rm_ndt_voxel g = ndt.ndt({x, 0, 0});
    if (g.count < 4) {
      continue;
    }
    ++with_gaussian;
    float p[6];
    rm_ndt_covariance(g.s, p);
    EXPECT_NEAR(double(g.mean_z) * kRes, kFloorZ, 0.002) << "x = " << x;
    flat += p[5] < 0.01f * (p[0] + p[2]) ? 1 : 0;
  }
  EXPECT_GT(with_gaussian, 30);
  EXPECT_EQ(flat, with_gaussian);

  // The floor goes: the rays now cross its surfels and erode them in NDT-OM too.
  for (int scan = 0; scan < 40; ++scan) {
    test::integrate(ndt, *ndt_backend, grazingScan(rng, 0.05 * scan, false));
  }
  EXPECT_LT(occupiedFloor(ndt) * 20, om) << "a floor that has gone is cleared";
}

/// Whether `a` and `b` hold the same regions with the same bytes in layer `layer` (compared in
/// place, region by region: copying every layer out cost these tests most of their time).
bool sameLayerBytes(const VoxelMap& a, const VoxelMap& b, int layer) {
  const RegionStore& sa = a.store();
  const RegionStore& sb = b.store();
  const std::size_t bytes =
      std::size_t{sa.schema().at(layer).bytes_per_voxel} * a.geometry().voxelsPerRegion();
  std::size_t regions_a = 0;
  bool same = true;
  sa.forEachRegion([&](std::uint32_t slot, Vec3i region) {
    ++regions_a;
    const std::uint32_t other = sb.find(region);
    same = same && other != RegionStore::kNoSlot &&
           std::memcmp(sa.layerData<std::byte>(slot, layer), sb.layerData<std::byte>(other, layer),
                       bytes) == 0;
  });
  std::size_t regions_b = 0;
  sb.forEachRegion([&](std::uint32_t, Vec3i) { ++regions_b; });
  return same && regions_a == regions_b;
}

class NdtThreads : public ::testing::TestWithParam<MapMode> {};

TEST_P(NdtThreads, OneWorkerOrSeveralGiveTheSameMapBitForBit) {
  const std::vector<Ray> rays = test::randomScans(17, 4, 3000);
  VoxelMap serial = test::makeMap(configFor(GetParam()));
  VoxelMap parallel = test::makeMap(configFor(GetParam()));
  auto one = test::cpuBackend(serial, 1);
  auto four = test::cpuBackend(parallel, 4);
  test::integrate(serial, *one, rays);
  test::integrate(parallel, *four, rays);
  const test::MapComparison cmp = test::compareMaps(serial, parallel);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
  for (int layer = 0; layer < serial.store().schema().size(); ++layer) {
    EXPECT_TRUE(sameLayerBytes(serial, parallel, layer)) << "layer " << layer;
  }
}

INSTANTIATE_TEST_SUITE_P(Modes, NdtThreads, ::testing::Values(MapMode::kNdtOm, MapMode::kNdtTm),
                         [](const ::testing::TestParamInfo<MapMode>& mode) {
                           return mode.param == MapMode::kNdtOm ? std::string("ndt_om")
                                                                : std::string("ndt_tm");
                         });

TEST(NdtMap, ConfigurationIsValidated) {
  MapConfig config = configFor(MapMode::kNdtOm);
  config.semantics = Semantics::kPerScan;
  auto refused = VoxelMap::create(config);
  ASSERT_FALSE(refused.has_value());
  EXPECT_NE(refused.error().message.find("per-ray"), std::string::npos) << refused.error().message;
  config = configFor(MapMode::kNdtTm);
  config.ndt.sensor_noise = -1.0;
  refused = VoxelMap::create(config);
  ASSERT_FALSE(refused.has_value());
  EXPECT_NE(refused.error().message.find("sensor-noise"), std::string::npos);
  // The layers each mode adds.
  EXPECT_TRUE(configFor(MapMode::kNdtOm).schema().has(LayerKind::kNdt));
  EXPECT_FALSE(configFor(MapMode::kNdtOm).schema().has(LayerKind::kHitMiss));
  EXPECT_TRUE(configFor(MapMode::kNdtTm).schema().has(LayerKind::kIntensity));
  EXPECT_FALSE(configFor(MapMode::kOccupancy).schema().has(LayerKind::kNdt));
}

}  // namespace
}  // namespace raymap
