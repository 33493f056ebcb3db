// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper (the public API): it integrates exactly what the library's own path does, takes
// sensor-frame points with one pose or a pose per time, answers queries, makes height maps,
// saves and loads, reports errors as values and allocates nothing per scan.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "raymap/mapper.hpp"
#include "raymap/version.hpp"
#include <gtest/gtest.h>

#include "src/core/eigen_conversions.hpp"
#include "src/device/backend_choice.hpp"
#include "src/io/map_file.hpp"
#include "src/io/trajectory.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

std::vector<WorldRay> toWorldRays(std::span<const Ray> rays) {
  std::vector<WorldRay> out;
  for (const Ray& r : rays) {
    WorldRay w;
    w.origin = toEigen(r.origin);
    w.end = toEigen(r.sample);
    w.intensity = r.intensity;
    w.no_return = (r.flags & kRayNoReturn) != 0u;
    out.push_back(w);
  }
  return out;
}

MapperConfig smallMapper(Semantics semantics) {
  MapperConfig config;
  config.map.semantics = semantics;
  config.map.region_voxels = 8;
  config.map.max_memory_bytes = std::uint64_t{256} << 20;
  config.backend.threads = 1;
  return config;
}

/// The same rays through the library's internals (VoxelMap, CPU backend, RayPreparer), one scan
/// per run of Ray::scan: what `raymap populate` does.
VoxelMap referenceMap(const MapperConfig& config, std::span<const Ray> rays) {
  MapConfig map_config = test::smallConfig(config.map.semantics, config.map.region_voxels);
  map_config.memory_budget_bytes = config.map.max_memory_bytes;
  VoxelMap map = test::makeMap(map_config);
  auto backend = test::cpuBackend(map, 1);
  (void)test::integrate(map, *backend, rays);
  return map;
}

VoxelMap savedMap(Mapper& mapper, const test::TempDir& dir) {
  const std::string path = dir.file("mapper.rmap");
  auto saved = mapper.save(path);
  EXPECT_TRUE(saved) << (saved ? "" : saved.error().message);
  auto loaded = io::loadMap(path);
  EXPECT_TRUE(loaded) << (loaded ? "" : loaded.error().message);
  return std::move(*loaded);
}

class MapperSemantics : public ::testing::TestWithParam<Semantics> {};

TEST_P(MapperSemantics, IntegratesExactlyWhatTheLibraryPathDoes) {
  const std::vector<Ray> rays = test::randomScans(7, 6, 3000);
  const MapperConfig config = smallMapper(GetParam());
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  // One integrate() per scan, as a sensor driver would call it.
  std::size_t begin = 0;
  while (begin < rays.size()) {
    std::size_t end = begin;
    while (end < rays.size() && rays[end].scan == rays[begin].scan) {
      ++end;
    }
    const std::vector<WorldRay> scan = toWorldRays(std::span(rays).subspan(begin, end - begin));
    ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(scan)));
    begin = end;
  }
  ASSERT_TRUE(mapper->flush());
  test::TempDir dir;
  const VoxelMap ours = savedMap(*mapper, dir);
  const VoxelMap reference = referenceMap(config, rays);
  const test::MapComparison c = test::compareMaps(ours, reference);
  EXPECT_GT(c.compared, 1000u);
  EXPECT_EQ(c.exact_value, c.compared);
  const MapSummary expected = reference.summarise();
  const MapCounts counts = mapper->counts();
  EXPECT_EQ(counts.voxels_occupied, expected.voxels_occupied);
  EXPECT_EQ(counts.voxels_free, expected.voxels_free);
  const MapperCounters counters = mapper->counters();
  EXPECT_EQ(counters.scans, 6u);
  EXPECT_EQ(counters.rays_in, rays.size());
  EXPECT_EQ(counters.rays_pending, 0u);
}

INSTANTIATE_TEST_SUITE_P(Both, MapperSemantics,
                         ::testing::Values(Semantics::kPerRay, Semantics::kPerScan));

