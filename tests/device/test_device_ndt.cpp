// SPDX-License-Identifier: BSD-3-Clause
// NDT-OM and NDT-TM maps on a device backend: agreement with the CPU reference on generated
// scans of a room (voxel states, Gaussians, counts, intensity), and the square-root covariance of
// the samples of single voxels against an independent double-precision batch covariance for
// planar, collinear and spherical point sets. Written once; linked into one executable per GPU
// API (test_unit_opencl runs it on PoCL in CI; test_cuda_device on an NVIDIA GPU).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <random>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/ndt.h"
#include "src/device/staging/staged_backend.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

constexpr double kMinAgreement = 0.999;  // fraction of voxels in the same state / equal counts
constexpr double kMaxError = 1e-3;       // NDT means (voxel units), covariances (relative)
// Log-odds difference beyond which two occupancy values count as different: misses land on the
// device in another order, which moves a sum by rounding only; a plain miss instead of a shaped
// one moves it by up to 0.4.
constexpr float kValueTolerance = 1e-3f;
// Frobenius norm below which a covariance counts as zero when dividing (voxel units squared):
// (0.01 voxel)^2, a tenth of a millimetre in 0.1 m voxels. Covariances of one sample are zero.
constexpr double kCovarianceFloor = 1e-4;

MapConfig ndtConfig(MapMode mode) {
  MapConfig config = smallConfig(Semantics::kPerRay);
  config.mode = mode;
  config.voxel_mean = true;
  return config;
}

/// Scans of a closed room ([-2.5,2.5] x [-2.5,2.5] x [0,2.5] m) from random origins near its
/// centre: the returns lie on the floor, ceiling and walls with 1 cm range noise, so surface voxels
/// collect many samples and flat Gaussians, and shallow rays cross the Gaussians of the floor and
/// walls before they end. Intensity depends on the surface (plus noise); every 13th ray has no
/// return.
std::vector<Ray> roomScans(std::uint64_t seed, int scans, int rays_per_scan) {
  constexpr double kHalf = 2.5;    // metres
  constexpr double kHeight = 2.5;  // metres
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);  // metres
  std::normal_distribution<double> intensity_noise(0.0, 2.0);
  std::vector<Ray> rays;
  for (int s = 0; s < scans; ++s) {
    const Vec3d origin{u(rng), u(rng), 1.0 + 0.3 * u(rng)};
    for (int i = 0; i < rays_per_scan; ++i) {
      Vec3d d{u(rng), u(rng), 0.6 * u(rng)};
      d = d * (1.0 / d.norm());
      // Distance to the first wall along d: the smallest positive exit parameter of the box.
      double t = 1e9;
      std::size_t surface = 0;
      const std::array<double, 3> o{origin.x, origin.y, origin.z};
      const std::array<double, 3> v{d.x, d.y, d.z};
      const std::array<double, 3> lo{-kHalf, -kHalf, 0.0};
      const std::array<double, 3> hi{kHalf, kHalf, kHeight};
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (v[axis] != 0.0) {
          const double exit = ((v[axis] > 0 ? hi[axis] : lo[axis]) - o[axis]) / v[axis];
          if (exit < t) {
            t = exit;
            surface = axis;
          }
        }
      }
      t += noise(rng);
      const float intensity =
          static_cast<float>(20.0 + 30.0 * static_cast<double>(surface) + intensity_noise(rng));
      Ray ray = makeRay(origin, origin + d * t, (i % 13 == 0) ? kRayNoReturn : 0u,
                        static_cast<std::uint64_t>(s));
      ray.intensity = intensity;
      rays.push_back(ray);
    }
  }
  return rays;
}

/// Integrates one integrate() call per scan (one device batch each), then synchronises.
void integrateByScan(VoxelMap& map, Backend& backend, const std::vector<Ray>& rays) {
  std::size_t begin = 0;
  while (begin < rays.size()) {
    std::size_t end = begin;
    while (end < rays.size() && rays[end].scan == rays[begin].scan) {
      ++end;
    }
    test::integrate(map, backend, std::span<const Ray>(rays).subspan(begin, end - begin));
    begin = end;
  }
  ASSERT_TRUE(backend.synchronise());
}

/// Packed P = S S^T in double (same packing as rm_ndt_voxel::s).
std::array<double, 6> covariance(const rm_ndt_voxel& v) {
  float p[6];
  rm_ndt_covariance(v.s, p);
  return {double(p[0]), double(p[1]), double(p[2]), double(p[3]), double(p[4]), double(p[5])};
}

