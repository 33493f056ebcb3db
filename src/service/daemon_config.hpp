// SPDX-License-Identifier: BSD-3-Clause
// The configuration of raymapd: one YAML file read and validated at start-up. Every error names
// the file, the line, the key and the reason.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/device/backend_choice.hpp"
#include "src/heightmap/costmap.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/trajectory.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/security/security_config.hpp"

namespace raymap::service {

using backends::BackendChoice;

/// What a sensor publishes.
enum class SensorKind : std::uint8_t {
  kPointCloud,  ///< sensor_msgs/PointCloud2 (a lidar, or a camera driver's point cloud)
  kDepth,       ///< sensor_msgs/Image (16UC1 mm or 32FC1 m) with sensor_msgs/CameraInfo
};

/// The most sensors one raymapd takes (per-sensor counters are fixed arrays).
inline constexpr std::size_t kMaxSensors = pipeline::kMaxSensors;

/// @brief One lidar publishing sensor_msgs/PointCloud2, or one depth camera publishing
/// sensor_msgs/Image and sensor_msgs/CameraInfo (`kind: depth`).
struct SensorConfig {
  std::string name = "lidar";
  SensorKind kind = SensorKind::kPointCloud;
  std::string topic = "rt/points";  ///< DDS topic ("rt/" + the ROS topic name)
  /// Depth cameras: the CameraInfo topic; default the image topic's namespace plus
  /// "camera_info" (rt/camera/depth/image_rect_raw -> rt/camera/depth/camera_info).
  std::string camera_info_topic;
  /// Frame of the points. Empty: whatever the message's header.frame_id says. tf_static
  /// transforms from the base frame to this frame override `extrinsic` when they arrive.
  /// A depth camera's frame is its optical frame (x right, y down, z forward).
  std::string frame;
  io::Pose extrinsic;         ///< sensor in the base frame (metres; quaternion w, x, y, z)
  double min_range_m = 0.5;   ///< shorter returns are the robot itself: dropped
  double max_range_m = 20.0;  ///< longer rays clear free space up to here only
  /// Larger clouds are dropped whole (and counted). Depth cameras: points after down-sampling
  /// (default 307,200: a 640 x 480 image at downsample 1).
  std::uint32_t max_points = 262144;
  /// Per-point time field: "auto" (t, time, timestamp by their usual types), "none" or a name.
  std::string time_field = "auto";
  /// Points whose time is further than this from header.stamp (seconds), or not finite, are
  /// left out and counted: a corrupt time field costs the point, not the scan.
  double max_time_offset_s = 1.0;
  // ---- depth cameras ----
  /// N: each N x N block of pixels gives its nearest valid depth (msgs::DepthDecodeOptions).
  std::uint32_t downsample = 1;
  /// Pixels without a depth (0, NaN, inf) clear free space up to max_range along their ray.
  bool invalid_as_free = false;
  /// Frames (or clouds) arriving faster than this are dropped and counted; 0 = every one.
  double max_rate_hz = 0.0;
};

/// @brief Where the robot's pose comes from.
struct PoseConfig {
  enum class Source : std::uint8_t { kOdometry, kTf };
  Source source = Source::kOdometry;
  std::string odometry_topic = "rt/odom";  ///< nav_msgs/Odometry (source: odometry)
  std::string world_frame = "odom";        ///< the map's frame; GridMaps are published in it
  std::string base_frame = "base_link";    ///< the robot body the pose describes
  std::uint32_t history = 4096;            ///< poses kept for deskewing (ring)
  double max_wait_s = 0.2;  ///< a scan waits this long for poses to cover it, then is dropped
  double hold_s = 0.02;     ///< beyond the newest pose, up to this long, the newest is used
  /// A pose stamped this long before the newest means the clock went back (a bag played in a
  /// loop, a simulation reset): the pose history and the deskewing start over (counted, WARN).
  double time_reset_s = 1.0;
  /// A pose this far (metres) from the one before is a jump (relocalisation, an odometry reset):
  /// counted and reported (WARN), the pose history starts over; 0 = off.
  double max_jump_m = 5.0;
  /// What a jump does to the map: keep it, or clear the rolling window (what was mapped is in
  /// the frame before the jump).
  bool clear_on_jump = false;
};

/// @brief The published height map.
struct HeightmapConfig {
  double rate_hz = 5.0;
  double size_m = 20.0;
  heightmap::HeightmapMode mode = heightmap::HeightmapMode::kPlanar;
  double min_clearance_m = 0.5;
  std::optional<double> floor_depth_m;
  std::optional<double> ceiling_height_m;
  bool virtual_surfaces = false;
  /// Height of the base frame above the ground (metres): the search reference is base z minus it.
  double base_height_m = 0.0;
  /// The map is generated at least this long before each publish instant, which is then kept
  /// exactly. The lead grows with the measured generation time (the worst of the last 8 cycles,
  /// waiting for the map included, times 1.5, plus 2 ms) up to publish_lead_max_s.
  double publish_lead_s = 0.015;
  double publish_lead_max_s = 0.1;
  /// The GridMap's layers by name (dds::gridLayerName), in any order; empty: every layer the map
  /// has (elevation, clearance, kind, observed_count, and normal_x/y/z for NDT maps). Each costs
  /// cells x 4 bytes a message.
  std::vector<std::string> layers;
};

/// @brief DDS: domain, Cyclone configuration, output topics.
struct DdsConfig {
  std::uint32_t domain = 0;  ///< = ROS_DOMAIN_ID of the ROS 2 side
  /// Cyclone DDS configuration (a file:// URI or XML); empty: the CYCLONEDDS_URI environment.
  std::string cyclonedds_uri;
  /// Receive buffer of the DDS sockets (MiB); 0: sized for the sensors' clouds, within the
  /// kernel's net.core.rmem_max (service::planReceiveBuffer). A size set in the Cyclone
  /// configuration wins over both.
  std::uint32_t receive_buffer_mb = 0;
  /// Largest burst of a map's data resent at once to a reader that missed part of it (KiB;
  /// dds::DomainSettings::repair_burst_bytes). Maps go out whole; a planner whose socket buffer
  /// is the OS default (208 KiB, of which a 64 KB datagram takes 128 KiB) loses what did not
  /// fit and gets it again in bursts it can hold, every map. 0: Cyclone's own repairs (up to
  /// 1 MiB at once). Settings of the Cyclone configuration win.
  std::uint32_t repair_burst_kb = 64;
  std::string grid_map_topic = "rt/height_map";
  std::string diagnostics_topic = "rt/diagnostics";
  double diagnostics_rate_hz = 1.0;
  std::string voxels_topic;  ///< occupied voxels as PointCloud2; empty: off
  /// A Nav2 costmap (nav_msgs/OccupancyGrid) with each height map; empty: off.
  std::string costmap_topic;
  double voxels_rate_hz = 1.0;
  std::uint32_t voxels_max_points = 200000;
  /// DDS Security (the `dds.security` section; docs/security.md). Without the section, ROS 2's
  /// ROS_SECURITY_* variables decide, as for any ROS 2 node (security_in_file false).
  security::SecurityConfig security;
  bool security_in_file = false;
};

/// @brief Buffers between the threads.
struct QueueConfig {
  std::uint32_t scan_slots = 4;     ///< decoded scans waiting for the integrator (+1 in use)
  std::uint32_t pose_queue = 1024;  ///< pose messages waiting for the integrator
  std::uint32_t batch_rays =
      16384;  ///< rays per backend call (bounds how long a batch holds the map)
  double batch_deadline_s =
      0.005;  ///< a partial batch is integrated once its oldest ray is this old
  /// The integrator holds the map at most about this long at a time (seconds), then lets a
  /// waiting publisher in (per-ray semantics; per-scan holds one whole scan).
  double max_lock_hold_s = 0.005;
  /// Latency bound, seconds from a cloud's arrival to the first height map that contains it:
  /// scans that cannot make it are subsampled (every k-th point) or dropped, and counted. 0: off.
  double max_latency_s = 0.25;
  /// How the bound sheds: subsample scans by up to max_subsample, dropping only what needs more
  /// (true), or drop whole scans only (false: queues.shed: drop).
  bool shed_subsample = true;
  std::uint32_t max_subsample = 8;
  /// When the bound applies: only while the integrator is saturated (false: the default; at the
  /// nominal rate a scan keeps the latency its own size and phase give it), or always (true:
  /// queues.shed_when: always, latency is then bounded even when the CPU is merely slow).
  bool shed_always = false;
};

/// @brief Scheduling of one thread.
struct ThreadConfig {
  int priority = 0;       ///< SCHED_FIFO 1..99; 0 = normal scheduling
  std::vector<int> cpus;  ///< CPU affinity; empty = any
};

struct RealtimeConfig {
  bool lock_memory = true;  ///< mlockall when RLIMIT_MEMLOCK allows it
  ThreadConfig ingest{40, {}};
  ThreadConfig integrator{30, {}};
  ThreadConfig publisher{60, {}};
};

/// @brief What the service calls unhealthy, and how it names itself in diagnostics.
struct HealthConfig {
  /// No scan integrated for this long (seconds) while running (or since start): the pipeline
  /// status is ERROR and no GridMap is published (a planner must not take the last one for the
  /// present). The systemd watchdog keeps being pinged: a restart cannot make the input come.
  double stale_after_s = 1.0;
  /// Seconds after start during which no cloud at all is "waiting for the first cloud" (WARN)
  /// rather than the staleness ERROR: systemd starts the service before the sensor drivers.
  double startup_grace_s = 10.0;
  /// The share of the rays offered (after decoding; points without a return are not offered)
  /// that must go into the map over a diagnostics window: below it WARN, none of them ERROR.
  /// Rays are rejected by range (min_range), the map's bounds, max_ray_length or the window.
  double min_integrated_fraction = 0.5;
  /// diagnostic_msgs hardware_id; empty: "<host name>/<name>", so that two services on one
  /// domain are told apart.
  std::string hardware_id;
};

/// @brief Everything raymapd reads from its YAML file.
struct DaemonConfig {
  std::string path;  ///< the file it came from
  /// Keys and values the file writes in an older form, each with its new name (they are read
  /// until the next release): logged at start and printed by --check-config.
  std::vector<std::string> warnings;
  /// The service's name: the diagnostics' status names ("<name>: pipeline", ...) and the default
  /// hardware_id.
  std::string name = "raymapd";
  HealthConfig health;
  MapConfig map;  ///< always the rolling policy
  BackendChoice backend;
  PoseConfig pose;
  std::vector<SensorConfig> sensors;
  HeightmapConfig heightmap;
  heightmap::CostmapParams costmap;  ///< the `costmap` section (used when dds.costmap_topic)
  DdsConfig dds;
  QueueConfig queues;
  RealtimeConfig realtime;
  std::string save_map_on_exit;  ///< map file written (atomically) at shutdown; empty: none
  /// The line (1-based) of every key the file has, by key path ("map.save_on_exit",
  /// "sensors[0].min_range"): checks that involve several keys name a line too.
  std::map<std::string, int> key_lines;

  /// @brief "FILE: line N: KEY" (or "FILE: KEY" for a key the file does not have): the start of
  /// an error about `key` found after parsing.
  std::string where(const std::string& key) const;
};

/// @brief Pixels a depth camera's ray table is sized for at start-up: every pixel of an image
/// that max_points covers at its downsample, at most 1280 x 800 (8 MB of rays; a larger camera's
/// table grows once, when its first CameraInfo arrives). 0 for point clouds.
std::size_t depthRayTablePixels(const SensorConfig& sensor) noexcept;

/// @brief Reads and validates a configuration file.
Result<DaemonConfig> loadDaemonConfig(const std::string& path);
/// @brief Same, from text (`name` stands for the file in messages).
Result<DaemonConfig> parseDaemonConfig(const std::string& text, const std::string& name);

}  // namespace raymap::service
