// SPDX-License-Identifier: BSD-3-Clause
// raymapd's YAML configuration: section readers over the checked reader of src/config, then the
// checks that span sections.
#include "src/service/daemon_config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "src/config/yaml_reader.hpp"
#include "src/core/byte_size.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/dds/grid_map_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/mapper/mapper_conversions.hpp"
#include "src/mapper/mapper_yaml.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/pipeline/sensor_decoder.hpp"

namespace raymap::service {
namespace {

using config::choiceOr;
using config::Context;
using config::Fields;
using config::flag;
using config::formatNumber;
using config::text;

std::string topic(Fields& f, const std::string& key, const std::string& fallback) {
  std::string name = text(f, key, fallback);
  f.check(!name.empty() && name.find_first_of(" \t") == std::string::npos && name != "/", key,
          "must be a DDS topic name (rt/points) or a ROS one (/points), without spaces (got '" +
              name + "')");
  return msgs::ddsTopicName(name);
}

/// The `map:` section as the library's MapOptions (the names raymap::MapperConfig and
/// `raymap populate` use), converted by the library's one conversion, which checks the
/// combinations; then what only a rolling service map has.
void readMap(Context& ctx, const YAML::Node& node, DaemonConfig& config) {
  MapOptions o;
  mapper::readMapOptions(ctx, node, o, config.warnings);
  Fields f(ctx, node, "map");  // raymapd's own keys of the section
  config.save_map_on_exit = text(f, "save_on_exit", "");
  o.window = Eigen::Vector3i(8, 8, 3);  // a service's map is always a rolling window
  if (f.has("window")) {
    const YAML::Node w = f.get("window");
    const std::string path = f.path("window");
    if (!w.IsSequence() || w.size() != 3) {
      ctx.fail(w, path, "expected [x, y, z]: the rolling window in regions per axis");
    } else {
      o.window = Eigen::Vector3i(config::toInteger<std::int32_t>(ctx, w[0], path + "[0]", 1, 256),
                                 config::toInteger<std::int32_t>(ctx, w[1], path + "[1]", 1, 256),
                                 config::toInteger<std::int32_t>(ctx, w[2], path + "[2]", 1, 256));
    }
  }
  if (ctx.failed()) {
    return;
  }
  auto converted = mapper::toMapConfig(o);
  if (!converted) {
    ctx.fail(node, "", converted.error().message);
    return;
  }
  config.map = *converted;
  config.map.prefault = true;  // a service touches its pool once at start-up, not in the loop
}

/// The `backend:` section as the library's BackendOptions, converted as raymap::Mapper and
/// `raymap populate` convert them.
void readBackend(Context& ctx, const YAML::Node& node, DaemonConfig& config) {
  BackendOptions backend;
  mapper::readBackendOptions(ctx, node, backend, config.warnings);
  // backend.batch_rays stays 0: device batches keep BackendChoice's default size.
  config.backend = mapper::toBackendChoice(backend);
}

void readPose(Context& ctx, const YAML::Node& node, PoseConfig& pose) {
  Fields f(ctx, node, "pose");
  f.knownKeys({"source", "topic", "world_frame", "base_frame", "history", "max_wait_s", "hold_s",
               "time_reset_s", "max_jump_m", "on_jump"});
  pose.source = choiceOr(f, "source", {"odometry", "tf"}, 0) == 0 ? PoseConfig::Source::kOdometry
                                                                  : PoseConfig::Source::kTf;
  pose.odometry_topic = topic(f, "topic", pose.odometry_topic);
  pose.world_frame = text(f, "world_frame", pose.world_frame);
  pose.base_frame = text(f, "base_frame", pose.base_frame);
  f.check(!pose.world_frame.empty() && pose.world_frame.size() < 64, "world_frame",
          "must be 1 to 63 characters");
  f.check(!pose.base_frame.empty() && pose.base_frame.size() < 64, "base_frame",
          "must be 1 to 63 characters");
  pose.history = f.integer<std::uint32_t>("history", pose.history, 16u, 1u << 20);
  pose.max_wait_s = f.positive("max_wait_s", pose.max_wait_s, true);
  pose.hold_s = f.positive("hold_s", pose.hold_s, true);
  pose.time_reset_s = f.positive("time_reset_s", pose.time_reset_s);
  pose.max_jump_m = f.positive("max_jump_m", pose.max_jump_m, true);
  pose.clear_on_jump = choiceOr(f, "on_jump", {"keep", "clear"}, 0) == 1;
}

io::Pose readExtrinsic(Context& ctx, const YAML::Node& node, const std::string& path) {
  Fields f(ctx, node, path);
  f.knownKeys({"translation", "rotation"});
  io::Pose pose;
  if (f.has("translation")) {
    pose.position = toEigen(f.vec3("translation"));
  }
  if (f.has("rotation")) {
    const std::vector<double> q =
        config::toNumbers(ctx, f.get("rotation"), f.path("rotation"), 4, "[w, x, y, z]");
    if (!ctx.failed()) {
      const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);  // w, x, y, z
      if (rotation.norm() < 1e-6) {
        ctx.fail(f.get("rotation"), f.path("rotation"), "is not a rotation (zero quaternion)");
      } else {
        pose.orientation = rotation.normalized();
      }
    }
  }
  return pose;
}

void readSensors(Context& ctx, const YAML::Node& node, std::vector<SensorConfig>& sensors) {
  if (!node.IsDefined()) {
    sensors.push_back(SensorConfig{});
    return;
  }
  if (!node.IsSequence() || node.size() == 0) {
    ctx.fail(node, "sensors", "expected a list of at least one sensor (- topic: rt/points ...)");
    return;
  }
  std::set<std::string> topics;
  std::set<std::string> names;
  if (node.size() > kMaxSensors) {
    ctx.fail(node, "sensors", "at most " + std::to_string(kMaxSensors) + " sensors");
    return;
  }
  for (std::size_t i = 0; i < node.size() && !ctx.failed(); ++i) {
    const std::string path = config::item("sensors", i);
    Fields f(ctx, node[i], path);
    f.knownKeys({"name", "kind", "topic", "camera_info_topic", "frame", "extrinsic", "min_range",
                 "max_range", "max_points", "time_field", "max_time_offset_s", "downsample",
                 "invalid_as_free", "max_rate_hz"});
    SensorConfig s;
    s.kind = choiceOr(f, "kind", {"points", "depth"}, 0) == 0 ? SensorKind::kPointCloud
                                                              : SensorKind::kDepth;
    const bool depth = s.kind == SensorKind::kDepth;
    s.name = text(f, "name", (depth ? "depth" : "lidar") + std::to_string(i));
    f.check(names.insert(s.name).second, "name",
            "two sensors with one name (their diagnostics would share one status)");
    s.topic = topic(f, "topic", depth ? "rt/camera/depth/image_rect_raw" : s.topic);
    f.check(topics.insert(s.topic).second, "topic", "two sensors on one topic");
    if (depth) {
      s.camera_info_topic = topic(f, "camera_info_topic", pipeline::cameraInfoTopicFor(s.topic));
      f.check(topics.insert(s.camera_info_topic).second, "camera_info_topic",
              "a topic another sensor already uses");
      s.min_range_m = 0.1;
      s.max_range_m = 3.0;
      s.max_points = 640 * 480;
    } else {
      f.check(!f.has("camera_info_topic") && !f.has("downsample") && !f.has("invalid_as_free"),
              f.has("camera_info_topic") ? "camera_info_topic"
              : f.has("downsample")      ? "downsample"
                                         : "invalid_as_free",
              "applies to depth cameras only (kind: depth)");
    }
    s.frame = text(f, "frame", "");
    f.check(s.frame.size() < 64, "frame", "must be shorter than 64 characters");
    if (f.has("extrinsic")) {
      s.extrinsic = readExtrinsic(ctx, f.get("extrinsic"), f.path("extrinsic"));
    }
    s.min_range_m = f.positive("min_range", s.min_range_m, true);
    s.max_range_m = f.positive("max_range", s.max_range_m);
    f.check(s.max_range_m > s.min_range_m, "max_range", "must exceed min_range");
    s.max_points = f.integer<std::uint32_t>("max_points", s.max_points, 1u, 1u << 24);
    s.time_field = text(f, "time_field", s.time_field);
    f.check(!s.time_field.empty() && s.time_field.size() < 32, "time_field",
            "must be auto, none or a field name shorter than 32 characters");
    s.max_time_offset_s = f.positive("max_time_offset_s", s.max_time_offset_s);
    f.check(s.max_time_offset_s <= 60.0, "max_time_offset_s",
            "must be at most 60 s (a scan's points lie within one revolution of its stamp)");
    s.downsample = f.integer<std::uint32_t>("downsample", s.downsample, 1u, 64u);
    s.invalid_as_free = flag(f, "invalid_as_free", s.invalid_as_free);
    s.max_rate_hz = f.positive("max_rate_hz", s.max_rate_hz, true);
    f.check(s.max_rate_hz == 0.0 || (s.max_rate_hz >= 0.01 && s.max_rate_hz <= 1000.0),
            "max_rate_hz", "must be 0 (no limit) or 0.01 to 1000");
    sensors.push_back(s);
  }
}

void readHeightmap(Context& ctx, const YAML::Node& node, HeightmapConfig& hm) {
  Fields f(ctx, node, "heightmap");
  f.knownKeys({"rate_hz", "size", "mode", "min_clearance", "floor_depth", "ceiling_height",
               "virtual_surfaces", "base_height", "publish_lead_s", "publish_lead_max_s",
               "layers"});
  if (f.has("layers")) {
    const YAML::Node layers = f.get("layers");
    if (!layers.IsSequence() || layers.size() == 0) {
      ctx.fail(layers, f.path("layers"),
               "expected a list of GridMap layers, e.g. [elevation, clearance] (leave it out "
               "for all)");
    } else {
      for (std::size_t i = 0; i < layers.size(); ++i) {
        const std::string where = config::item(f.path("layers"), i);
        const std::string name = layers[i].IsScalar() ? layers[i].Scalar() : std::string();
        if (!dds::gridLayerNamed(name)) {
          ctx.fail(layers[i], where,
                   "unknown layer '" + name +
                       "' (elevation, clearance, kind, observed_count, normal_x, normal_y, "
                       "normal_z)");
        } else if (std::find(hm.layers.begin(), hm.layers.end(), name) != hm.layers.end()) {
          ctx.fail(layers[i], where, "layer '" + name + "' listed twice");
        } else {
          hm.layers.push_back(name);
        }
      }
    }
  }
  hm.rate_hz = f.positive("rate_hz", hm.rate_hz);
  f.check(hm.rate_hz <= 100.0, "rate_hz", "must be at most 100");
  hm.size_m = f.positive("size", hm.size_m);
  hm.mode = choiceOr(f, "mode", {"planar", "fill"}, 0) == 0 ? heightmap::HeightmapMode::kPlanar
                                                            : heightmap::HeightmapMode::kFill;
  hm.min_clearance_m = f.positive("min_clearance", hm.min_clearance_m, true);
  if (f.has("floor_depth")) {
    hm.floor_depth_m = f.positive("floor_depth", std::nullopt, true);
  }
  if (f.has("ceiling_height")) {
    hm.ceiling_height_m = f.positive("ceiling_height", std::nullopt, true);
  }
  hm.virtual_surfaces = flag(f, "virtual_surfaces", hm.virtual_surfaces);
  hm.base_height_m = f.number("base_height", hm.base_height_m);
  hm.publish_lead_s = f.positive("publish_lead_s", hm.publish_lead_s, true);
  f.check(hm.publish_lead_s < 0.9 / hm.rate_hz, "publish_lead_s",
          "must be shorter than 90 % of the publish period (1 / rate_hz)");
  // Default: 100 ms, at most half the period, at least the minimum lead.
  hm.publish_lead_max_s = f.positive(
      "publish_lead_max_s",
      std::max(hm.publish_lead_s, std::min(hm.publish_lead_max_s, 0.5 / hm.rate_hz)), true);
  f.check(hm.publish_lead_max_s >= hm.publish_lead_s, "publish_lead_max_s",
          "must be at least publish_lead_s");
  f.check(hm.publish_lead_max_s < 0.9 / hm.rate_hz, "publish_lead_max_s",
          "must be shorter than 90 % of the publish period (1 / rate_hz)");
}

/// `dds.security`: keys the file leaves out come from ROS 2's variables where those name them
/// (ROS_SECURITY_KEYSTORE, ROS_SECURITY_ENCLAVE_OVERRIDE), so one keystore set-up serves both.
void readSecurity(Context& ctx, const YAML::Node& node, security::SecurityConfig& sec) {
  Fields f(ctx, node, "dds.security");
  f.knownKeys({"enable", "keystore", "enclave", "enclave_dir", "strategy"});
  sec.enabled = flag(f, "enable", true);
  // NOLINTNEXTLINE(concurrency-mt-unsafe): configuration is read at start-up, on one thread
  const char* keystore_env = std::getenv("ROS_SECURITY_KEYSTORE");
  // NOLINTNEXTLINE(concurrency-mt-unsafe): as above
  const char* enclave_env = std::getenv("ROS_SECURITY_ENCLAVE_OVERRIDE");
  sec.keystore = text(f, "keystore", keystore_env != nullptr ? keystore_env : "");
  sec.enclave = text(f, "enclave",
                     enclave_env != nullptr && enclave_env[0] != '\0'
                         ? std::string(enclave_env)
                         : std::string(security::kDaemonEnclave));
  sec.enclave_dir = text(f, "enclave_dir", "");
  if (auto name = security::checkEnclaveName(sec.enclave); !name) {
    f.check(false, "enclave", name.error().message);
  }
  const std::string strategy = text(f, "strategy", "Enforce");
  if (auto parsed = security::parseStrategy(strategy, "strategy"); parsed) {
    sec.strategy = *parsed;
  } else {
    f.check(false, "strategy", "must be Enforce or Permissive (got '" + strategy + "')");
  }
  f.check(!sec.enabled || !sec.keystore.empty() || !sec.enclave_dir.empty(), "keystore",
          "security is enabled: name the SROS2 keystore (or enclave_dir, the folder of the "
          "enclave's files)");
}

void readDds(Context& ctx, const YAML::Node& node, DdsConfig& dds) {
  Fields f(ctx, node, "dds");
  f.knownKeys({"domain", "cyclonedds_uri", "receive_buffer_mb", "repair_burst_kb", "grid_map_topic",
               "diagnostics_topic", "diagnostics_rate_hz", "voxels_topic", "voxels_rate_hz",
               "voxels_max_points", "costmap_topic", "security"});
  if (const YAML::Node security = f.get("security"); security.IsDefined() && !ctx.failed()) {
    dds.security_in_file = true;
    readSecurity(ctx, security.IsNull() ? YAML::Node(YAML::NodeType::Map) : security, dds.security);
    dds.security.source = "dds.security";
  }
  dds.domain = f.integer<std::uint32_t>("domain", 0u, 0u, 232u);
  dds.cyclonedds_uri = text(f, "cyclonedds_uri", "");
  dds.receive_buffer_mb = f.integer<std::uint32_t>("receive_buffer_mb", 0u, 0u, 2048u);
  dds.repair_burst_kb =
      f.integer<std::uint32_t>("repair_burst_kb", dds.repair_burst_kb, 0u, 65536u);
  f.check(dds.repair_burst_kb == 0 || dds.repair_burst_kb >= 8, "repair_burst_kb",
          "must be 0 (off) or at least 8 (KiB)");
  dds.grid_map_topic = topic(f, "grid_map_topic", dds.grid_map_topic);
  dds.diagnostics_topic = topic(f, "diagnostics_topic", dds.diagnostics_topic);
  dds.diagnostics_rate_hz = f.positive("diagnostics_rate_hz", dds.diagnostics_rate_hz);
  f.check(dds.diagnostics_rate_hz <= 10.0, "diagnostics_rate_hz", "must be at most 10");
  dds.voxels_topic = text(f, "voxels_topic", "");  // empty: off
  if (!dds.voxels_topic.empty()) {
    dds.voxels_topic = topic(f, "voxels_topic", "");
  }
  dds.costmap_topic = text(f, "costmap_topic", "");  // empty: off
  if (!dds.costmap_topic.empty()) {
    dds.costmap_topic = topic(f, "costmap_topic", "");
  }
  dds.voxels_rate_hz = f.positive("voxels_rate_hz", dds.voxels_rate_hz);
  f.check(dds.voxels_rate_hz <= 5.0, "voxels_rate_hz", "must be at most 5");
  dds.voxels_max_points =
      f.integer<std::uint32_t>("voxels_max_points", dds.voxels_max_points, 1u, 1u << 24);
}

void readCostmap(Context& ctx, const YAML::Node& node, heightmap::CostmapParams& c) {
  Fields f(ctx, node, "costmap");
  f.knownKeys({"max_step", "max_slope", "min_clearance", "virtual_surfaces", "max_free_cost"});
  c.max_step_m = f.positive("max_step", c.max_step_m);
  c.max_slope_deg = f.positive("max_slope", c.max_slope_deg);
  f.check(c.max_slope_deg < 90.0, "max_slope", "must be below 90 degrees");
  c.min_clearance_m = f.positive("min_clearance", c.min_clearance_m, true);
  c.virtual_lethal = choiceOr(f, "virtual_surfaces", {"lethal", "unknown"}, 0) == 0;
  c.max_free_cost = f.integer<int>("max_free_cost", c.max_free_cost, 0, 99);
}

void readQueues(Context& ctx, const YAML::Node& node, QueueConfig& q) {
  Fields f(ctx, node, "queues");
  f.knownKeys({"scan_slots", "pose_queue", "batch_rays", "batch_deadline_s", "max_lock_hold_s",
               "max_latency_s", "shed", "max_subsample", "shed_when"});
  q.scan_slots = f.integer<std::uint32_t>("scan_slots", q.scan_slots, 1u, 256u);
  q.pose_queue = f.integer<std::uint32_t>("pose_queue", q.pose_queue, 16u, 1u << 20);
  q.batch_rays = f.integer<std::uint32_t>("batch_rays", q.batch_rays, 256u, 1u << 22);
  q.batch_deadline_s = f.positive("batch_deadline_s", q.batch_deadline_s);
  q.max_lock_hold_s = f.positive("max_lock_hold_s", q.max_lock_hold_s);
  f.check(q.max_lock_hold_s <= 1.0, "max_lock_hold_s", "must be at most 1 s");
  if (f.has("max_latency_s")) {
    q.max_latency_s = f.positive("max_latency_s", q.max_latency_s, true);
  } else {
    q.max_latency_s = -1.0;  // the default, once the publish rate is known (parse())
  }
  q.shed_subsample = choiceOr(f, "shed", {"subsample", "drop"}, 0) == 0;
  q.max_subsample = f.integer<std::uint32_t>("max_subsample", q.max_subsample, 1u, 64u);
  q.shed_always = choiceOr(f, "shed_when", {"overload", "always"}, 0) == 1;
}

/// A name for logs, diagnostics and hardware ids: letters, digits, '-', '_', '.', '/'.
bool isPlainName(const std::string& name) {
  return !name.empty() && name.size() < 64 && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' || c == '.' ||
           c == '/';
  });
}