TEST(Mapper, WallIsOccupiedTheSpaceBeforeItFreeAndBehindItUnobserved) {
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper) << mapper.error().message;
  // A sensor at the origin looking at a wall at x = 4.05 m (the centre of voxel column 40).
  std::vector<SensorPoint> points;
  for (int j = -10; j <= 10; ++j) {
    for (int k = -10; k <= 10; ++k) {
      SensorPoint p;
      p.position = Eigen::Vector3d(4.05, 0.1 * j + 0.05, 0.1 * k + 0.05);
      points.push_back(p);
    }
  }
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(
        mapper->integrate(std::span<const SensorPoint>(points), Eigen::Isometry3d::Identity()));
  }
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(4.05, 0.05, 0.05)), VoxelState::kOccupied);
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(2.0, 0.05, 0.05)), VoxelState::kFree);
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(6.0, 0.05, 0.05)), VoxelState::kUnobserved);
  const std::optional<VoxelKey> key = mapper->key(Eigen::Vector3d(4.05, 0.05, 0.05));
  ASSERT_TRUE(key);
  EXPECT_EQ(*key, VoxelKey(40, 0, 0));
  EXPECT_TRUE(mapper->centre(*key).isApprox(Eigen::Vector3d(4.05, 0.05, 0.05)));
  const VoxelInfo info = mapper->voxel(*key);
  EXPECT_EQ(info.state, VoxelState::kOccupied);
  ASSERT_TRUE(info.probability);
  EXPECT_GT(*info.probability, 0.9);
  EXPECT_EQ(info.samples, 3u);
  ASSERT_TRUE(info.mean);
  EXPECT_NEAR(info.mean->x(), 4.05, 0.001);
  EXPECT_FALSE(mapper->voxel(VoxelKey(60, 0, 0)).probability);
  EXPECT_FALSE(mapper->key(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0)));
  EXPECT_EQ(mapper->counters().rays_integrated, 3u * points.size());
}

TEST(Mapper, VoxelsListsEveryVoxelOfAStateAsCountsCountsThem) {
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper) << mapper.error().message;
  // A 5 x 5 patch of a wall at x = 4.05 m seen from the origin, twice.
  std::vector<WorldRay> rays;
  for (int j = 0; j < 5; ++j) {
    for (int k = 0; k < 5; ++k) {
      WorldRay ray;
      ray.end = Eigen::Vector3d(4.05, 0.1 * j + 0.05, 0.1 * k + 0.05);
      rays.push_back(ray);
    }
  }
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());

  const Result<std::vector<VoxelKey>> occupied = mapper->voxels(VoxelState::kOccupied);
  const Result<std::vector<VoxelKey>> free = mapper->voxels(VoxelState::kFree);
  const Result<std::vector<VoxelKey>> unobserved = mapper->voxels(VoxelState::kUnobserved);

  ASSERT_TRUE(occupied) << occupied.error().message;
  ASSERT_TRUE(free) << free.error().message;
  const MapCounts counts = mapper->counts();
  ASSERT_EQ(occupied->size(), counts.voxels_occupied);
  EXPECT_EQ(free->size(), counts.voxels_free);
  EXPECT_EQ(occupied->size(), 25u);
  for (const VoxelKey& key : *occupied) {
    EXPECT_EQ(key.x(), 40);
    EXPECT_EQ(mapper->occupancy(key), VoxelState::kOccupied);
  }
  for (const VoxelKey& key : *free) {
    EXPECT_EQ(mapper->occupancy(key), VoxelState::kFree) << key.transpose();
  }
  ASSERT_FALSE(unobserved);
  EXPECT_EQ(unobserved.error().code, ErrorCode::kInvalidArgument);
}

TEST(Mapper, OnePoseIsTheSameAsWorldRaysFromThatPose) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(1.0, -2.0, 0.5));
  pose.rotate(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  std::vector<SensorPoint> points;
  std::vector<WorldRay> rays;
  for (int i = 0; i < 500; ++i) {
    SensorPoint p;
    const double a = 0.01 * i;
    p.position = Eigen::Vector3d(5.0 * std::cos(a), 5.0 * std::sin(a), 0.3 * std::sin(3 * a));
    p.no_return = i % 50 == 0;
    points.push_back(p);
    WorldRay r;
    r.origin = pose.translation();
    r.end = pose * p.position;
    r.no_return = p.no_return;
    rays.push_back(r);
  }
  auto a = Mapper::create(smallMapper(Semantics::kPerScan));
  auto b = Mapper::create(smallMapper(Semantics::kPerScan));
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(a->integrate(std::span<const SensorPoint>(points), pose));
  ASSERT_TRUE(b->integrate(std::span<const WorldRay>(rays)));
  test::TempDir dir;
  const VoxelMap map_a = savedMap(*a, dir);
  const VoxelMap map_b = savedMap(*b, dir);
  const test::MapComparison c = test::compareMaps(map_a, map_b);
  EXPECT_GT(c.compared, 100u);
  EXPECT_EQ(c.exact_value, c.compared);
  EXPECT_EQ(a->counters().rays_no_return, 10u);
}

