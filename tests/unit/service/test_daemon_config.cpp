// SPDX-License-Identifier: BSD-3-Clause
// raymapd's configuration: defaults, the shipped profiles, and errors that name the file, the key
// and the reason.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/backend_choice.hpp"
#include "src/service/daemon_config.hpp"

namespace raymap::service {
namespace {

constexpr const char* kName = "robot.yaml";

/// config/ of this checkout (this file is tests/unit/service/ of it).
std::filesystem::path configDir() {
  return std::filesystem::path(__FILE__).parent_path().parent_path().parent_path().parent_path() /
         "config";
}

bool haveBackend(const std::string& name) {
  const std::vector<std::string> available = backends::availableBackends();
  return std::find(available.begin(), available.end(), name) != available.end();
}

/// Parses `text` expecting an error; returns its message ("" and a test failure when it parsed).
std::string errorOf(const std::string& text) {
  auto result = parseDaemonConfig(text, kName);
  EXPECT_FALSE(result) << "accepted:\n" << text;
  return result ? std::string() : result.error().message;
}

/// Expects the error message of `text` to name the file, `key` and `reason`.
void expectError(const std::string& text, const std::string& key, const std::string& reason) {
  SCOPED_TRACE(text);
  const std::string message = errorOf(text);
  EXPECT_NE(message.find(kName), std::string::npos) << message;
  EXPECT_NE(message.find(key), std::string::npos) << "key '" << key << "' not in: " << message;
  EXPECT_NE(message.find(reason), std::string::npos)
      << "reason '" << reason << "' not in: " << message;
}

TEST(DaemonConfig, EmptyMappingGivesTheDefaults) {
  auto result = parseDaemonConfig("{}\n", kName);

  ASSERT_TRUE(result) << result.error().message;
  const DaemonConfig& c = result.value();
  EXPECT_EQ(c.path, kName);
  EXPECT_EQ(c.map.policy, StorePolicy::kRolling);
  EXPECT_EQ(c.map.geometry.resolution, MapGeometry::kDefaultResolution);
  EXPECT_EQ(c.map.geometry.region_voxels, MapGeometry::kDefaultRegionVoxels);
  EXPECT_EQ(c.map.window_regions, (Vec3i{8, 8, 3}));
  EXPECT_EQ(c.map.semantics, Semantics::kPerRay);
  EXPECT_TRUE(c.map.voxel_mean);
  EXPECT_TRUE(c.map.prefault);
  EXPECT_EQ(c.backend.name, "cpu");
  EXPECT_FALSE(c.backend.fallback_cpu);
  EXPECT_EQ(c.backend.opencl_span_work, "auto");
  EXPECT_EQ(c.backend.device_planning, "host");
  EXPECT_EQ(c.pose.source, PoseConfig::Source::kOdometry);
  EXPECT_EQ(c.pose.odometry_topic, "rt/odom");
  EXPECT_EQ(c.pose.history, 4096u);
  ASSERT_EQ(c.sensors.size(), 1u);
  EXPECT_EQ(c.sensors[0].topic, "rt/points");
  EXPECT_EQ(c.sensors[0].min_range_m, 0.5);
  EXPECT_EQ(c.sensors[0].max_range_m, 20.0);
  EXPECT_EQ(c.sensors[0].time_field, "auto");
  EXPECT_EQ(c.heightmap.rate_hz, 5.0);
  EXPECT_EQ(c.heightmap.size_m, 20.0);
  EXPECT_FALSE(c.heightmap.floor_depth_m.has_value());
  EXPECT_EQ(c.dds.domain, 0u);
  EXPECT_EQ(c.dds.grid_map_topic, "rt/height_map");
  EXPECT_TRUE(c.dds.voxels_topic.empty());
  EXPECT_EQ(c.queues.scan_slots, 4u);
  EXPECT_EQ(c.queues.batch_rays, 16384u);
  EXPECT_TRUE(c.realtime.lock_memory);
  EXPECT_EQ(c.realtime.ingest.priority, 40);
  EXPECT_EQ(c.realtime.integrator.priority, 30);
  EXPECT_EQ(c.realtime.publisher.priority, 60);
  EXPECT_TRUE(c.save_map_on_exit.empty());
}

TEST(DaemonConfig, EmptySectionsGiveTheDefaults) {
  auto result = parseDaemonConfig("map:\nbackend:\npose:\nheightmap:\n", kName);

  ASSERT_TRUE(result) << result.error().message;
  EXPECT_EQ(result->map.window_regions, (Vec3i{8, 8, 3}));
  EXPECT_EQ(result->backend.name, "cpu");
}

TEST(DaemonConfig, HeightmapLayersAreNamedOnceEach) {
  auto chosen = parseDaemonConfig("heightmap: {layers: [clearance, elevation]}\n", kName);
  ASSERT_TRUE(chosen) << chosen.error().message;
  EXPECT_EQ(chosen->heightmap.layers, (std::vector<std::string>{"clearance", "elevation"}));
  auto all = parseDaemonConfig("heightmap: {}\n", kName);
  ASSERT_TRUE(all);
  EXPECT_TRUE(all->heightmap.layers.empty()) << "left out: every layer the map has";
  expectError("heightmap: {layers: [elevation, height]}\n", "heightmap.layers[1]",
              "unknown layer 'height'");
  expectError("heightmap: {layers: [kind, kind]}\n", "heightmap.layers[1]", "listed twice");
  expectError("heightmap: {layers: []}\n", "heightmap.layers", "expected a list");
  expectError("heightmap: {layers: elevation}\n", "heightmap.layers", "expected a list");
  expectError("heightmap: {layers: [elevation, normal_z]}\n", "heightmap.layers",
              "normal_z needs a map with surface normals");
}

TEST(DaemonConfig, CpuProfileParses) {
  auto result = loadDaemonConfig((configDir() / "cpu.yaml").string());

  ASSERT_TRUE(result) << result.error().message;
  const DaemonConfig& c = result.value();
  EXPECT_EQ(c.map.window_regions, (Vec3i{10, 10, 4}));
  EXPECT_EQ(c.backend.name, "cpu");
  EXPECT_EQ(c.backend.threads, 0u);
  ASSERT_EQ(c.sensors.size(), 1u);
  EXPECT_EQ(c.sensors[0].name, "lidar");
  EXPECT_EQ(c.sensors[0].max_points, 262144u);
  EXPECT_EQ(c.sensors[0].extrinsic.orientation.w(), 1.0);
  EXPECT_EQ(c.dds.voxels_topic, "rt/raymap/occupied_voxels");
  EXPECT_EQ(c.heightmap.publish_lead_s, 0.015);
  EXPECT_TRUE(c.realtime.ingest.cpus.empty());
  EXPECT_NE(c.path.find("cpu.yaml"), std::string::npos);
}

/// A profile for a device backend: parses where this build has the backend, else the error names
/// backend.name.
void expectProfile(const std::string& file, const std::string& backend) {
  SCOPED_TRACE(file);
  auto result = loadDaemonConfig((configDir() / file).string());
  if (!haveBackend(backend)) {
    ASSERT_FALSE(result) << file << " parsed without a " << backend << " backend";
    EXPECT_NE(result.error().message.find(file), std::string::npos) << result.error().message;
    EXPECT_NE(result.error().message.find("backend.name"), std::string::npos)
        << result.error().message;
    EXPECT_NE(result.error().message.find(backend), std::string::npos) << result.error().message;
    return;
  }
  ASSERT_TRUE(result) << result.error().message;
  EXPECT_EQ(result->backend.name, backend);
  EXPECT_TRUE(result->backend.fallback_cpu);
}

TEST(DaemonConfig, NucOpenClProfileParsesOrNamesTheMissingBackend) {
  expectProfile("nuc-opencl.yaml", "opencl");
  auto result = loadDaemonConfig((configDir() / "nuc-opencl.yaml").string());
  if (result) {
    EXPECT_EQ(result->pose.source, PoseConfig::Source::kTf);
    ASSERT_EQ(result->sensors.size(), 1u);
    EXPECT_EQ(result->sensors[0].frame, "os_sensor");
    EXPECT_EQ(result->realtime.integrator.cpus, (std::vector<int>{2, 3}));
  }
}

TEST(DaemonConfig, JetsonCudaProfileParsesOrNamesTheMissingBackend) {
  expectProfile("jetson-cuda.yaml", "cuda");
  auto result = loadDaemonConfig((configDir() / "jetson-cuda.yaml").string());
  if (result) {
    // A lidar and two body depth cameras (issue 26's example).
    ASSERT_EQ(result->sensors.size(), 3u);
    EXPECT_EQ(result->sensors[0].kind, SensorKind::kPointCloud);
    EXPECT_EQ(result->sensors[1].kind, SensorKind::kDepth);
    EXPECT_EQ(result->sensors[2].kind, SensorKind::kDepth);
    EXPECT_EQ(result->sensors[1].camera_info_topic, "rt/front_left/depth/camera_info");
    EXPECT_EQ(result->sensors[2].downsample, 6u);
    EXPECT_EQ(result->sensors[2].max_rate_hz, 5.0);
    // The optical axis (z) of the left camera looks forward-left and 45 degrees down.
    const Eigen::Vector3d axis =
        result->sensors[1].extrinsic.orientation * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(axis.z(), -std::sqrt(0.5), 1e-5);
    EXPECT_GT(axis.x(), 0.6);
    EXPECT_GT(axis.y(), 0.3);
    EXPECT_EQ(result->backend.gpu_cache_bytes, std::uint64_t{512} << 20);
  }
}

TEST(DaemonConfig, DeviceProfilesParseOnTheCpuBackend) {
  // Whatever this build has: with backend.name switched to cpu every other key must be valid.
  for (const char* file : {"nuc-opencl.yaml", "jetson-cuda.yaml"}) {
    SCOPED_TRACE(file);
    auto loaded = loadDaemonConfig((configDir() / file).string());
    if (loaded) {
      continue;
    }
    std::ifstream in(configDir() / file);
    ASSERT_TRUE(in) << file;
    std::string text;
    for (std::string line; std::getline(in, line);) {
      text += line + "\n";
    }
    for (const char* name : {"name: opencl", "name: cuda"}) {
      const std::size_t at = text.find(name);
      if (at != std::string::npos) {
        text.replace(at, std::string(name).size(), "name: cpu");
      }
    }
    auto result = parseDaemonConfig(text, file);
    EXPECT_TRUE(result) << result.error().message;
  }
}

TEST(DaemonConfig, MissingFileIsAnIoErrorNamingIt) {
  auto result = loadDaemonConfig("/nonexistent/raymapd.yaml");

  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().code, ErrorCode::kIo);
  EXPECT_NE(result.error().message.find("/nonexistent/raymapd.yaml"), std::string::npos)
      << result.error().message;
  EXPECT_NE(result.error().message.find("cannot open"), std::string::npos);
}

TEST(DaemonConfig, InvalidYamlNamesTheLine) {
  const std::string message = errorOf("map:\n  resolution: 0.1\n  window: [1, 2\nbackend: {}\n");

  EXPECT_NE(message.find(kName), std::string::npos) << message;
  EXPECT_NE(message.find("not valid YAML"), std::string::npos) << message;
  EXPECT_NE(message.find("line "), std::string::npos) << message;
}

TEST(DaemonConfig, InvalidYamlReportsTheRightLine) {
  // A tab where YAML wants spaces, on line 3.
  const std::string message = errorOf("map:\n  resolution: 0.1\n\tregion_voxels: 16\n");

  EXPECT_NE(message.find("line 3"), std::string::npos) << message;
}

TEST(DaemonConfig, UnknownKeysAreTyposNotIgnored) {
  expectError("mapp:\n  resolution: 0.1\n", "mapp", "unknown key");
  expectError("map:\n  resolutoin: 0.1\n", "map.resolutoin", "unknown key");
  expectError("sensors:\n  - topic: rt/a\n    max_rang: 5\n", "sensors[0].max_rang", "unknown key");
  expectError("sensors:\n  - extrinsic: {translaton: [0, 0, 0]}\n",
              "sensors[0].extrinsic.translaton", "unknown key");
  expectError("realtime:\n  ingest: {priority: 10, cpu: [1]}\n", "realtime.ingest.cpu",
              "unknown key");
  // The list of known keys helps to fix the typo.
  EXPECT_NE(errorOf("map:\n  resolutoin: 0.1\n").find("resolution"), std::string::npos);
}

TEST(DaemonConfig, ErrorsGiveTheLineOfTheKey) {
  const std::string message = errorOf("map:\n  resolution: 0.1\n  resolutoin: 0.1\n");

  EXPECT_NE(message.find("line 3"), std::string::npos) << message;
}

TEST(DaemonConfig, NdtModeAndParametersParseAndAreChecked) {
  auto parsed = parseDaemonConfig(
      "map:\n  mode: ndt-tm\n  ndt:\n    sensor_noise: 0.03\n    sample_threshold: 6\n"
      "    adaptation_rate: 0.3\n",
      kName);
  ASSERT_TRUE(parsed) << parsed.error().message;
  EXPECT_EQ(parsed->map.mode, MapMode::kNdtTm);
  EXPECT_DOUBLE_EQ(parsed->map.ndt.sensor_noise, 0.03);
  EXPECT_EQ(parsed->map.ndt.sample_threshold, 6u);
  ASSERT_TRUE(parsed->map.ndt.adaptation_rate.has_value());
  EXPECT_DOUBLE_EQ(*parsed->map.ndt.adaptation_rate, 0.3);
  EXPECT_EQ(parseDaemonConfig("map: {}\n", kName)->map.mode, MapMode::kOccupancy);

  expectError("map:\n  mode: ndt\n", "map.mode", "occupancy, ndt-om or ndt-tm");
  expectError("map:\n  mode: ndt-om\n  semantics: per-scan\n", "map.mode", "semantics: ray");
  expectError("map:\n  mode: ndt-om\n  ndt: {sensor_nois: 0.1}\n", "map.ndt.sensor_nois",
              "unknown key");
  expectError("map:\n  mode: ndt-om\n  ndt: {sensor_noise: -1}\n", "map.ndt.sensor_noise",
              "positive");
}

TEST(DaemonConfig, DecayRateIsAFlagThatNeedsTheVoxelMean) {
  auto parsed = parseDaemonConfig("map:\n  mode: ndt-om\n  decay_rate: true\n", kName);
  ASSERT_TRUE(parsed) << parsed.error().message;
  EXPECT_TRUE(parsed->map.decay_rate);
  EXPECT_FALSE(parseDaemonConfig("map: {}\n", kName)->map.decay_rate);
  expectError("map:\n  decay_rate: true\n  voxel_mean: false\n", "map.decay_rate", "voxel_mean");
  expectError("map:\n  decay_rate: often\n", "map.decay_rate", "expected true or false");
}

TEST(DaemonConfig, WrongTypesAreNamed) {
  expectError("map: 5\n", "map", "expected a mapping");
  expectError("map:\n  resolution: fine\n", "map.resolution", "expected a number");
  expectError("map:\n  voxel_mean: maybe\n", "map.voxel_mean", "expected true or false");
  expectError("map:\n  window: [8, 8]\n", "map.window", "expected [x, y, z]");
  expectError("map:\n  semantics: sometimes\n", "map.semantics", "per-ray or per-scan");
  expectError("queues:\n  scan_slots: 2.5\n", "queues.scan_slots", "expected an integer");
  expectError("backend:\n  name: [cpu]\n", "backend.name", "must be cpu, opencl or cuda");
  expectError("backend:\n  opencl_span_work: atomics\n", "backend.opencl_span_work",
              "must be auto, span or region");
  auto region = parseDaemonConfig("backend:\n  opencl_span_work: region\n", kName);
  ASSERT_TRUE(region) << region.error().message;
  EXPECT_EQ(region->backend.opencl_span_work, "region");
  expectError("backend:\n  device_planning: gpu\n", "backend.device_planning",
              "must be host or device");
  auto planned = parseDaemonConfig("backend:\n  device_planning: device\n", kName);
  ASSERT_TRUE(planned) << planned.error().message;
  EXPECT_EQ(planned->backend.device_planning, "device");
  expectError("pose:\n  source: gps\n", "pose.source", "must be odometry or tf");
  expectError("sensors:\n  topic: rt/points\n", "sensors", "expected a list");
  expectError("sensors: []\n", "sensors", "at least one sensor");
  expectError("sensors:\n  - topic: rt/my points\n", "sensors[0].topic", "without spaces");
  expectError("sensors:\n  - extrinsic: {rotation: [0, 0, 0, 0]}\n",
              "sensors[0].extrinsic.rotation", "zero quaternion");
  expectError("sensors:\n  - extrinsic: {translation: [1, 2]}\n",
              "sensors[0].extrinsic.translation", "[x, y, z]");
  expectError("realtime:\n  publisher: {cpus: 3}\n", "realtime.publisher.cpus", "expected a list");
}

TEST(DaemonConfig, ValuesOutOfRangeAreNamed) {
  expectError("heightmap:\n  rate_hz: 0\n", "heightmap.rate_hz", "must be > 0");
  expectError("heightmap:\n  rate_hz: 1000\n", "heightmap.rate_hz", "at most 100");
  expectError("sensors:\n  - max_range: -1\n", "sensors[0].max_range", "must be > 0");
  expectError("sensors:\n  - min_range: 5\n    max_range: 2\n", "sensors[0].max_range",
              "must exceed min_range");
  expectError("map:\n  hit_probability: 0.4\n", "map.hit_probability", "above 0.5");
  expectError("map:\n  hit_probability: 1.0\n", "map.hit_probability", "between 0 and 1");
  expectError("map:\n  miss_probability: 0.6\n", "map.miss_probability", "below 0.5");
  expectError("map:\n  region_voxels: 2\n", "map.region_voxels", "from 4 to 128");
  expectError("map:\n  window: [8, 0, 3]\n", "map.window[1]", "from 1 to 256");
  expectError("realtime:\n  ingest: {priority: 120}\n", "realtime.ingest.priority", "from 0 to 99");
  expectError("realtime:\n  integrator: {cpus: [-1]}\n", "realtime.integrator.cpus[0]",
              "from 0 to 63");
  expectError("queues:\n  scan_slots: 0\n", "queues.scan_slots", "from 1 to 256");
  expectError("queues:\n  batch_rays: 10\n", "queues.batch_rays", "from 256");
  expectError("dds:\n  domain: 300\n", "dds.domain", "from 0 to 232");
  expectError("pose:\n  max_wait_s: -0.1\n", "pose.max_wait_s", "must be >= 0");
  expectError("map:\n  resolution: .nan\n", "map.resolution", "finite");
}

TEST(DaemonConfig, MapRepairsGoOutInBurstsOfRepairBurstKb) {
  auto defaults = parseDaemonConfig("{}\n", kName);
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_EQ(defaults->dds.repair_burst_kb, 64u);  // one 64 KB datagram: within a stock buffer
  auto off = parseDaemonConfig("dds: {repair_burst_kb: 0}\n", kName);
  ASSERT_TRUE(off) << off.error().message;
  EXPECT_EQ(off->dds.repair_burst_kb, 0u);
  expectError("dds: {repair_burst_kb: 4}\n", "dds.repair_burst_kb", "at least 8");
  expectError("dds: {repair_burst_kb: -1}\n", "dds.repair_burst_kb", "");
}

TEST(DaemonConfig, HeightMapMustFitTheWindow) {
  // Default window: 8 x 8 regions of 3.2 m = 25.6 m; the map must be a region smaller.
  expectError("heightmap:\n  size: 25\n", "heightmap.size", "does not fit the rolling window");
  EXPECT_TRUE(parseDaemonConfig("heightmap:\n  size: 22.4\n", kName));
  EXPECT_TRUE(parseDaemonConfig("map:\n  window: [12, 12, 3]\nheightmap:\n  size: 25\n", kName));
}

TEST(DaemonConfig, TwoSensorsOnOneTopicAreRefused) {
  expectError("sensors:\n  - topic: rt/points\n  - topic: rt/points\n", "sensors[1].topic",
              "two sensors on one topic");
  EXPECT_TRUE(parseDaemonConfig("sensors:\n  - topic: rt/a\n  - topic: rt/b\n", kName));
}

TEST(DaemonConfig, PublishLeadMustBeShorterThanThePeriod) {
  expectError("heightmap:\n  rate_hz: 10\n  publish_lead_s: 0.1\n", "heightmap.publish_lead_s",
              "publish period");
  expectError("heightmap:\n  rate_hz: 10\n  publish_lead_s: 0.2\n", "heightmap.publish_lead_s",
              "publish period");
  EXPECT_TRUE(parseDaemonConfig("heightmap:\n  rate_hz: 10\n  publish_lead_s: 0.05\n", kName));
}

TEST(DaemonConfig, DuplicateKeysAreRefused) {
  expectError("map:\n  resolution: 0.1\n  resolution: 0.2\n", "map.resolution", "duplicate key");
}

TEST(DaemonConfig, SaveOnExitMustNameAFile) {
  expectError("map:\n  save_on_exit: /var/lib/raymapd/\n", "map.save_on_exit", "file name");
  auto ok = parseDaemonConfig("map:\n  save_on_exit: /var/lib/raymapd/last.rmap\n", kName);
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_EQ(ok->save_map_on_exit, "/var/lib/raymapd/last.rmap");
}

TEST(DaemonConfig, UnavailableBackendIsNamed) {
  for (const char* name : {"opencl", "cuda"}) {
    if (haveBackend(name)) {
      continue;
    }
    expectError(std::string("backend:\n  name: ") + name + "\n", "backend.name",
                std::string("no ") + name + " backend");
  }
}

TEST(DaemonConfig, ValuesAreRead) {
  auto result = parseDaemonConfig(
      "map:\n"
      "  resolution: 0.05\n"
      "  region_voxels: 16\n"
      "  window: [20, 20, 6]\n"
      "  semantics: scan\n"
      "pose:\n"
      "  source: tf\n"
      "  history: 128\n"
      "  max_wait_s: 0.1\n"
      "sensors:\n"
      "  - name: front\n"
      "    topic: rt/front\n"
      "    extrinsic: {translation: [0.1, 0.2, 0.3], rotation: [0, 0, 0, 2]}\n"
      "    min_range: 0\n"
      "    time_field: t\n"
      "heightmap:\n"
      "  size: 10\n"
      "  mode: fill\n"
      "  floor_depth: 0\n"
      "queues:\n"
      "  scan_slots: 8\n"
      "  batch_rays: 4096\n"
      "realtime:\n"
      "  lock_memory: false\n"
      "  ingest: {priority: 0, cpus: [0, 63]}\n",
      kName);

  ASSERT_TRUE(result) << result.error().message;
  const DaemonConfig& c = result.value();
  EXPECT_EQ(c.map.geometry.resolution, 0.05);
  EXPECT_EQ(c.map.geometry.region_voxels, 16);
  EXPECT_EQ(c.map.window_regions, (Vec3i{20, 20, 6}));
  EXPECT_EQ(c.map.semantics, Semantics::kPerScan);
  EXPECT_EQ(c.pose.source, PoseConfig::Source::kTf);
  EXPECT_EQ(c.pose.history, 128u);
  EXPECT_EQ(c.pose.max_wait_s, 0.1);
  ASSERT_EQ(c.sensors.size(), 1u);
  EXPECT_EQ(c.sensors[0].name, "front");
  EXPECT_EQ(c.sensors[0].extrinsic.position, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(c.sensors[0].extrinsic.orientation.z(), 1.0) << "normalised";
  EXPECT_EQ(c.sensors[0].min_range_m, 0.0);
  EXPECT_EQ(c.sensors[0].time_field, "t");
  EXPECT_EQ(c.heightmap.mode, heightmap::HeightmapMode::kFill);
  ASSERT_TRUE(c.heightmap.floor_depth_m.has_value());
  EXPECT_EQ(*c.heightmap.floor_depth_m, 0.0);
  EXPECT_EQ(c.queues.scan_slots, 8u);
  EXPECT_EQ(c.queues.batch_rays, 4096u);
  EXPECT_FALSE(c.realtime.lock_memory);
  EXPECT_EQ(c.realtime.ingest.priority, 0);
  EXPECT_EQ(c.realtime.ingest.cpus, (std::vector<int>{0, 63}));
  EXPECT_EQ(c.realtime.integrator.priority, 30) << "default kept";
}

TEST(DaemonConfig, HealthAndLoadDefaults) {
  auto result = parseDaemonConfig("{}\n", kName);

  ASSERT_TRUE(result) << result.error().message;
  const DaemonConfig& c = result.value();
  EXPECT_EQ(c.name, "raymapd");
  EXPECT_EQ(c.health.stale_after_s, 1.0);
  EXPECT_EQ(c.health.startup_grace_s, 10.0);
  EXPECT_EQ(c.health.min_integrated_fraction, 0.5);
  EXPECT_TRUE(c.health.hardware_id.empty()) << "host name + name at start-up";
  EXPECT_EQ(c.sensors[0].max_time_offset_s, 1.0);
  EXPECT_EQ(c.queues.max_lock_hold_s, 0.005);
  EXPECT_EQ(c.queues.max_latency_s, 0.25);
  EXPECT_TRUE(c.queues.shed_subsample);
  EXPECT_EQ(c.queues.max_subsample, 8u);
  EXPECT_FALSE(c.queues.shed_always);
  EXPECT_EQ(c.heightmap.publish_lead_max_s, 0.1);
}

TEST(DaemonConfig, HealthAndLoadValuesAreRead) {
  auto result = parseDaemonConfig(
      "name: front-mapper\n"
      "health: {stale_after_s: 2.5, hardware_id: robot7/front, startup_grace_s: 30,\n"
      "         min_integrated_fraction: 0.2}\n"
      "sensors:\n  - max_time_offset_s: 0.2\n"
      "queues: {max_lock_hold_s: 0.002, max_latency_s: 0.4, shed: drop, max_subsample: 4,\n"
      "         shed_when: always}\n"
      "heightmap: {publish_lead_max_s: 0.05}\n",
      kName);

  ASSERT_TRUE(result) << result.error().message;
  const DaemonConfig& c = result.value();
  EXPECT_EQ(c.name, "front-mapper");
  EXPECT_EQ(c.health.stale_after_s, 2.5);
  EXPECT_EQ(c.health.hardware_id, "robot7/front");
  EXPECT_EQ(c.health.startup_grace_s, 30.0);
  EXPECT_EQ(c.health.min_integrated_fraction, 0.2);
  EXPECT_EQ(c.sensors[0].max_time_offset_s, 0.2);
  EXPECT_EQ(c.queues.max_lock_hold_s, 0.002);
  EXPECT_EQ(c.queues.max_latency_s, 0.4);
  EXPECT_FALSE(c.queues.shed_subsample);
  EXPECT_EQ(c.queues.max_subsample, 4u);
  EXPECT_TRUE(c.queues.shed_always);
  EXPECT_EQ(c.heightmap.publish_lead_max_s, 0.05);
}

TEST(DaemonConfig, PoseResetsAndJumpsHaveDefaultsAndAreRead) {
  auto defaults = parseDaemonConfig("{}\n", kName);
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_EQ(defaults->pose.time_reset_s, 1.0);
  EXPECT_EQ(defaults->pose.max_jump_m, 5.0);
  EXPECT_FALSE(defaults->pose.clear_on_jump);
  auto set = parseDaemonConfig("pose: {time_reset_s: 3, max_jump_m: 0, on_jump: clear}\n", kName);
  ASSERT_TRUE(set) << set.error().message;
  EXPECT_EQ(set->pose.time_reset_s, 3.0);
  EXPECT_EQ(set->pose.max_jump_m, 0.0);
  EXPECT_TRUE(set->pose.clear_on_jump);
  expectError("pose: {on_jump: forget}\n", "pose.on_jump", "");
  expectError("pose: {time_reset_s: 0}\n", "pose.time_reset_s", "");
}

TEST(DaemonConfig, TheLatencyBoundFollowsThePublishRate) {
  // Off.
  auto off = parseDaemonConfig("queues: {max_latency_s: 0}\n", kName);
  ASSERT_TRUE(off) << off.error().message;
  EXPECT_EQ(off->queues.max_latency_s, 0.0);
  // At 2 Hz the default grows to a period, the lead and 35 ms.
  auto slow = parseDaemonConfig("heightmap: {rate_hz: 2}\n", kName);
  ASSERT_TRUE(slow) << slow.error().message;
  EXPECT_NEAR(slow->queues.max_latency_s, 0.55, 1e-12);
  // A bound no map can meet is refused.
  expectError("queues: {max_latency_s: 0.1}\n", "queues.max_latency_s", "shorter than one publish");
}

TEST(DaemonConfig, HealthAndLoadErrorsAreNamed) {
  expectError("name: two words\n", "name", "letters, digits");
  expectError("health: {stale_after_s: 0}\n", "health.stale_after_s", "");
  expectError("health: {hardware_id: 'a b'}\n", "health.hardware_id", "letters, digits");
  expectError("health: {grace: 1}\n", "health.grace", "");
  expectError("health: {startup_grace_s: -1}\n", "health.startup_grace_s", "0 to 3600");
  expectError("health: {min_integrated_fraction: 1.5}\n", "health.min_integrated_fraction",
              "must be 0 to 1");
  expectError("sensors:\n  - max_time_offset_s: 120\n", "sensors[0].max_time_offset_s",
              "at most 60");
  expectError("queues: {shed: sometimes}\n", "queues.shed", "");
  expectError("queues: {shed_when: never}\n", "queues.shed_when", "");
  expectError("queues: {max_lock_hold_s: 2}\n", "queues.max_lock_hold_s", "at most 1");
  expectError("heightmap: {publish_lead_s: 0.05, publish_lead_max_s: 0.02}\n",
              "heightmap.publish_lead_max_s", "at least publish_lead_s");
  expectError("heightmap: {publish_lead_max_s: 0.19}\n", "heightmap.publish_lead_max_s",
              "publish period");
}

TEST(DaemonConfig, TheCostmapIsOffByDefaultAndItsSectionIsRead) {
  auto defaults = parseDaemonConfig("{}\n", kName);
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_TRUE(defaults->dds.costmap_topic.empty());
  EXPECT_EQ(defaults->costmap.max_step_m, 0.15);
  EXPECT_TRUE(defaults->costmap.virtual_lethal);

  auto set = parseDaemonConfig(
      "dds: {costmap_topic: rt/costmap}\n"
      "costmap: {max_step: 0.1, max_slope: 20, min_clearance: 0.8, virtual_surfaces: unknown,\n"
      "          max_free_cost: 70}\n",
      kName);
  ASSERT_TRUE(set) << set.error().message;
  EXPECT_EQ(set->dds.costmap_topic, "rt/costmap");
  EXPECT_EQ(set->costmap.max_step_m, 0.1);
  EXPECT_EQ(set->costmap.max_slope_deg, 20.0);
  EXPECT_EQ(set->costmap.min_clearance_m, 0.8);
  EXPECT_FALSE(set->costmap.virtual_lethal);
  EXPECT_EQ(set->costmap.max_free_cost, 70);

  expectError("costmap: {max_slope: 95}\n", "costmap.max_slope", "below 90");
  expectError("costmap: {max_free_cost: 100}\n", "costmap.max_free_cost", "");
  expectError("costmap: {virtual_surfaces: maybe}\n", "costmap.virtual_surfaces", "");
  expectError("costmap: {inflation: 0.4}\n", "costmap.inflation", "");
  expectError("dds: {costmap_topic: 'rt/a b'}\n", "dds.costmap_topic", "without spaces");
}

TEST(DaemonConfig, TopicsTakeRosNamesAsRmwCycloneddsNamesThem) {
  auto result = parseDaemonConfig(
      "pose: {topic: /odom}\n"
      "sensors:\n  - topic: /ouster/points\n"
      "dds: {grid_map_topic: /height_map, costmap_topic: rt/costmap}\n",
      kName);
  ASSERT_TRUE(result) << result.error().message;
  EXPECT_EQ(result->pose.odometry_topic, "rt/odom");
  EXPECT_EQ(result->sensors[0].topic, "rt/ouster/points");
  EXPECT_EQ(result->dds.grid_map_topic, "rt/height_map");
  EXPECT_EQ(result->dds.costmap_topic, "rt/costmap");  // a DDS name stays as it is
  expectError("dds: {costmap_topic: /}\n", "dds.costmap_topic", "ROS one");
}

}  // namespace
}  // namespace raymap::service