void readHealth(Context& ctx, const YAML::Node& node, HealthConfig& health) {
  Fields f(ctx, node, "health");
  f.knownKeys({"stale_after_s", "startup_grace_s", "min_integrated_fraction", "hardware_id"});
  health.stale_after_s = f.positive("stale_after_s", health.stale_after_s);
  f.check(health.stale_after_s <= 3600.0, "stale_after_s", "must be at most 3600 s");
  health.startup_grace_s = f.number("startup_grace_s", health.startup_grace_s);
  f.check(health.startup_grace_s >= 0.0 && health.startup_grace_s <= 3600.0, "startup_grace_s",
          "must be 0 to 3600 s");
  health.min_integrated_fraction =
      f.number("min_integrated_fraction", health.min_integrated_fraction);
  f.check(health.min_integrated_fraction >= 0.0 && health.min_integrated_fraction <= 1.0,
          "min_integrated_fraction", "must be 0 to 1");
  health.hardware_id = text(f, "hardware_id", "");
  f.check(
      health.hardware_id.empty() || isPlainName(health.hardware_id), "hardware_id",
      "must be 1 to 63 letters, digits, '-', '_', '.' or '/' (got '" + health.hardware_id + "')");
}

void readThread(Context& ctx, const YAML::Node& node, const std::string& path, ThreadConfig& t) {
  if (!node.IsDefined()) {
    return;
  }
  Fields f(ctx, node, path);
  f.knownKeys({"priority", "cpus"});
  t.priority = f.integer<int>("priority", t.priority, 0, 99);
  if (f.has("cpus")) {
    const YAML::Node cpus = f.get("cpus");
    if (!cpus.IsSequence()) {
      ctx.fail(cpus, f.path("cpus"), "expected a list of CPU numbers, e.g. [2, 3] ([] = any)");
      return;
    }
    t.cpus.clear();
    for (std::size_t i = 0; i < cpus.size(); ++i) {
      t.cpus.push_back(
          config::toInteger<int>(ctx, cpus[i], config::item(f.path("cpus"), i), 0, 63));
    }
  }
}