TEST(Mapper, PosePerTimeDeskewsAndCountsPointsWithoutAPose) {
  // The sensor moves along x at 1 m/s; each point is 3 m ahead of where the sensor was at its
  // time, so every return lands in the same wall voxel column only if deskewed with its own pose.
  std::vector<SensorPoint> points;
  for (int i = 0; i < 100; ++i) {
    SensorPoint p;
    p.time_s = 0.01 * (i / 10);  // ten points per time
    p.position = Eigen::Vector3d(3.0, 0.05, 0.05);
    points.push_back(p);
  }
  SensorPoint late;
  late.time_s = 5.0;  // no pose then
  points.push_back(late);
  int calls = 0;
  const SensorPoseFunction pose_at = [&calls](double t) -> std::optional<Eigen::Isometry3d> {
    ++calls;
    if (t > 1.0) {
      return std::nullopt;
    }
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(t, 0.0, 0.0);
    return pose;
  };
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper);
  ASSERT_TRUE(mapper->integrate(std::span<const SensorPoint>(points), pose_at));
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(calls, 11);  // once per distinct time
  EXPECT_EQ(mapper->counters().points_no_pose, 1u);
  EXPECT_EQ(mapper->counters().rays_integrated, 100u);
  const VoxelInfo first = mapper->voxel(VoxelKey(30, 0, 0));
  const VoxelInfo last = mapper->voxel(VoxelKey(30, 0, 0));
  EXPECT_EQ(first.state, VoxelState::kOccupied);
  // Returns spread over 3.00-3.09 m: all in voxel 30, none in 31.
  EXPECT_EQ(first.samples, 100u);
  EXPECT_EQ(mapper->occupancy(VoxelKey(31, 0, 0)), VoxelState::kUnobserved);
  (void)last;
}

TEST(Mapper, BadOptionsAreErrorsThatNameTheOption) {
  MapperConfig config;
  config.map.resolution = -0.1;
  auto bad_resolution = Mapper::create(config);
  ASSERT_FALSE(bad_resolution);
  EXPECT_NE(bad_resolution.error().message.find("resolution"), std::string::npos)
      << bad_resolution.error().message;

  config = MapperConfig{};
  config.map.hit_probability = 1.5;
  auto bad_probability = Mapper::create(config);
  ASSERT_FALSE(bad_probability);
  EXPECT_NE(bad_probability.error().message.find("hit_probability"), std::string::npos);

  config = MapperConfig{};
  config.rays.min_range = -1.0;
  auto bad_range = Mapper::create(config);
  ASSERT_FALSE(bad_range);
  EXPECT_NE(bad_range.error().message.find("range"), std::string::npos)
      << bad_range.error().message;

  config = MapperConfig{};
  config.backend.name = "quantum";
  auto bad_backend = Mapper::create(config);
  ASSERT_FALSE(bad_backend);
  EXPECT_NE(bad_backend.error().message.find("quantum"), std::string::npos)
      << bad_backend.error().message;
}

// A library user never typed raymap's flags: errors name the option by its configuration key
// (backend.name, backend.fallback: cpu; raymap shows --backend, --fallback cpu).
TEST(Mapper, ErrorsNameConfigurationKeysNotCommandLineFlags) {
  MapperConfig config;
  config.backend.name = "quantum";
  auto unknown = Mapper::create(config);
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message,
            "backend.name: unknown backend 'quantum' (backend.fallback: cpu maps on the CPU "
            "instead)");

  // A device backend this build lacks (every build but one with both OpenCL and CUDA).
  const std::vector<std::string> built = backends::availableBackends();
  for (const std::string missing : {"cuda", "opencl"}) {
    if (std::find(built.begin(), built.end(), missing) != built.end()) {
      continue;
    }
    config.backend.name = missing;
    auto made = Mapper::create(config);
    ASSERT_FALSE(made);
    const std::string& message = made.error().message;
    EXPECT_EQ(message.rfind("backend.name: " + missing + ": this build has no ", 0), 0u) << message;
    EXPECT_NE(message.find("(backend.fallback: cpu maps on the CPU instead)"), std::string::npos)
        << message;
    EXPECT_EQ(message.find("--"), std::string::npos) << message;
  }

  config = MapperConfig{};
  config.rays.min_range = 5.0;
  config.rays.max_range = 2.0;
  auto ranges = Mapper::create(config);
  ASSERT_FALSE(ranges);
  EXPECT_EQ(ranges.error().message, "rays.max_range must be larger than rays.min_range");
}