/// Frobenius norm of a packed symmetric 3x3 matrix (off-diagonal entries count twice).
double frobenius(const std::array<double, 6>& p) {
  return std::sqrt(p[0] * p[0] + p[2] * p[2] + p[5] * p[5] +
                   2.0 * (p[1] * p[1] + p[3] * p[3] + p[4] * p[4]));
}

double relativeCovarianceError(const std::array<double, 6>& reference,
                               const std::array<double, 6>& other) {
  std::array<double, 6> difference{};
  for (std::size_t k = 0; k < 6; ++k) {
    difference[k] = other[k] - reference[k];
  }
  return frobenius(difference) / std::max(frobenius(reference), kCovarianceFloor);
}

/// NDT layers of two maps, voxel by voxel over the union of their regions.
struct NdtComparison {
  std::uint64_t observed = 0;          ///< voxels observed in both maps
  std::uint64_t value_outliers = 0;    ///< of those: occupancy beyond kValueTolerance
  std::uint64_t with_gaussian = 0;     ///< voxels with samples in either map
  std::uint64_t count_equal = 0;       ///< of those: equal sample counts
  std::uint64_t beyond_tolerance = 0;  ///< equal counts, mean or covariance beyond kMaxError
  double max_mean_error = 0.0;         ///< voxel units
  double max_covariance_error = 0.0;   ///< relative Frobenius
  std::uint64_t shaping = 0;           ///< reference voxels whose Gaussian shapes misses
  // NDT-TM
  std::uint64_t with_counts = 0;  ///< voxels with a hit or miss count in either map
  std::uint64_t hit_miss_equal = 0;
  std::uint64_t reference_misses = 0;  ///< sum of the reference's miss counts
  std::uint64_t intensity_beyond = 0;  ///< equal counts, intensity mean or variance beyond 1e-3
};

NdtComparison compareNdt(const VoxelMap& reference, const VoxelMap& map) {
  NdtComparison result;
  std::set<std::tuple<int, int, int>> regions;
  reference.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  map.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  const std::uint32_t n = map.store().voxelsPerRegion();
  const bool tm = map.mode() == MapMode::kNdtTm;
  for (const auto& [x, y, z] : regions) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const Vec3i voxel = map.voxelAt({x, y, z}, i);
      if (reference.state(voxel) != VoxelState::kUnobserved &&
          map.state(voxel) != VoxelState::kUnobserved) {
        ++result.observed;
        result.value_outliers +=
            std::fabs(reference.occupancyValue(voxel) - map.occupancyValue(voxel)) > kValueTolerance
                ? 1u
                : 0u;
      }
      const rm_ndt_voxel a = reference.ndt(voxel);
      const rm_ndt_voxel b = map.ndt(voxel);
      if (tm) {
        const rm_ndt_hit_miss ca = reference.hitMiss(voxel);
        const rm_ndt_hit_miss cb = map.hitMiss(voxel);
        if (ca.hit + ca.miss + cb.hit + cb.miss != 0) {
          ++result.with_counts;
          result.hit_miss_equal += (ca.hit == cb.hit && ca.miss == cb.miss) ? 1u : 0u;
          result.reference_misses += ca.miss;
        }
      }
      if (a.count == 0 && b.count == 0) {
        continue;
      }
      ++result.with_gaussian;
      result.shaping += a.count >= NdtParams::kDefaultSampleThreshold ? 1u : 0u;
      if (a.count != b.count) {
        continue;
      }
      ++result.count_equal;
      const double mean_error = std::max({std::fabs(double(a.mean_x) - double(b.mean_x)),
                                          std::fabs(double(a.mean_y) - double(b.mean_y)),
                                          std::fabs(double(a.mean_z) - double(b.mean_z))});
      const double covariance_error = relativeCovarianceError(covariance(a), covariance(b));
      result.max_mean_error = std::max(result.max_mean_error, mean_error);
      result.max_covariance_error = std::max(result.max_covariance_error, covariance_error);
      result.beyond_tolerance += (mean_error > kMaxError || covariance_error > kMaxError) ? 1u : 0u;
      if (tm) {
        const rm_ndt_intensity ia = reference.intensity(voxel);
        const rm_ndt_intensity ib = map.intensity(voxel);
        const double mean_scale = std::max(std::fabs(double(ia.mean)), 1.0);
        const double variance_scale = std::max(std::fabs(double(ia.variance)), 1.0);
        result.intensity_beyond +=
            (std::fabs(double(ia.mean) - double(ib.mean)) > kMaxError * mean_scale ||
             std::fabs(double(ia.variance) - double(ib.variance)) > kMaxError * variance_scale)
                ? 1u
                : 0u;
      }
    }
  }
  return result;
}