namespace raymap::service {
namespace {

TEST(DaemonConfig, DepthCameraTakesItsKeysAndDefaults) {
  auto config = parseDaemonConfig(R"(
sensors:
  - topic: rt/points
  - kind: depth
    topic: /cam/depth/image_rect_raw
    downsample: 4
    invalid_as_free: true
    max_rate_hz: 5
)",
                                  "depth.yaml");
  ASSERT_TRUE(config) << config.error().message;
  ASSERT_EQ(config->sensors.size(), 2u);
  const SensorConfig& depth = config->sensors[1];
  EXPECT_EQ(depth.kind, SensorKind::kDepth);
  EXPECT_EQ(depth.name, "depth1");
  EXPECT_EQ(depth.topic, "rt/cam/depth/image_rect_raw");
  EXPECT_EQ(depth.camera_info_topic, "rt/cam/depth/camera_info");
  EXPECT_EQ(depth.downsample, 4u);
  EXPECT_TRUE(depth.invalid_as_free);
  EXPECT_EQ(depth.max_rate_hz, 5.0);
  EXPECT_EQ(depth.max_range_m, 3.0);  // a depth camera's default, not a lidar's
  EXPECT_EQ(depth.max_points, 640u * 480u);
  EXPECT_EQ(config->sensors[0].kind, SensorKind::kPointCloud);
}

TEST(DaemonConfig, DepthCameraKeysAreRefusedOnPointCloudsAndCheckedOnCameras) {
  const struct {
    const char* yaml;
    const char* key;
  } cases[] = {
      {"sensors:\n  - topic: rt/points\n    downsample: 2\n", "sensors[0].downsample"},
      {"sensors:\n  - topic: rt/points\n    camera_info_topic: rt/ci\n",
       "sensors[0].camera_info_topic"},
      {"sensors:\n  - kind: depth\n    downsample: 0\n", "sensors[0].downsample"},
      {"sensors:\n  - kind: lidar\n", "sensors[0].kind"},
      {"sensors:\n  - kind: depth\n    max_rate_hz: -1\n", "sensors[0].max_rate_hz"},
      {"sensors:\n  - kind: depth\n    topic: rt/a/image\n  - kind: depth\n    topic: "
       "rt/a/depth\n",
       "sensors[1].camera_info_topic"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.yaml);
    auto config = parseDaemonConfig(c.yaml, "bad.yaml");
    ASSERT_FALSE(config);
    EXPECT_NE(config.error().message.find(c.key), std::string::npos) << config.error().message;
  }
}

}  // namespace
}  // namespace raymap::service