void readRealtime(Context& ctx, const YAML::Node& node, RealtimeConfig& rt) {
  Fields f(ctx, node, "realtime");
  f.knownKeys({"lock_memory", "ingest", "integrator", "publisher"});
  rt.lock_memory = flag(f, "lock_memory", rt.lock_memory);
  readThread(ctx, f.get("ingest"), f.path("ingest"), rt.ingest);
  readThread(ctx, f.get("integrator"), f.path("integrator"), rt.integrator);
  readThread(ctx, f.get("publisher"), f.path("publisher"), rt.publisher);
}

/// "key: why" when an output topic is one the service reads (its own maps would come back to it
/// as input, or another node's input would get maps), else "".
std::string outputOnAnInput(const DaemonConfig& config) {
  std::vector<std::pair<std::string, std::string>> inputs;  // (topic, key)
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    inputs.emplace_back(s.topic, config::item("sensors", i) + ".topic");
    if (!s.camera_info_topic.empty()) {
      inputs.emplace_back(s.camera_info_topic, config::item("sensors", i) + ".camera_info_topic");
    }
  }
  if (config.pose.source == PoseConfig::Source::kOdometry) {
    inputs.emplace_back(config.pose.odometry_topic, "pose.topic");
  } else {
    inputs.emplace_back("rt/tf", "pose.source: tf");
  }
  inputs.emplace_back("rt/tf_static", "the static transforms");
  const std::pair<const std::string*, const char*> outputs[] = {
      {&config.dds.grid_map_topic, "dds.grid_map_topic"},
      {&config.dds.diagnostics_topic, "dds.diagnostics_topic"},
      {&config.dds.voxels_topic, "dds.voxels_topic"},
      {&config.dds.costmap_topic, "dds.costmap_topic"},
  };
  for (const auto& [topic, key] : outputs) {
    for (const auto& [input, input_key] : inputs) {
      if (!topic->empty() && *topic == input) {
        return config.where(key) + ": " + *topic + " is an input too (" + input_key +
               "): the service would publish onto what it reads";
      }
    }
  }
  return {};
}