/// The agreement AgreesWithTheCpuReferenceOnRoomScans asks for, of the host map after a
/// synchronisation.
void expectAgreement(const VoxelMap& reference, const VoxelMap& map, MapMode mode,
                     const char* when) {
  const MapComparison states = compareMaps(reference, map);
  const NdtComparison ndt = compareNdt(reference, map);
  EXPECT_GE(states.sameStateFraction(), kMinAgreement) << when;
  EXPECT_GT(ndt.shaping, 1000u) << when;
  EXPECT_LE(double(ndt.value_outliers), (1.0 - kMinAgreement) * double(ndt.observed)) << when;
  EXPECT_GE(double(ndt.count_equal), kMinAgreement * double(ndt.with_gaussian)) << when;
  EXPECT_EQ(ndt.beyond_tolerance, 0u) << when;
  if (mode == MapMode::kNdtTm) {  // the misses-only pass counts passes too
    EXPECT_GE(double(ndt.hit_miss_equal), kMinAgreement * double(ndt.with_counts)) << when;
    EXPECT_EQ(ndt.intensity_beyond, 0u) << when;
  }
}

class DeviceNdt : public testing::TestWithParam<MapMode> {};

TEST_P(DeviceNdt, AgreesWithTheCpuReferenceOnRoomScans) {
  REQUIRE_DEVICE();
  // Arrange
  const MapMode mode = GetParam();
  const std::vector<Ray> rays = roomScans(20240611, 12, 10000);
  VoxelMap reference = makeMap(ndtConfig(mode));
  auto cpu = cpuBackend(reference, 1);
  integrateByScan(reference, *cpu, rays);
  for (DeviceMemory memory : {DeviceMemory::kCache, DeviceMemory::kShared}) {
    if (memory == DeviceMemory::kShared && !deviceUnderTest().shares_memory()) {
      continue;
    }
    VoxelMap map = makeMap(ndtConfig(mode));
    DeviceBackendOptions options;
    options.memory = memory;
    auto device = createDeviceBackend(map, options);
    ASSERT_TRUE(device);

    // Act
    integrateByScan(map, *device, rays);
    const MapComparison states = compareMaps(reference, map);
    const NdtComparison ndt = compareNdt(reference, map);
    const BackendStats stats = device->stats();

    // Report
    const std::string label = std::string(toString(mode)) +
                              (memory == DeviceMemory::kCache ? ", region cache" : ", shared");
    char line[640];
    std::snprintf(
        line, sizeof(line),
        "%s %s: states agree %.4f %% of %llu voxels, values beyond 1e-3 %llu of %llu; Gaussians "
        "%llu (%llu shaping), "
        "counts equal %.4f %%, beyond 1e-3 %llu, max mean error %.3g voxel, max "
        "covariance error %.3g; hit/miss equal %.4f %% of %llu (reference misses %llu), "
        "intensity beyond %llu; dropped %llu",
        deviceUnderTest().api, label.c_str(), 100.0 * states.sameStateFraction(),
        static_cast<unsigned long long>(states.compared),
        static_cast<unsigned long long>(ndt.value_outliers),
        static_cast<unsigned long long>(ndt.observed),
        static_cast<unsigned long long>(ndt.with_gaussian),
        static_cast<unsigned long long>(ndt.shaping),
        100.0 * double(ndt.count_equal) / double(std::max<std::uint64_t>(ndt.with_gaussian, 1)),
        static_cast<unsigned long long>(ndt.beyond_tolerance), ndt.max_mean_error,
        ndt.max_covariance_error,
        100.0 * double(ndt.hit_miss_equal) / double(std::max<std::uint64_t>(ndt.with_counts, 1)),
        static_cast<unsigned long long>(ndt.with_counts),
        static_cast<unsigned long long>(ndt.reference_misses),
        static_cast<unsigned long long>(ndt.intensity_beyond),
        static_cast<unsigned long long>(stats.updates_dropped));
    std::cout << "[device-ndt] " << line << std::endl;

    // Assert
    EXPECT_GT(states.compared, 50000u) << label;
    EXPECT_GT(ndt.shaping, 5000u) << label << ": too few Gaussians shape misses to test them";
    EXPECT_GE(states.sameStateFraction(), kMinAgreement) << label;
    EXPECT_LE(double(ndt.value_outliers), (1.0 - kMinAgreement) * double(ndt.observed)) << label;
    EXPECT_GE(double(ndt.count_equal), kMinAgreement * double(ndt.with_gaussian)) << label;
    EXPECT_EQ(ndt.beyond_tolerance, 0u) << label << ": max mean error " << ndt.max_mean_error
                                        << ", max covariance error " << ndt.max_covariance_error;
    if (mode == MapMode::kNdtTm) {
      EXPECT_GT(ndt.reference_misses, 1000u) << label;
      EXPECT_GE(double(ndt.hit_miss_equal), kMinAgreement * double(ndt.with_counts)) << label;
      EXPECT_EQ(ndt.intensity_beyond, 0u) << label;
    }
    EXPECT_EQ(stats.updates_dropped, 0u) << label;
    EXPECT_EQ(stats.rays_skipped, 0u) << label;
  }
}