TEST(Mapper, InvalidRaysAreCountedNotFatal) {
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper);
  std::vector<WorldRay> rays(3);
  rays[0].end = Eigen::Vector3d(1.0, 0.0, 0.0);
  rays[1].end = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0);
  rays[2].origin = Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(mapper->counters().rays_invalid, 2u);
  EXPECT_EQ(mapper->counters().rays_integrated, 1u);
}

TEST(Mapper, AFullMapIsACapacityErrorThatSaysWhatToRaise) {
  MapperConfig config = smallMapper(Semantics::kPerRay);
  config.map.max_memory_bytes = 64 << 10;  // a handful of 8³ regions
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  const std::vector<Ray> rays = test::randomScans(3, 1, 5000);
  const std::vector<WorldRay> scan = toWorldRays(rays);
  auto integrated = mapper->integrate(std::span<const WorldRay>(scan));
  auto flushed = mapper->flush();
  const Expected<void, Error>& failed = integrated ? flushed : integrated;
  ASSERT_FALSE(failed);
  EXPECT_EQ(failed.error().code, ErrorCode::kCapacity);
  EXPECT_NE(failed.error().message.find("max_memory_bytes"), std::string::npos);
}

TEST(Mapper, SavesAndLoadsTheSameMap) {
  const std::vector<Ray> rays = test::randomScans(11, 3, 2000);
  const std::vector<WorldRay> scan = toWorldRays(rays);
  MapperConfig config = smallMapper(Semantics::kPerRay);
  config.map.hit_probability = 0.8;
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper);
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(scan)));
  test::TempDir dir;
  const std::string path = dir.file("saved.rmap");
  ASSERT_TRUE(mapper->save(path));
  auto loaded = Mapper::load(path);
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(loaded->counts().voxels_occupied, mapper->counts().voxels_occupied);
  EXPECT_EQ(loaded->counts().voxels_free, mapper->counts().voxels_free);
  EXPECT_NEAR(loaded->mapOptions().hit_probability, 0.8, 1e-6);
  EXPECT_EQ(loaded->mapOptions().region_voxels, 8);
  // The loaded map keeps integrating.
  ASSERT_TRUE(loaded->integrate(std::span<const WorldRay>(scan)));
  ASSERT_TRUE(loaded->flush());
  EXPECT_EQ(loaded->counters().rays_in, scan.size());

  auto missing = Mapper::load(dir.file("missing.rmap"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("missing.rmap"), std::string::npos);
  // A failed save leaves no file behind and reports the path.
  auto unwritable = mapper->save(dir.file("no/such/dir/map.rmap"));
  ASSERT_FALSE(unwritable);
  EXPECT_NE(unwritable.error().message.find("map.rmap"), std::string::npos);
}

TEST(Mapper, HeightMapOfAFloorFollowsItsHeight) {
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper);
  // A sensor 1 m above a floor whose top is at z = -0.05 (voxel layer -1).
  std::vector<SensorPoint> points;
  for (int i = -30; i <= 30; ++i) {
    for (int j = -30; j <= 30; ++j) {
      SensorPoint p;
      p.position = Eigen::Vector3d(0.1 * i + 0.05, 0.1 * j + 0.05, -1.05);
      points.push_back(p);
    }
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(mapper->integrate(std::span<const SensorPoint>(points), pose));
  }
  HeightmapRequest request;
  request.centre = Eigen::Vector3d(0.0, 0.0, 0.0);
  request.size = 4.0;
  auto hm = mapper->heightmap(request);
  ASSERT_TRUE(hm) << hm.error().message;
  EXPECT_EQ(hm->cells_x, 40);
  EXPECT_EQ(hm->cells_y, 40);
  const std::size_t centre = hm->index(20, 20);
  EXPECT_EQ(hm->kind[centre], HeightCell::kSurface);
  EXPECT_NEAR(hm->elevation[centre], -0.05, 0.06);
  EXPECT_EQ(hm->observed_count[centre], 3u);

  request.size = 1e6;  // far beyond 8192 cells
  auto too_big = mapper->heightmap(request);
  ASSERT_FALSE(too_big);
  EXPECT_NE(too_big.error().message.find("size"), std::string::npos) << too_big.error().message;
}

