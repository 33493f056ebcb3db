// SPDX-License-Identifier: BSD-3-Clause
// Command-line options shared by the mapping subcommands, and their conversion and validation.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/mapper_config.hpp"
#include <CLI/CLI.hpp>

#include "tools/raymap/memory_tiers.hpp"
#include "tools/raymap/populate.hpp"

namespace raymap::cli {

/// @brief Options as typed by the user, before conversion (probabilities, sizes, vectors).
struct MappingFlags {
  /// --config: a YAML file whose map: and backend: sections (raymapd's names) set the options;
  /// a flag given as well wins.
  std::string config_file;
  /// The subcommand the flags belong to, to tell a flag given from its default (--config).
  const CLI::App* command = nullptr;
  /// @brief Whether `flag` was given on the command line.
  bool given(const char* flag) const { return command != nullptr && command->count(flag) > 0; }
  std::string trajectory;
  std::string sensor_offset;  ///< "" when not given: 0,0,0 (bags: only with a TF chain)
  double scan_period = io::RaySourceOptions::kDefaultScanPeriod;
  double resolution = MapGeometry::kDefaultResolution;
  int region_voxels = MapGeometry::kDefaultRegionVoxels;
  double min_range = 0.0;
  double max_range = 0.0;
  double max_ray_length = 1000.0;
  std::optional<double> hit;
  std::optional<double> miss;
  std::optional<double> clamp_min;
  std::optional<double> clamp_max;
  std::optional<double> threshold;
  std::string semantics = "ray";
  std::string mode = "occupancy";  ///< occupancy, ndt-om, ndt-tm, decay (occupancy + decay), tsdf
  bool decay_rate = false;         ///< --decay-rate: the traversal layer on any mode
  // NDT parameters (unset: NdtParams defaults); only with --mode ndt-om / ndt-tm.
  std::optional<double> ndt_sensor_noise;
  std::optional<double> ndt_regulariser;
  std::optional<std::uint32_t> ndt_sample_threshold;
  std::optional<double> ndt_reinit_probability;
  std::optional<std::uint32_t> ndt_reinit_count;
  std::optional<double> ndt_adaptation_rate;
  std::optional<double> ndt_initial_intensity_variance;
  // TSDF parameters (unset: TsdfParams defaults); only with --mode tsdf.
  std::optional<double> tsdf_truncation;
  std::optional<double> tsdf_max_weight;
  std::optional<double> tsdf_dropoff;
  std::string backend = "cpu";
  unsigned threads = 0;
  std::string opencl_platform;
  std::string opencl_device;
  int cuda_device = 0;
  std::string gpu_cache = "auto";
  std::string gpu_memory = "auto";
  std::string opencl_span_work = "auto";
  std::string device_planning = "host";
  std::string fallback = "none";
  double segment_length = 0.0;
  bool reverse = false;
  bool forward = false;
  bool no_mean = false;
  std::string max_memory = "4GiB";
  TierFlags tiers;             ///< --compressed-memory, --spill-dir, --no-tiers
  std::size_t batch_rays = 0;  // 0: the backend's Backend::preferredBatchRays()
  // rosbag2 input (a bag directory, .mcap or .db3)
  std::vector<std::string> topics;  ///< --topic: PointCloud2 or depth Image topics
  std::string pose_topic;           ///< --pose-topic: nav_msgs/msg/Odometry topic
  std::string pose_source = "auto";
  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  std::string time_field = "auto";
  // depth images in bags (sensor_msgs/msg/Image + CameraInfo)
  std::vector<std::string> camera_info_topics;  ///< --camera-info-topic, per Image topic
  std::uint32_t downsample = 1;                 ///< --downsample
  bool invalid_as_free = false;                 ///< --invalid-as-free
  bool skip_damaged = false;                    ///< --skip-damaged
  double max_rate_hz = 0.0;                     ///< --max-rate
};

/// @brief Registers the input and mapping options on a subcommand.
void addMappingOptions(CLI::App& command, MappingFlags& flags);

/// @brief The library configuration the mapping flags ask for (raymap::MapperConfig, the same
/// a program linking the library fills in); what the flags cannot express wrongly is checked
/// by the library's one conversion (mapper::toMapConfig), naming configuration keys that
/// withCliFlags() shows as flags.
Result<MapperConfig> toMapperConfig(const MappingFlags& flags,
                                    std::vector<std::string>* warnings = nullptr);

/// @brief Converts and validates the flags; errors name the option and the reason.
Result<PopulateOptions> toPopulateOptions(const std::string& input, const MappingFlags& flags);

/// @brief Parses "x,y,z" (metres).
Result<Vec3d> parseVector(const std::string& text, const std::string& option);

/// @brief Writes `text` and a newline to `path` (temporary file + rename; a staged temporary
/// of io::StagedOutputs in place).
Expected<void, Error> writeTextFile(const std::string& path, const std::string& text);

}  // namespace raymap::cli