TEST_P(DeviceNdt, ASynchronisationWithoutNewSamplesDownloadsNoSampleLayer) {
  REQUIRE_DEVICE();
  // Arrange: a room mapped and synchronised, then rays without returns through it (misses only,
  // in regions that hold Gaussians), then more scans with returns; the CPU gets the same calls.
  const MapMode mode = GetParam();
  const std::vector<Ray> first = roomScans(20261128, 6, 10000);
  std::vector<Ray> misses_only = roomScans(20261129, 4, 10000);
  for (Ray& ray : misses_only) {
    ray.flags |= kRayNoReturn;
  }
  const std::vector<Ray> more = roomScans(20261130, 4, 10000);
  VoxelMap reference = makeMap(ndtConfig(mode));
  auto cpu = cpuBackend(reference, 1);
  VoxelMap map = makeMap(ndtConfig(mode));
  DeviceBackendOptions options;
  options.memory = DeviceMemory::kCache;
  auto device = createDeviceBackend(map, options);
  ASSERT_TRUE(device);
  // Bytes of a region's layers without and with the sample layers (voxel means, Gaussians,
  // NDT-TM's intensities).
  const RegionStore& store = map.store();
  std::uint64_t bytes_without_samples = 0;
  std::uint64_t sample_bytes = 0;
  for (int l = 0; l < store.schema().size(); ++l) {
    (gpu::sampleLayer(store.schema().at(l).kind) ? sample_bytes : bytes_without_samples) +=
        store.layerRegionBytes(l);
  }

  // Act and assert, pass by pass.
  integrateByScan(reference, *cpu, first);
  integrateByScan(map, *device, first);
  const std::uint64_t before_misses = device->stats().region_bytes_from_device;
  const std::uint64_t regions_before = store.size();
  integrateByScan(reference, *cpu, misses_only);
  integrateByScan(map, *device, misses_only);
  const std::uint64_t misses_download = device->stats().region_bytes_from_device - before_misses;
  // Every region at most once, and only the regions the pass created (cleared on the device:
  // every layer new) with their sample layers.
  const std::uint64_t created = store.size() - regions_before;
  EXPECT_GT(misses_download, 0u) << "the misses changed the occupancy of resident regions";
  EXPECT_LE(misses_download, store.size() * bytes_without_samples + created * sample_bytes)
      << "a region with no new sample was downloaded with its sample layers";
  expectAgreement(reference, map, mode, "after the misses-only pass");
  integrateByScan(reference, *cpu, more);
  integrateByScan(map, *device, more);
  expectAgreement(reference, map, mode, "after more scans");
  EXPECT_EQ(device->stats().updates_dropped, 0u);
}

INSTANTIATE_TEST_SUITE_P(Modes, DeviceNdt, testing::Values(MapMode::kNdtOm, MapMode::kNdtTm),
                         [](const testing::TestParamInfo<MapMode>& param_info) {
                           return param_info.param == MapMode::kNdtOm ? std::string("NdtOm")
                                                                      : std::string("NdtTm");
                         });

// ---- single voxels against a double-precision batch covariance ----

enum class PointSet { kPlanar, kLinear, kSpherical };

/// `count` points in voxel units inside the unit voxel, around its centre.
std::vector<std::array<double, 3>> pointSet(PointSet shape, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::array<double, 3>> points;
  // A tilted plane (normal (1, 0.5, 2)) and a tilted line (direction (1, 2, 0.5)).
  const std::array<double, 3> e1{0.8944271909999159, -0.4472135954999579, 0.0};
  const std::array<double, 3> e2{0.3651483716701107, 0.7302967433402214, -0.5477225575051661};
  const std::array<double, 3> line{0.4364357804719848, 0.8728715609439696, 0.2182178902359924};
  while (static_cast<int>(points.size()) < count) {
    const double a = u(rng);
    const double b = u(rng);
    const double c = u(rng);
    std::array<double, 3> p{};
    switch (shape) {
      case PointSet::kPlanar:
        for (std::size_t k = 0; k < 3; ++k) {
          p[k] = 0.5 + 0.3 * (a * e1[k] + b * e2[k]);
        }
        break;
      case PointSet::kLinear:
        for (std::size_t k = 0; k < 3; ++k) {
          p[k] = 0.5 + 0.4 * a * line[k];
        }
        break;
      case PointSet::kSpherical:
        if (a * a + b * b + c * c > 1.0) {
          continue;  // rejection: uniform in the ball
        }
        p = {0.5 + 0.4 * a, 0.5 + 0.4 * b, 0.5 + 0.4 * c};
        break;
    }
    points.push_back(p);
  }
  return points;
}