TEST(Mapper, IntegrateAllocatesNothingOnceWarm) {
  if (!test::allocationCountingAvailable()) {
    GTEST_SKIP() << "the sanitizers own malloc here";
  }
  auto mapper = Mapper::create(smallMapper(Semantics::kPerScan));
  ASSERT_TRUE(mapper);
  const std::vector<Ray> rays = test::randomScans(5, 1, 20000);
  const std::vector<WorldRay> scan = toWorldRays(rays);
  std::vector<SensorPoint> points(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    points[i].position = scan[i].end;
    points[i].time_s = 0.001 * static_cast<double>(i / 64);
  }
  const SensorPoseFunction pose_at = [](double) -> std::optional<Eigen::Isometry3d> {
    return Eigen::Isometry3d::Identity();
  };
  // Warm-up: regions are taken from the preallocated pool; the CPU backend's scratch grows.
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(scan)));
  ASSERT_TRUE(mapper->integrate(std::span<const SensorPoint>(points), pose_at));
  ASSERT_TRUE(mapper->flush());
  test::AllocationScope scope;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(scan)));
    ASSERT_TRUE(
        mapper->integrate(std::span<const SensorPoint>(points), Eigen::Isometry3d::Identity()));
    ASSERT_TRUE(mapper->integrate(std::span<const SensorPoint>(points), pose_at));
    ASSERT_TRUE(mapper->flush());
  }
  EXPECT_EQ(scope.count(), 0u);
}

// Every device backend this build has gives the CPU's map and height map through the public API
// (queries after flush() read the device's map copied back; the height map is made on the
// device). PoCL runs the OpenCL case in CI; CUDA skips without a GPU.
TEST(Mapper, DeviceBackendsGiveTheCpuMap) {
  const std::vector<Ray> rays = test::randomScans(13, 4, 4000);
  const std::vector<WorldRay> scan = toWorldRays(rays);
  HeightmapRequest request;
  request.size = 8.0;
  auto integrate_all = [&](Mapper& mapper) {
    ASSERT_TRUE(mapper.integrate(std::span<const WorldRay>(scan)));
    ASSERT_TRUE(mapper.flush());
  };
  auto cpu = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(cpu);
  integrate_all(*cpu);
  auto cpu_heights = cpu->heightmap(request);
  ASSERT_TRUE(cpu_heights) << cpu_heights.error().message;
  int compared = 0;
  for (const auto& [device, planning] : {std::pair{"opencl", "host"}, std::pair{"opencl", "device"},
                                         std::pair{"cuda", "host"}, std::pair{"cuda", "device"}}) {
    MapperConfig config = smallMapper(Semantics::kPerRay);
    config.backend.name = device;
    config.backend.device_planning = planning;
    config.rays.walk = RayOptions::Walk::kForward;  // the CPU's walk: the same voxels either way
    auto mapper = Mapper::create(config);
    if (!mapper) {
      std::printf("%s: not run here (%s)\n", device, mapper.error().message.c_str());
      continue;
    }
    ++compared;
    EXPECT_EQ(mapper->backendName(), device);
    integrate_all(*mapper);
    EXPECT_EQ(mapper->counts().voxels_occupied, cpu->counts().voxels_occupied) << device;
    EXPECT_EQ(mapper->counts().voxels_free, cpu->counts().voxels_free) << device;
    auto heights = mapper->heightmap(request);
    ASSERT_TRUE(heights) << heights.error().message;
    ASSERT_EQ(heights->kind.size(), cpu_heights->kind.size());
    for (std::size_t i = 0; i < heights->kind.size(); ++i) {
      ASSERT_EQ(heights->kind[i], cpu_heights->kind[i]) << device << " cell " << i;
      if (heights->kind[i] == HeightCell::kSurface) {
        ASSERT_FLOAT_EQ(heights->elevation[i], cpu_heights->elevation[i]) << device;
      }
    }
  }
  if (compared == 0) {
    GTEST_SKIP() << "no device backend can run here";
  }
}

