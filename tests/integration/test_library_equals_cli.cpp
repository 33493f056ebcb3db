// SPDX-License-Identifier: BSD-3-Clause
// Every `raymap populate` map option has a library equivalent (issue 55): the same rays mapped by
// `raymap populate` with flags and by raymap::Mapper with the public MapperConfig give the same
// map, region for region and byte for byte in every layer — NDT-OM and NDT-TM with their
// parameters, decay rates (beside occupancy and alone), TSDF, per-scan occupancy with OctoMap's
// probabilities, and a map larger than its memory budget (compressed and spilled regions).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include "raymap/ray_cloud.hpp"
#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/same_map.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// The room scene's lidar, five scans: a ray cloud, and the same returns as a point cloud with
/// its trajectory (with intensities, for NDT-TM).
struct Room {
  TempDir dir;
  std::string rays = dir.file("room.ply");
  std::string points = dir.file("room_points.ply");
  std::string trajectory = dir.file("room_trajectory.txt");
  Room() {
    const RunResult r = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/room.yaml",
                                   "--sensors", "lidar", "--scans", "5", "--rays", rays, "--points",
                                   points, "--trajectory", trajectory, "-q"});
    EXPECT_EQ(r.exit_code, 0) << describe(r);
  }
};

struct Case {
  const char* name;
  std::vector<std::string> flags;  ///< `raymap populate` flags
  std::function<void(MapperConfig&)> library;
  bool points = false;  ///< the point cloud with its trajectory instead of the ray cloud
};

class LibraryEqualsCli : public testing::TestWithParam<Case> {};

TEST_P(LibraryEqualsCli, TheSameMapFromFlagsAndFromMapperConfig) {
  const Case& c = GetParam();
  Room room;
  const std::string cli = room.dir.file("cli.rmap");
  const std::string library = room.dir.file("library.rmap");
  const std::string input = c.points ? room.points : room.rays;
  std::vector<std::string> args{"populate",    input, "-o",        cli, "-q",
                                "--max-range", "20",  "--threads", "1"};
  RayCloudOptions read;
  if (c.points) {
    args.insert(args.end(), {"--trajectory", room.trajectory});
    read.trajectory_path = room.trajectory;
  }
  args.insert(args.end(), c.flags.begin(), c.flags.end());
  const RunResult r = runRaymap(args);
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  MapperConfig config;
  config.rays.max_range = 20.0;
  config.backend.threads = 1;
  c.library(config);
  ASSERT_NO_FATAL_FAILURE(mapWithLibrary(input, read, config, library));
  expectSameMap(cli, library);
}

std::vector<Case> cases() {
  return {
      {"OccupancyPerScanWithOctomapsProbabilities",
       {"--semantics", "scan", "--hit", "0.7", "--miss", "0.4", "--resolution", "0.05"},
       [](MapperConfig& c) {
         c.map.semantics = Semantics::kPerScan;
         c.map.hit_probability = 0.7;
         c.map.miss_probability = 0.4;
         c.map.resolution = 0.05;
       }},
      {"NdtOmWithItsParameters",
       {"--mode", "ndt-om", "--ndt-sensor-noise", "0.03", "--ndt-sample-threshold", "6",
        "--ndt-adaptation-rate", "0.5"},
       [](MapperConfig& c) {
         c.map.mode = MapMode::kNdtOm;
         c.map.ndt.sensor_noise = 0.03;
         c.map.ndt.sample_threshold = 6;
         c.map.ndt.adaptation_rate = 0.5;
       }},
      {"NdtTmWithDecayRatesFromPointsAndATrajectory",
       {"--mode", "ndt-tm", "--decay-rate", "--ndt-initial-intensity-variance", "4"},
       [](MapperConfig& c) {
         c.map.mode = MapMode::kNdtTm;
         c.map.decay_rate = true;
         c.map.ndt.initial_intensity_variance = 4.0;
       },
       true},
      {"DecayRatesOnly",
       {"--mode", "decay"},
       [](MapperConfig& c) {
         c.map.decay_rate = true;
         c.map.occupancy = false;
       }},
      {"TsdfWithItsParameters",
       {"--mode", "tsdf", "--tsdf-truncation", "0.25", "--tsdf-max-weight", "50", "--tsdf-dropoff",
        "0.05"},
       [](MapperConfig& c) {
         c.map.mode = MapMode::kTsdf;
         c.map.tsdf.truncation = 0.25;
         c.map.tsdf.max_weight = 50.0;
         c.map.tsdf.dropoff = 0.05;
       }},
      {"AMapLargerThanItsMemoryBudget",
       {"--region-voxels", "8", "--max-memory", "200KiB", "--compressed-memory", "64KiB",
        "--no-mean"},
       [](MapperConfig& c) {
         c.map.region_voxels = 8;
         c.map.max_memory_bytes = 200 * 1024;
         c.map.voxel_mean = false;
         c.map.tiers.enabled = true;
         c.map.tiers.compressed_memory_bytes = 64 * 1024;
         c.map.tiers.spill_dir = testing::TempDir();
       }},
  };
}