namespace raymap::service {
namespace {

// One set of names (issue 55): map.semantics takes `ray` and `scan` as `raymap populate
// --semantics` does, and backend.gpu_cache a size, a region count or auto as `--gpu-cache`; the
// older spellings still work for one release, each with a warning naming the new one.
TEST(DaemonConfigNames, OldSpellingsAreReadWithAWarningNamingTheNewOnes) {
  auto current =
      parseDaemonConfig("map:\n  semantics: scan\nbackend:\n  gpu_cache: 512MiB\n", "robot.yaml");
  ASSERT_TRUE(current) << current.error().message;
  EXPECT_TRUE(current->warnings.empty());
  EXPECT_EQ(current->map.semantics, Semantics::kPerScan);
  EXPECT_EQ(current->backend.gpu_cache_bytes, std::uint64_t{512} << 20);

  auto old = parseDaemonConfig("map:\n  semantics: per-scan\nbackend:\n  gpu_cache_mb: 512\n",
                               "robot.yaml");
  ASSERT_TRUE(old) << old.error().message;
  EXPECT_EQ(old->map.semantics, Semantics::kPerScan);
  EXPECT_EQ(old->backend.gpu_cache_bytes, std::uint64_t{512} << 20);
  ASSERT_EQ(old->warnings.size(), 2u);
  EXPECT_NE(old->warnings[0].find("map.semantics: per-scan is the old name: write scan"),
            std::string::npos)
      << old->warnings[0];
  EXPECT_NE(old->warnings[1].find("backend.gpu_cache_mb is the old key: write backend.gpu_cache"),
            std::string::npos)
      << old->warnings[1];

  auto regions = parseDaemonConfig("backend:\n  gpu_cache: 2000regions\n", "robot.yaml");
  ASSERT_TRUE(regions) << regions.error().message;
  EXPECT_EQ(regions->backend.gpu_cache_regions, 2000u);
  auto both = parseDaemonConfig("backend:\n  gpu_cache: auto\n  gpu_cache_mb: 64\n", "robot.yaml");
  ASSERT_FALSE(both);
  EXPECT_NE(both.error().message.find("not both"), std::string::npos) << both.error().message;
  auto bad = parseDaemonConfig("backend:\n  gpu_cache: 5xregions\n", "robot.yaml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("backend.gpu_cache"), std::string::npos)
      << bad.error().message;
}

// The occupancy clamps are probabilities like every other occupancy key (and `--clamp-min`):
// map.clamp_min_probability / clamp_max_probability. The older log-odds keys give the same map
// parameters, with a warning naming the new key; both at once are refused.
TEST(DaemonConfigNames, ClampsAreProbabilitiesAndTheOldLogOddsKeysStillWork) {
  auto current = parseDaemonConfig(
      "map:\n  clamp_min_probability: 0.2\n  clamp_max_probability: 0.95\n", "robot.yaml");
  auto old = parseDaemonConfig("map:\n  clamp_min: -1.3862943611\n  clamp_max: 2.9444389792\n",
                               "robot.yaml");
  auto both =
      parseDaemonConfig("map:\n  clamp_min: -1\n  clamp_min_probability: 0.2\n", "robot.yaml");
  auto defaults = parseDaemonConfig("map:\n  resolution: 0.1\n", "robot.yaml");

  ASSERT_TRUE(current) << current.error().message;
  ASSERT_TRUE(old) << old.error().message;
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_TRUE(current->warnings.empty());
  EXPECT_FLOAT_EQ(current->map.occupancy.clamp_min, logOdds(0.2));
  EXPECT_FLOAT_EQ(current->map.occupancy.clamp_max, logOdds(0.95));
  EXPECT_FLOAT_EQ(old->map.occupancy.clamp_min, logOdds(0.2));
  EXPECT_FLOAT_EQ(old->map.occupancy.clamp_max, logOdds(0.95));
  ASSERT_EQ(old->warnings.size(), 2u);
  EXPECT_NE(old->warnings[0].find("map.clamp_min is the old key (log-odds): write "
                                  "map.clamp_min_probability"),
            std::string::npos)
      << old->warnings[0];
  ASSERT_FALSE(both);
  EXPECT_NE(both.error().message.find("not both"), std::string::npos) << both.error().message;
  // The defaults stay OctoMap's log-odds to the bit: -2 and 3.511.
  EXPECT_EQ(defaults->map.occupancy.clamp_min, -2.0f);
  EXPECT_EQ(defaults->map.occupancy.clamp_max, 3.511f);
}

// The map section goes through the library's conversion (mapper::toMapConfig), the same as
// raymap::Mapper and `raymap populate`: NDT parameters for a map that is not NDT are refused
// there, naming the key, as the command line refuses --ndt-* without an NDT --mode.
TEST(DaemonConfigNames, NdtParametersForAnOccupancyMapAreRefusedByTheLibrarysRule) {
  auto refused = parseDaemonConfig("map:\n  ndt: {sensor_noise: 0.1}\n", "robot.yaml");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("map.ndt.sensor_noise applies only to map.mode ndt-om"),
            std::string::npos)
      << refused.error().message;
}

}  // namespace
}  // namespace raymap::service