/// A sweep of points with times over 0.1 s from a sensor moving and turning, and the table of
/// its poses (every 10 ms, 50 ms beyond the sweep on each side). Some points fall outside it.
struct TableScan {
  std::vector<SensorPoint> points;
  std::vector<TimedPose> poses;
};

TableScan tableScan(int scan, int count) {
  TableScan out;
  const double start = 0.1 * scan;
  for (int k = -2; k <= 14; ++k) {
    const double t = start + 0.01 * k;
    TimedPose p;
    p.time_s = t;
    p.sensor_to_world.translation() = Eigen::Vector3d(1.2 * t, 0.3 * t, 0.4);
    p.sensor_to_world.linear() = Eigen::AngleAxisd(0.7 * t, Eigen::Vector3d::UnitZ()).matrix();
    out.poses.push_back(p);
  }
  for (int i = 0; i < count; ++i) {
    const double a = 6.283185307179586 * i / count;
    const double r = 1.0 + 4.0 * ((i * 7919) % 1000) / 1000.0;
    SensorPoint p;
    p.position = Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.3 * std::sin(5.0 * a));
    p.time_s = start + 0.2 * i / count - 0.04;  // the first and last tenth: no pose
    p.intensity = 1.0f;
    p.no_return = i % 23 == 0;
    out.points.push_back(p);
  }
  return out;
}

/// The rays the table gives, as a device would deskew them (kernels/common/deskew.h).
std::vector<WorldRay> tableRays(const TableScan& scan, std::uint64_t* no_pose) {
  std::vector<rm_pose_sample> samples;
  for (const TimedPose& p : scan.poses) {
    samples.push_back(rm_pose_sample{std::llround(p.time_s * 1e9), 0,
                                     io::toRmPose(io::Pose::fromIsometry(p.sensor_to_world))});
  }
  const rm_deskew_segment segment{rm_pose{rm_vec3d{0.0, 0.0, 0.0}, rm_quat{1.0, 0.0, 0.0, 0.0}}, 0u,
                                  static_cast<rm_u32>(samples.size())};
  const std::uint64_t scan_number = 0;
  const DeskewTables tables{samples, std::span<const rm_deskew_segment>(&segment, 1),
                            std::span<const std::uint64_t>(&scan_number, 1)};
  std::vector<WorldRay> rays;
  for (const SensorPoint& p : scan.points) {
    const std::int64_t t = std::llround(p.time_s * 1e9);
    if (t < samples.front().time_ns || t > samples.back().time_ns) {
      ++*no_pose;
      continue;
    }
    const Ray r = deskewedRay(
        rm_scan_point{static_cast<float>(p.position.x()), static_cast<float>(p.position.y()),
                      static_cast<float>(p.position.z()), p.intensity,
                      p.no_return ? RM_RAW_RAY_NO_RETURN : 0u, 0u, t},
        tables);
    WorldRay w;
    w.origin = toEigen(r.origin);
    w.end = toEigen(r.sample);
    w.intensity = r.intensity;
    w.no_return = p.no_return;
    rays.push_back(w);
  }
  return rays;
}

TEST(Mapper, APoseTableDeskewsEachPointAtItsTime) {
  auto table = Mapper::create(smallMapper(Semantics::kPerRay));
  auto rays = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(table && rays);
  std::uint64_t no_pose = 0;
  for (int s = 0; s < 4; ++s) {
    const TableScan scan = tableScan(s, 3000);
    ASSERT_TRUE(table->integrate(std::span<const SensorPoint>(scan.points),
                                 std::span<const TimedPose>(scan.poses)));
    const std::vector<WorldRay> world = tableRays(scan, &no_pose);
    ASSERT_TRUE(rays->integrate(std::span<const WorldRay>(world)));
  }
  ASSERT_TRUE(table->flush());
  ASSERT_TRUE(rays->flush());
  EXPECT_GT(no_pose, 100u);
  EXPECT_EQ(table->counters().points_no_pose, no_pose);
  EXPECT_EQ(table->counters().rays_in, rays->counters().rays_in);
  EXPECT_EQ(table->counters().rays_integrated, rays->counters().rays_integrated);
  test::TempDir dir;
  const VoxelMap a = savedMap(*table, dir);
  const VoxelMap b = savedMap(*rays, dir);
  const test::MapComparison c = test::compareMaps(a, b);
  EXPECT_GT(c.compared, 1000u);
  EXPECT_EQ(c.exact_value, c.compared);
}