const char* toString(PointSet shape) {
  return shape == PointSet::kPlanar   ? "planar"
         : shape == PointSet::kLinear ? "linear"
                                      : "spherical";
}

class DeviceNdtVoxel : public testing::TestWithParam<PointSet> {};

TEST_P(DeviceNdtVoxel, SquareRootCovarianceMatchesTheBatchCovariance) {
  REQUIRE_DEVICE();
  // Arrange: every ray ends in voxel `key`, from four origins about 2 m away, in batches of 100.
  constexpr int kSamples = 300;
  const PointSet shape = GetParam();
  const MapConfig config = ndtConfig(MapMode::kNdtTm);
  const double resolution = config.geometry.resolution;
  const Vec3i key{12, 7, 3};
  const std::vector<std::array<double, 3>> points = pointSet(shape, kSamples, 77);
  const std::array<Vec3d, 4> origins{Vec3d{-0.5, -1.0, 2.0}, Vec3d{3.0, 0.2, 1.5},
                                     Vec3d{1.0, 2.5, -1.0}, Vec3d{2.2, -1.5, 0.8}};
  std::vector<Ray> rays;
  for (int i = 0; i < kSamples; ++i) {
    const auto& p = points[static_cast<std::size_t>(i)];
    const Vec3d sample{(key.x + p[0]) * resolution, (key.y + p[1]) * resolution,
                       (key.z + p[2]) * resolution};
    Ray ray = makeRay(origins[static_cast<std::size_t>(i) % origins.size()], sample, 0u,
                      static_cast<std::uint64_t>(i / 100));
    ray.intensity = 50.0f;
    rays.push_back(ray);
  }
  // The reference: mean and population covariance of the same points, in double.
  std::array<double, 3> mean{};
  for (const auto& p : points) {
    for (std::size_t k = 0; k < 3; ++k) {
      mean[k] += p[k] / kSamples;
    }
  }
  std::array<double, 6> expected{};  // packed like rm_ndt_voxel::s
  for (const auto& p : points) {
    const double d[3] = {p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]};
    std::size_t e = 0;
    for (std::size_t row = 0; row < 3; ++row) {
      for (std::size_t col = 0; col <= row; ++col) {
        expected[e++] += d[row] * d[col] / kSamples;
      }
    }
  }
  VoxelMap map = makeMap(config);
  auto device = createDeviceBackend(map);
  ASSERT_TRUE(device);
  VoxelMap reference = makeMap(config);
  auto cpu = cpuBackend(reference, 1);

  // Act
  integrateByScan(map, *device, rays);
  integrateByScan(reference, *cpu, rays);

  // Assert: the device, and the CPU reference as a check of the test itself.
  for (const VoxelMap* m : {&map, &reference}) {
    const char* who = m == &map ? deviceUnderTest().api : "CPU";
    const rm_ndt_voxel v = m->ndt(key);
    const double covariance_error = relativeCovarianceError(expected, covariance(v));
    const double mean_error =
        std::max({std::fabs(double(v.mean_x) - mean[0]), std::fabs(double(v.mean_y) - mean[1]),
                  std::fabs(double(v.mean_z) - mean[2])});
    std::cout << "[device-ndt] " << who << " " << toString(shape) << ": count " << v.count
              << ", relative covariance error " << covariance_error << ", mean error " << mean_error
              << " voxel" << std::endl;
    EXPECT_EQ(v.count, static_cast<std::uint32_t>(kSamples)) << who;
    EXPECT_LE(covariance_error, kMaxError) << who << " " << toString(shape);
    EXPECT_LE(mean_error, kMaxError) << who << " " << toString(shape);
  }
  EXPECT_EQ(device->stats().updates_dropped, 0u);
}

INSTANTIATE_TEST_SUITE_P(PointSets, DeviceNdtVoxel,
                         testing::Values(PointSet::kPlanar, PointSet::kLinear,
                                         PointSet::kSpherical),
                         [](const testing::TestParamInfo<PointSet>& param_info) {
                           return std::string(toString(param_info.param));
                         });

}  // namespace
}  // namespace raymap::test