INSTANTIATE_TEST_SUITE_P(Options, LibraryEqualsCli, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<Case>& param) {
                           return param.param.name;
                         });

TEST(LibraryOptions, ImpossibleCombinationsAreRefusedNamingTheKey) {
  const auto refused = [](const std::function<void(MapperConfig&)>& change,
                          const std::string& key) {
    MapperConfig config;
    change(config);
    auto mapper = Mapper::create(config);
    ASSERT_FALSE(mapper) << key;
    EXPECT_NE(mapper.error().message.find(key), std::string::npos) << mapper.error().message;
  };
  refused(
      [](MapperConfig& c) {
        c.map.mode = MapMode::kNdtOm;
        c.map.semantics = Semantics::kPerScan;
      },
      "map.semantics");
  refused(
      [](MapperConfig& c) {
        c.map.decay_rate = true;
        c.map.voxel_mean = false;
      },
      "map.voxel_mean");
  refused(
      [](MapperConfig& c) {
        c.map.mode = MapMode::kTsdf;
        c.map.decay_rate = true;
      },
      "map.decay_rate");
  refused([](MapperConfig& c) { c.map.occupancy = false; }, "map.occupancy");
  refused(
      [](MapperConfig& c) {
        c.map.mode = MapMode::kNdtOm;
        c.map.ndt.regulariser = 2.0;
      },
      "regulariser");
  refused(
      [](MapperConfig& c) {
        c.map.mode = MapMode::kTsdf;
        c.map.tsdf.truncation = -1.0;
      },
      "truncation");
}

}  // namespace
}  // namespace raymap::test

namespace raymap::test {
namespace {

// One configuration schema (issue 55): a file written for raymapd — its map: and backend:
// sections, in raymapd's names, beside sections populate does not read — configures `raymap
// populate --config` to the same map as the same options given as flags; a flag given as well
// wins over the file, and an old spelling is read with a warning naming the new one.
TEST(ConfigFile, RaymapdsMapSectionConfiguresPopulateAsItsFlagsDo) {
  Room room;
  const std::string yaml = room.dir.file("robot.yaml");
  writeText(yaml,
            "name: robot\n"
            "map:\n"
            "  resolution: 0.05\n"
            "  region_voxels: 16\n"
            "  window: [10, 10, 4]\n"
            "  semantics: per-ray\n"
            "  mode: ndt-om\n"
            "  ndt: {sensor_noise: 0.03, sample_threshold: 6}\n"
            "  hit_probability: 0.8\n"
            "  clamp_max: 3.0\n"
            "backend:\n"
            "  name: cpu\n"
            "  threads: 1\n"
            "sensors:\n"
            "  - {name: lidar, topic: rt/points}\n");
  const std::string from_file = room.dir.file("file.rmap");
  const RunResult r = runRaymap(
      {"populate", room.rays, "--config", yaml, "--max-range", "20", "-o", from_file, "-q"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "map.semantics: per-ray is the old name: write ray")) << r.err;

  // clamp_max is log-odds in raymapd's file; --clamp-max takes a probability.
  const std::string from_flags = room.dir.file("flags.rmap");
  const RunResult f = runRaymap({"populate",
                                 room.rays,
                                 "--max-range",
                                 "20",
                                 "--resolution",
                                 "0.05",
                                 "--region-voxels",
                                 "16",
                                 "--mode",
                                 "ndt-om",
                                 "--ndt-sensor-noise",
                                 "0.03",
                                 "--ndt-sample-threshold",
                                 "6",
                                 "--hit",
                                 "0.8",
                                 "--clamp-max",
                                 "0.95257412682243336",
                                 "--threads",
                                 "1",
                                 "-o",
                                 from_flags,
                                 "-q"});
  ASSERT_EQ(f.exit_code, 0) << describe(f);
  expectSameMap(from_file, from_flags);

  // A flag wins over the file.
  const std::string coarse = room.dir.file("coarse.rmap");
  ASSERT_EQ(runRaymap({"populate", room.rays, "--config", yaml, "--resolution", "0.1", "-o", coarse,
                       "-q"})
                .exit_code,
            0);
  const RunResult info = runRaymap({"info", coarse});
  EXPECT_TRUE(contains(info.out, "resolution     0.1 m, regions of 16^3")) << info.out;
  EXPECT_TRUE(contains(info.out, "ndt-om")) << info.out;
}

TEST(ConfigFile, ErrorsNameTheFileLineAndKey) {
  TempDir dir;
  const std::string yaml = dir.file("bad.yaml");
  writeText(yaml, "map:\n  resolution: 0.1\n  semantics: sometimes\n");
  const RunResult r =
      runRaymap({"populate", dir.file("none.ply"), "--config", yaml, "-o", dir.file("m.rmap")});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "bad.yaml: line 3: map.semantics")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.rmap")));
}

}  // namespace
}  // namespace raymap::test