TEST(Mapper, ABadPoseTableIsAnErrorNamingTheSample) {
  auto mapper = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(mapper);
  const TableScan scan = tableScan(0, 100);
  auto empty =
      mapper->integrate(std::span<const SensorPoint>(scan.points), std::span<const TimedPose>());
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.error().code, ErrorCode::kInvalidArgument);
  std::vector<TimedPose> backwards = scan.poses;
  backwards[3].time_s = backwards[1].time_s;
  auto bad = mapper->integrate(std::span<const SensorPoint>(scan.points),
                               std::span<const TimedPose>(backwards));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("sensor_poses[3]"), std::string::npos) << bad.error().message;
  backwards[3].time_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(mapper->integrate(std::span<const SensorPoint>(scan.points),
                                 std::span<const TimedPose>(backwards)));
  EXPECT_EQ(mapper->counters().rays_in, 0u);  // nothing went in
}

// One conversion of points into rays: a scan at one pose (and a depth pixel's point, and
// raymapd's pipeline) is converted by io::aimRay, the devices' and the pose table's by
// rm_deskew_point; both apply the pose as rm_pose_apply does, so the same scan at the same pose
// gives the same map bit for bit whichever path takes it (a path with another rotation
// convention, frame order or no-return rule would not). The points are floats, as a pose
// table's points are.
TEST(Mapper, OnePoseAndAOneSamplePoseTableGiveTheSameMap) {
  TimedPose pose;
  pose.time_s = 2.0;
  pose.sensor_to_world.translation() = Eigen::Vector3d(1.3, -2.1, 0.45);
  pose.sensor_to_world.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.1, 1.0).normalized()).matrix();
  std::vector<SensorPoint> points;
  for (int i = 0; i < 4000; ++i) {
    const double a = 6.283185307179586 * i / 4000.0;
    const double r = 1.0 + 6.0 * ((i * 7919) % 1000) / 1000.0;
    SensorPoint p;
    p.time_s = pose.time_s;
    p.position =
        Eigen::Vector3f(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                        static_cast<float>(0.5 * std::sin(5.0 * a)))
            .cast<double>();
    p.no_return = i % 31 == 0;
    points.push_back(p);
  }
  auto at_pose = Mapper::create(smallMapper(Semantics::kPerRay));
  auto by_table = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(at_pose && by_table);
  ASSERT_TRUE(at_pose->integrate(std::span<const SensorPoint>(points), pose.sensor_to_world));
  ASSERT_TRUE(by_table->integrate(std::span<const SensorPoint>(points),
                                  std::span<const TimedPose>(&pose, 1)));
  ASSERT_TRUE(at_pose->flush());
  ASSERT_TRUE(by_table->flush());
  EXPECT_EQ(by_table->counters().points_no_pose, 0u);
  EXPECT_EQ(at_pose->counters().rays_integrated, points.size());
  EXPECT_EQ(by_table->counters().rays_integrated, points.size());
  test::TempDir dir;
  const VoxelMap a = savedMap(*at_pose, dir);
  const VoxelMap b = savedMap(*by_table, dir);
  const test::MapComparison c = test::compareMaps(a, b);
  EXPECT_GT(c.compared, 1000u);
  EXPECT_EQ(c.exact_value, c.compared);
}