/// Records the line of every key under `node` (a mapping or sequence at `path`).
void recordKeyLines(const YAML::Node& node, const std::string& path,
                    std::map<std::string, int>& lines) {
  if (node.IsMap()) {
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) {
        continue;
      }
      const std::string key = config::child(path, entry.first.Scalar());
      lines.emplace(key, entry.first.Mark().line + 1);
      recordKeyLines(entry.second, key, lines);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      const std::string key = config::item(path, i);
      lines.emplace(key, node[i].Mark().line + 1);
      recordKeyLines(node[i], key, lines);
    }
  }
}

Result<DaemonConfig> parse(const YAML::Node& root, const std::string& name) {
  Context ctx(name);
  DaemonConfig config;
  config.path = name;
  recordKeyLines(root, "", config.key_lines);
  Fields top(ctx, root, "");
  top.knownKeys({"name", "map", "backend", "pose", "sensors", "heightmap", "costmap", "dds",
                 "queues", "realtime", "health"});
  config.name = text(top, "name", config.name);
  top.check(isPlainName(config.name), "name",
            "must be 1 to 63 letters, digits, '-', '_', '.' or '/' (got '" + config.name + "')");
  const auto section = [&](const char* key) {
    const YAML::Node node = top.get(key);
    return node.IsDefined() && !node.IsNull() ? node : YAML::Node(YAML::NodeType::Map);
  };
  if (!ctx.failed()) readMap(ctx, section("map"), config);
  if (!ctx.failed()) readBackend(ctx, section("backend"), config);
  if (!ctx.failed()) readPose(ctx, section("pose"), config.pose);
  if (!ctx.failed()) readSensors(ctx, top.get("sensors"), config.sensors);
  if (!ctx.failed()) readHeightmap(ctx, section("heightmap"), config.heightmap);
  if (!ctx.failed()) readCostmap(ctx, section("costmap"), config.costmap);
  if (!ctx.failed()) readDds(ctx, section("dds"), config.dds);
  if (!ctx.failed()) readQueues(ctx, section("queues"), config.queues);
  if (!ctx.failed()) readRealtime(ctx, section("realtime"), config.realtime);
  if (!ctx.failed()) readHealth(ctx, section("health"), config.health);
  if (ctx.failed()) {
    return Unexpected(ctx.error());
  }
  // Checks across sections.
  if (auto clash = outputOnAnInput(config); !clash.empty()) {
    return fail(ErrorCode::kInvalidArgument, clash);
  }
  if (auto valid = config.map.validate(); !valid) {
    return fail(ErrorCode::kInvalidArgument, name + ": map: " + valid.error().message);
  }
  const double extent = config.map.geometry.regionExtent();
  const double window_x = extent * config.map.window_regions.x;
  const double window_y = extent * config.map.window_regions.y;
  // The window is centred on the robot to the nearest region, so the map is inside it when it
  // is smaller than the window by one region.
  if (config.heightmap.size_m > std::min(window_x, window_y) - extent) {
    return fail(
        ErrorCode::kInvalidArgument,
        config.where("heightmap.size") + ": " + formatNumber(config.heightmap.size_m) +
            " m does not fit the rolling window (map.window x, y = " + formatNumber(window_x) +
            " x " + formatNumber(window_y) + " m; the map must be at least one region (" +
            formatNumber(extent) + " m) smaller)");
  }
  for (const std::string& layer : config.heightmap.layers) {
    const std::optional<dds::GridLayer> known = dds::gridLayerNamed(layer);
    if (known && dds::isNormalLayer(*known) && !isNdt(config.map.mode)) {
      return fail(ErrorCode::kInvalidArgument,
                  config.where("heightmap.layers") + ": " + layer +
                      " needs a map with surface normals (map.mode ndt-om or ndt-tm; it is " +
                      toString(config.map.mode) + ")");
    }
  }
  const double period = 1.0 / config.heightmap.rate_hz;
  if (config.queues.max_latency_s < 0.0) {
    // 250 ms at 5 Hz and faster; slower maps need a period, the lead and 35 ms to integrate in.
    config.queues.max_latency_s =
        std::max(QueueConfig{}.max_latency_s, period + config.heightmap.publish_lead_s + 0.035);
  }
  if (config.queues.max_latency_s > 0.0 &&
      config.queues.max_latency_s < period + config.heightmap.publish_lead_s) {
    return fail(ErrorCode::kInvalidArgument,
                config.where("queues.max_latency_s") + ": " +
                    formatNumber(config.queues.max_latency_s) +
                    " s is shorter than one publish period plus the lead (" +
                    formatNumber(period + config.heightmap.publish_lead_s) +
                    " s): most scans could never be published in time (0 turns the bound off)");
  }
  if (!config.save_map_on_exit.empty() && config.save_map_on_exit.back() == '/') {
    return fail(ErrorCode::kInvalidArgument,
                config.where("map.save_on_exit") + ": must be a file name, not a directory");
  }
  return config;
}

}  // namespace

std::string DaemonConfig::where(const std::string& key) const {
  const auto it = key_lines.find(key);
  return it == key_lines.end() ? path + ": " + key
                               : path + ": line " + std::to_string(it->second) + ": " + key;
}

std::size_t depthRayTablePixels(const SensorConfig& sensor) noexcept {
  if (sensor.kind != SensorKind::kDepth) {
    return 0;
  }
  constexpr std::size_t kLargestReserved = std::size_t{1280} * 800;
  return std::min(std::size_t{sensor.max_points} * sensor.downsample * sensor.downsample,
                  kLargestReserved);
}

Result<DaemonConfig> parseDaemonConfig(const std::string& text, const std::string& name) {
  try {
    return parse(YAML::Load(text), name);
  } catch (const YAML::Exception& e) {
    return fail(ErrorCode::kFormat,
                name + ": line " + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
}

Result<DaemonConfig> loadDaemonConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    return fail(ErrorCode::kIo, path + ": cannot open the configuration file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parseDaemonConfig(text.str(), path);
}

}  // namespace raymap::service