TEST(Mapper, APoseTableOnADeviceGivesTheCpuMap) {
  auto cpu = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(cpu);
  std::vector<TableScan> scans;
  for (int s = 0; s < 3; ++s) {
    scans.push_back(tableScan(s, 4000));
    ASSERT_TRUE(cpu->integrate(std::span<const SensorPoint>(scans.back().points),
                               std::span<const TimedPose>(scans.back().poses)));
  }
  ASSERT_TRUE(cpu->flush());
  int compared = 0;
  for (const auto& [device, planning] :
       {std::pair{"opencl", "host"}, std::pair{"opencl", "device"}, std::pair{"cuda", "device"}}) {
    MapperConfig config = smallMapper(Semantics::kPerRay);
    config.backend.name = device;
    config.backend.device_planning = planning;
    config.rays.walk = RayOptions::Walk::kForward;  // the CPU's walk: the same voxels
    auto mapper = Mapper::create(config);
    if (!mapper) {
      std::printf("%s: not run here (%s)\n", device, mapper.error().message.c_str());
      continue;
    }
    ++compared;
    for (const TableScan& scan : scans) {
      ASSERT_TRUE(mapper->integrate(std::span<const SensorPoint>(scan.points),
                                    std::span<const TimedPose>(scan.poses)));
    }
    ASSERT_TRUE(mapper->flush());
    EXPECT_EQ(mapper->counters().points_no_pose, cpu->counters().points_no_pose) << device;
    EXPECT_EQ(mapper->counters().rays_integrated, cpu->counters().rays_integrated) << device;
    EXPECT_EQ(mapper->counts().voxels_occupied, cpu->counts().voxels_occupied) << device;
    EXPECT_EQ(mapper->counts().voxels_free, cpu->counts().voxels_free) << device;
    // Planned on the device, the points are deskewed there (every CUDA device and PoCL have
    // double precision).
    EXPECT_EQ(mapper->counters().points_deskewed_on_device > 0, std::string(planning) == "device")
        << device << " planning " << planning;
  }
  EXPECT_EQ(cpu->counters().points_deskewed_on_device, 0u);
  if (compared == 0) {
    GTEST_SKIP() << "no device backend can run here";
  }
}

TEST(Mapper, AnUnknownDevicePlanningIsRefusedByName) {
  MapperConfig config = smallMapper(Semantics::kPerRay);
  config.backend.name = "opencl";
  config.backend.device_planning = "gpu";
  auto mapper = Mapper::create(config);
  ASSERT_FALSE(mapper);
  EXPECT_NE(mapper.error().message.find("device planning 'gpu': must be host or device"),
            std::string::npos)
      << mapper.error().message;
}

TEST(Mapper, MaxMemoryBeyondTheMachineIsSizedToWhatItCanHold) {
  // 64 TiB of regions would be about 179 million slots, whose bookkeeping alone is committed up
  // front (about 28 GB): Mapper::create sizes the pool to what this machine can fill, as
  // `raymap populate` does, and says so.
  MapperConfig config = smallMapper(Semantics::kPerRay);
  config.map.region_voxels = 32;
  config.map.max_memory_bytes = std::uint64_t{64} << 40;
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  EXPECT_NE(mapper->memoryWarning().find("map.max_memory asks for"), std::string::npos)
      << mapper->memoryWarning();
  EXPECT_NE(mapper->memoryWarning().find("this machine can hold"), std::string::npos);
  const std::vector<WorldRay> rays = {
      WorldRay{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(4.05, 0.05, 0.05), 0.0f, false}};
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(mapper->occupancy(VoxelKey(40, 0, 0)), VoxelState::kOccupied);
  // A budget the machine holds: no warning.
  auto small = Mapper::create(smallMapper(Semantics::kPerRay));
  ASSERT_TRUE(small);
  EXPECT_TRUE(small->memoryWarning().empty()) << small->memoryWarning();
}

TEST(Mapper, VersionHeaderMatchesTheProject) {
  EXPECT_GE(RAYMAP_VERSION_MAJOR, 0);
  EXPECT_STRNE(RAYMAP_VERSION_STRING, "");
}

// The public defaults are the library's own: one set of numbers.
TEST(MapperDefaults, AreTheLibrarys) {
  const MapOptions map;
  EXPECT_EQ(map.resolution, MapGeometry::kDefaultResolution);
  EXPECT_EQ(map.region_voxels, MapGeometry::kDefaultRegionVoxels);
  EXPECT_EQ(map.hit_probability, OccupancyParams::kDefaultHitProbability);
  EXPECT_EQ(map.miss_probability, OccupancyParams::kDefaultMissProbability);
  // The probabilities whose log-odds are exactly the defaults (-2 and 3.511 as floats).
  EXPECT_EQ(logOdds(map.clamp_min_probability), OccupancyParams::kDefaultClampMin);
  EXPECT_EQ(logOdds(map.clamp_max_probability), OccupancyParams::kDefaultClampMax);
  EXPECT_EQ(map.occupied_threshold, OccupancyParams::kDefaultThresholdProbability);
  EXPECT_EQ(map.max_memory_bytes, MapConfig::kDefaultMemoryBudget);
  EXPECT_EQ(map.tiers.compressed_memory_bytes, RegionTierConfig::kDefaultCompressedBytes);
  EXPECT_EQ(map.tiers.enabled, RegionTierConfig{}.enabled);
}

}  // namespace
}  // namespace raymap
