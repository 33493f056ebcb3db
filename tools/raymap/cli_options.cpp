// SPDX-License-Identifier: BSD-3-Clause
// Shared mapping options.
#include "tools/raymap/cli_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string_view>
#include <tuple>
#include <utility>

#include "src/core/byte_size.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/io/atomic_file.hpp"
#include "src/map/cpu_backend.hpp"
#include "src/mapper/mapper_conversions.hpp"
#include "src/mapper/mapper_yaml.hpp"

namespace raymap::cli {

namespace {

void addNdtOptions(CLI::App& c, MappingFlags& f) {
  char text[160];
  const auto help = [&text](const char* what, double value) {
    std::snprintf(text, sizeof(text), "NDT: %s (default %g)", what, value);
    return std::string(text);
  };
  c.add_option("--ndt-sensor-noise", f.ndt_sensor_noise,
               help("range noise of the sensor (sigma), metres", NdtParams::kDefaultSensorNoise));
  c.add_option("--ndt-regulariser", f.ndt_regulariser,
               help("sigma added where a Gaussian is inverted, voxel edges, (0, 1]",
                    NdtParams::kDefaultRegulariser));
  c.add_option("--ndt-sample-threshold", f.ndt_sample_threshold,
               help("samples before a voxel's Gaussian shapes its misses",
                    NdtParams::kDefaultSampleThreshold));
  c.add_option("--ndt-reinit-probability", f.ndt_reinit_probability,
               help("a voxel below this occupancy probability restarts its Gaussian, (0, 0.5)",
                    NdtParams::kDefaultReinitProbability));
  c.add_option(
      "--ndt-reinit-count", f.ndt_reinit_count,
      help("samples a Gaussian needs before it can restart", NdtParams::kDefaultReinitCount));
  c.add_option("--ndt-adaptation-rate", f.ndt_adaptation_rate,
               "NDT: how strongly a ray through a surfel lowers its occupancy, [0, 1] (default: "
               "from the miss probability, clamp(2 (1 - 2 p_miss), 0, 1) = 0.2 for 0.45)");
  c.add_option("--ndt-initial-intensity-variance", f.ndt_initial_intensity_variance,
               help("NDT-TM: intensity variance after a voxel's first sample, intensity units^2",
                    NdtParams::kDefaultInitialIntensityVariance));
}

void addTsdfOptions(CLI::App& c, MappingFlags& f) {
  c.add_option("--tsdf-truncation", f.tsdf_truncation,
               "TSDF: truncation distance, metres: distances are kept within +-this, and rays go "
               "on this far behind their sample (default 3 voxel edges)");
  c.add_option("--tsdf-max-weight", f.tsdf_max_weight,
               "TSDF: largest voxel weight, rays (default 10000)");
  c.add_option("--tsdf-dropoff", f.tsdf_dropoff,
               "TSDF: behind the surface the ray weight falls from 1 at -this to 0 at minus the "
               "truncation, metres; 0 = constant weight (default 1 voxel edge)");
}

/// The --ndt-* and --tsdf-* options given (those of a --config file stay unless given).
void copyNdtAndTsdf(const MappingFlags& f, MapOptions& map) {
  const auto set = [](auto& field, const auto& flag) {
    if (flag) {
      field = flag;
    }
  };
  set(map.ndt.sensor_noise, f.ndt_sensor_noise);
  set(map.ndt.regulariser, f.ndt_regulariser);
  set(map.ndt.sample_threshold, f.ndt_sample_threshold);
  set(map.ndt.reinit_probability, f.ndt_reinit_probability);
  set(map.ndt.reinit_count, f.ndt_reinit_count);
  set(map.ndt.adaptation_rate, f.ndt_adaptation_rate);
  set(map.ndt.initial_intensity_variance, f.ndt_initial_intensity_variance);
  set(map.tsdf.truncation, f.tsdf_truncation);
  set(map.tsdf.max_weight, f.tsdf_max_weight);
  set(map.tsdf.dropoff, f.tsdf_dropoff);
}

}  // namespace

namespace {

/// The input's options: files (trajectory, scans) and bags (topics, poses, depth images).
void addInputOptions(CLI::App& c, MappingFlags& f) {
  c.add_option("--trajectory", f.trajectory,
               "Point clouds: sensor trajectory, lines 'time x y z [qw qx qy qz]'");
  c.add_option("--sensor-offset", f.sensor_offset,
               "Sensor position in the trajectory's body frame, metres: x,y,z (default 0,0,0); "
               "bags: the sensor in --base-frame when /tf_static has no chain to its frame");
  c.add_option("--scan-period", f.scan_period,
               "Without a 'scan' property: seconds per scan (<= 0: one scan)")
      ->capture_default_str();
  c.add_option("--topic", f.topics,
               "Bags: a PointCloud2 or depth Image (16UC1/32FC1) topic to map (repeat for several "
               "sensors; default: the only PointCloud2 topic, else the only Image topic)");
  c.add_option("--camera-info-topic", f.camera_info_topics,
               "Bags: the CameraInfo topic of each Image topic, in their order (default: the "
               "image topic's namespace + camera_info)");
  c.add_option("--downsample", f.downsample,
               "Bags, depth images: N x N pixel blocks give their nearest depth (1 = every pixel)")
      ->check(CLI::Range(1u, 64u))
      ->capture_default_str();
  c.add_option("--max-rate", f.max_rate_hz,
               "Bags: skip a sensor's messages above this rate, Hz (by header stamp; 0 = all)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  c.add_flag("--invalid-as-free", f.invalid_as_free,
             "Bags, depth images: pixels without a depth clear free space up to --max-range");
  c.add_option("--pose-topic", f.pose_topic,
               "Bags: the nav_msgs/msg/Odometry topic of the poses (default: the only one)");
  c.add_option("--pose-source", f.pose_source,
               "Bags: odometry, tf (the chain --world-frame -> --base-frame), or auto")
      ->check(CLI::IsMember({"auto", "odometry", "tf"}))
      ->capture_default_str();
  c.add_option("--world-frame", f.world_frame, "Bags, TF poses: the fixed frame")
      ->capture_default_str();
  c.add_option("--base-frame", f.base_frame,
               "Bags: the robot's body frame (poses, and /tf_static to each cloud's frame)")
      ->capture_default_str();
  c.add_option("--time-field", f.time_field,
               "Bags: the per-point time field (auto, a field name, or none)")
      ->capture_default_str();
  c.add_flag("--skip-damaged", f.skip_damaged,
             "Bags: map what a damaged or cut-off bag holds (skipping to its next indexed chunk) "
             "instead of failing, and say what was skipped");
}

/// The map's geometry and the range filter.
void addGeometryOptions(CLI::App& c, MappingFlags& f) {
  c.add_option("--resolution", f.resolution, "Voxel edge, metres")->capture_default_str();
  c.add_option("--region-voxels", f.region_voxels, "Voxels per region edge (4 to 128)")
      ->capture_default_str();
  c.add_option("--min-range", f.min_range, "Drop rays shorter than this, metres")
      ->capture_default_str();
  c.add_option("--max-range", f.max_range,
               "Clip longer rays (free space only, no hit), metres; 0 = none")
      ->capture_default_str();
  c.add_option("--max-ray-length", f.max_ray_length,
               "Reject longer rays as outlier returns (counted as out of bounds), metres; "
               "0 = none")
      ->capture_default_str();
}

/// The update rules: probabilities, semantics, the map mode and its layers' parameters.
void addUpdateOptions(CLI::App& c, MappingFlags& f) {
  c.add_option("--hit", f.hit, "Hit probability (default 0.9)");
  c.add_option("--miss", f.miss, "Miss probability (default 0.45)");
  c.add_option("--clamp-min", f.clamp_min,
               "Lower probability clamp (default 0.1192 = -2.0 log-odds)");
  c.add_option("--clamp-max", f.clamp_max,
               "Upper probability clamp (default 0.971 = 3.511 log-odds)");
  c.add_option("--threshold", f.threshold, "Occupied at or above this probability (default 0.5)");
  c.add_option("--semantics", f.semantics,
               "ray: every ray updates every voxel it crosses; scan: each voxel once per scan, "
               "occupied wins")
      ->check(CLI::IsMember({"ray", "scan"}))
      ->capture_default_str();
  c.add_option("--mode", f.mode,
               "occupancy: log-odds occupancy; ndt-om: occupancy whose misses follow each voxel's "
               "Gaussian (NDT-OM); ndt-tm: NDT-OM plus hit/miss counts and intensity (NDT-TM); "
               "decay: decay rates only (samples per metre of ray path in each voxel; no "
               "occupancy); tsdf: a truncated signed distance field only (no occupancy). "
               "occupancy+decay, ndt-om+decay, ndt-tm+decay: that mode with --decay-rate. NDT, "
               "decay and TSDF need --semantics ray")
      ->check(CLI::IsMember({"occupancy", "ndt-om", "ndt-tm", "decay", "tsdf", "occupancy+decay",
                             "ndt-om+decay", "ndt-tm+decay"}))
      ->capture_default_str();
  c.add_flag("--decay-rate", f.decay_rate,
             "Keep the metres of ray path in each voxel (decay rates) beside occupancy or NDT "
             "(--mode occupancy --decay-rate is occupancy with decay rates)");
  addNdtOptions(c, f);
  addTsdfOptions(c, f);
}

/// The integration backend and its device.
void addBackendOptions(CLI::App& c, MappingFlags& f) {
  c.add_option("--backend", f.backend, "Integration backend: cpu, opencl or cuda")
      ->check(CLI::IsMember({"cpu", "opencl", "cuda"}))
      ->capture_default_str();
  c.add_option("--threads", f.threads, "CPU worker threads (0 = all cores, 1 = reference)")
      ->capture_default_str();
  c.add_option("--opencl-platform", f.opencl_platform,
               "OpenCL platform: index or name substring (see raymap devices)");
  c.add_option("--opencl-device", f.opencl_device,
               "OpenCL device: index or name substring; default: first GPU, else first device");
  c.add_option("--cuda-device", f.cuda_device,
               "CUDA device ordinal (see raymap devices; CUDA_VISIBLE_DEVICES applies)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  c.add_option("--gpu-cache", f.gpu_cache,
               "Device region cache: a size (512MiB), a region count (2000regions), or auto = "
               "min(1 GiB, half the device memory)")
      ->capture_default_str();
  c.add_option("--gpu-memory", f.gpu_memory,
               "Where the device keeps the map: cache (device buffers), shared (the host map in "
               "place, for devices sharing memory with the host), or auto")
      ->check(CLI::IsMember({"auto", "cache", "shared"}))
      ->capture_default_str();
  c.add_option("--opencl-span-work", f.opencl_span_work,
               "How OpenCL work-items share a batch's ray spans: span (one per span, atomic voxel "
               "updates), region (one per region, plain updates), or auto (region on CPU "
               "devices such as PoCL, span on GPUs)")
      ->check(CLI::IsMember({"auto", "span", "region"}))
      ->capture_default_str();
  c.add_option("--device-planning", f.device_planning,
               "Where OpenCL and CUDA batches are planned (each ray's regions, span records, hit "
               "groups): host, or device (the host only places each batch's distinct regions); "
               "the maps are the same")
      ->check(CLI::IsMember({"host", "device"}))
      ->capture_default_str();
  c.add_option("--fallback", f.fallback,
               "If the device backend cannot start: none (fail) or cpu (warn, map on the CPU)")
      ->check(CLI::IsMember({"none", "cpu"}))
      ->capture_default_str();
}

}  // namespace

void addMappingOptions(CLI::App& c, MappingFlags& f) {
  f.command = &c;
  c.add_option("--config", f.config_file,
               "A YAML file whose map: and backend: sections (raymapd's keys, e.g. its own "
               "configuration) set the map and backend options; flags given as well win")
      ->check(CLI::ExistingFile);
  addInputOptions(c, f);
  addGeometryOptions(c, f);
  addUpdateOptions(c, f);
  addBackendOptions(c, f);
  c.add_option("--segment-length", f.segment_length,
               "Split longer rays into equal pieces, metres; 0 = off")
      ->capture_default_str();
  auto* reverse = c.add_flag("--reverse", f.reverse, "Walk rays from the sample to the sensor");
  auto* forward = c.add_flag("--forward", f.forward,
                             "Walk rays from the sensor (default on the CPU; device backends "
                             "default to --reverse)");
  reverse->excludes(forward);
  c.add_flag("--no-mean", f.no_mean, "Do not keep the voxel-mean layer");
  addMaxMemoryOption(c, f.max_memory);
  addTierOptions(c, f.tiers);
  c.add_option("--batch-rays", f.batch_rays,
               "Prepared rays per backend call (default: 32768 on the CPU per ray, except NDT; "
               "262144 otherwise)")
      ->check(CLI::Range(std::size_t{1024}, std::size_t{1} << 26));
}

Result<Vec3d> parseVector(const std::string& text, const std::string& option) {
  Vec3d v;
  char c1 = 0;
  char c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !v.isFinite()) {
    return fail(ErrorCode::kInvalidArgument,
                option + ": expected three numbers 'x,y,z' in metres, got '" + text + "'");
  }
  std::string rest;
  if (in >> rest) {
    return fail(ErrorCode::kInvalidArgument, option + ": unexpected '" + rest + "' after 'x,y,z'");
  }
  return v;
}

Expected<void, Error> writeTextFile(const std::string& path, const std::string& text) {
  auto writer = io::AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = writer->write(text + "\n"); !ok) {
    return ok;
  }
  return writer->commit();
}

namespace {

/// --gpu-cache: "auto", a byte size ("512MiB") or a region count ("2000regions").
Expected<void, Error> applyCacheSize(const std::string& text, BackendOptions* choice) {
  auto size = parseCacheSize(text);
  if (!size) {
    return fail(ErrorCode::kInvalidArgument, "--gpu-cache: " + size.error().message);
  }
  choice->gpu_cache_bytes = size->bytes;
  choice->gpu_cache_regions = size->regions;
  return {};
}

}  // namespace

/// The backend flags (those given, with a --config file) over `c.backend`.
template <class Given>
Result<MapperConfig> applyBackendFlags(const MappingFlags& f, const Given& given, MapperConfig c) {
  BackendOptions& b = c.backend;
  const auto set = [&](const char* flag, auto& field, const auto& value) {
    if (given(flag)) {
      field = value;
    }
  };
  set("--backend", b.name, f.backend);
  set("--threads", b.threads, f.threads);
  set("--opencl-platform", b.opencl_platform, f.opencl_platform);
  set("--opencl-device", b.opencl_device, f.opencl_device);
  set("--cuda-device", b.cuda_device, f.cuda_device);
  set("--fallback", b.fallback_cpu, f.fallback == "cpu");
  set("--gpu-memory", b.gpu_memory, f.gpu_memory);
  set("--opencl-span-work", b.opencl_span_work, f.opencl_span_work);
  set("--device-planning", b.device_planning, f.device_planning);
  b.batch_rays = f.batch_rays;
  if (given("--gpu-cache")) {
    if (auto cache = applyCacheSize(f.gpu_cache, &b); !cache) {
      return Unexpected(cache.error());
    }
  }
  return c;
}

Result<MapperConfig> toMapperConfig(const MappingFlags& f, std::vector<std::string>* warnings) {
  MapperConfig c;
  if (!f.config_file.empty()) {
    std::vector<std::string> notes;
    auto loaded = mapper::loadMapperConfig(f.config_file, c, notes);
    if (!loaded) {
      return Unexpected(loaded.error());
    }
    c = *loaded;
    if (warnings != nullptr) {
      warnings->insert(warnings->end(), notes.begin(), notes.end());
    }
  }
  // Without --config every flag applies (its default included); with one, a flag the user gave.
  const auto given = [&](const char* flag) { return f.config_file.empty() || f.given(flag); };
  MapOptions& m = c.map;
  if (given("--resolution")) {
    m.resolution = f.resolution;
  }
  if (given("--region-voxels")) {
    m.region_voxels = f.region_voxels;
  }
  if (given("--semantics")) {
    m.semantics = f.semantics == "scan" ? Semantics::kPerScan : Semantics::kPerRay;
  }
  if (given("--no-mean")) {
    m.voxel_mean = !f.no_mean;
  }
  m.decay_rate = m.decay_rate || f.decay_rate;
  if (given("--mode")) {
    // CLI11 checked the name against the same list.
    if (auto mode = mapper::applyModeName(f.mode, m); !mode) {
      return Unexpected(mode.error());
    }
  }
  copyNdtAndTsdf(f, m);
  m.hit_probability = f.hit.value_or(m.hit_probability);
  m.miss_probability = f.miss.value_or(m.miss_probability);
  m.occupied_threshold = f.threshold.value_or(m.occupied_threshold);
  m.clamp_min_probability = f.clamp_min.value_or(m.clamp_min_probability);
  m.clamp_max_probability = f.clamp_max.value_or(m.clamp_max_probability);
  auto budget = parseByteSize(f.max_memory);
  if (!budget) {
    return fail(ErrorCode::kInvalidArgument, "--max-memory: " + budget.error().message);
  }
  m.max_memory_bytes = *budget;
  auto tiers = toTierConfig(f.tiers, "");  // the spill folder follows the output (runPopulate)
  if (!tiers) {
    return Unexpected(tiers.error());
  }
  m.tiers.enabled = tiers->enabled;
  m.tiers.compressed_memory_bytes = tiers->compressed_bytes;
  m.tiers.spill_dir = tiers->spill_dir;
  c.rays.min_range = f.min_range;
  c.rays.max_range = f.max_range;
  c.rays.max_ray_length = f.max_ray_length;
  c.rays.segment_length = f.segment_length;
  c.rays.walk = f.reverse   ? RayOptions::Walk::kReverse
                : f.forward ? RayOptions::Walk::kForward
                            : RayOptions::Walk::kAuto;
  return applyBackendFlags(f, given, c);
}

Result<PopulateOptions> toPopulateOptions(const std::string& input, const MappingFlags& f) {
  PopulateOptions o;
  o.input = input;
  auto offset = parseVector(f.sensor_offset.empty() ? "0,0,0" : f.sensor_offset, "--sensor-offset");
  if (!offset) {
    return Unexpected(offset.error());
  }
  if (f.max_rate_hz != 0.0 && f.max_rate_hz < 0.01) {
    return fail(ErrorCode::kInvalidArgument, "--max-rate: must be 0 (all) or at least 0.01 Hz");
  }
  RecordingOptions& r = o.recording;
  r.trajectory_path = f.trajectory;
  r.scan_period_s = f.scan_period;
  r.sensor_offset = toEigen(*offset);
  BagOptions& b = r.bag;
  b.topics = f.topics;
  b.pose_topic = f.pose_topic;
  b.pose_source = f.pose_source == "odometry" ? BagOptions::PoseSource::kOdometry
                  : f.pose_source == "tf"     ? BagOptions::PoseSource::kTf
                                              : BagOptions::PoseSource::kAuto;
  b.world_frame = f.world_frame;
  b.base_frame = f.base_frame;
  b.time_field = f.time_field;
  b.camera_info_topics = f.camera_info_topics;
  b.downsample = f.downsample;
  b.depth_min_range = f.min_range;
  b.depth_max_range = f.max_range;
  b.invalid_as_free = f.invalid_as_free;
  b.max_rate_hz = f.max_rate_hz;
  b.skip_damaged = f.skip_damaged;
  if (!f.sensor_offset.empty()) {
    b.sensor_offset = toEigen(*offset);
  }
  const bool is_bag = bag::isBag(input);
  if (is_bag && !f.trajectory.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                "--trajectory: " + input + " is a bag: its poses come from --pose-topic or TF");
  }
  if (!is_bag && (!f.topics.empty() || !f.pose_topic.empty() || f.pose_source != "auto" ||
                  f.time_field != "auto" || !f.camera_info_topics.empty() || f.downsample != 1 ||
                  f.invalid_as_free || f.max_rate_hz != 0.0 || f.skip_damaged)) {
    return fail(ErrorCode::kInvalidArgument,
                input +
                    " is not a bag: --topic, --pose-topic, --pose-source, --time-field, "
                    "--camera-info-topic, --downsample, --invalid-as-free, --max-rate and "
                    "--skip-damaged apply to bags only");
  }
  std::vector<std::string> warnings;
  auto config = toMapperConfig(f, &warnings);
  if (!config) {
    return Unexpected(config.error());
  }
  for (const std::string& warning : warnings) {  // --config: a key in an older spelling
    std::fprintf(stderr, "raymap %s: warning: %s\n",
                 f.command != nullptr ? f.command->get_name().c_str() : "", warning.c_str());
  }
  // One conversion, the library's (the same as raymap::Mapper's): it checks the combinations.
  auto map = mapper::toMapConfig(config->map);
  if (!map) {
    return Unexpected(map.error());
  }
  o.map = *map;
  auto filter = mapper::toRayFilter(config->rays, config->backend.name != "cpu");
  if (!filter) {
    return Unexpected(filter.error());
  }
  o.filter = *filter;
  if (f.segment_length > 0.0 && f.segment_length < config->map.resolution) {
    return fail(ErrorCode::kInvalidArgument,
                "--segment-length must be 0 (off) or at least the resolution");
  }
  if (f.threads > CpuBackendOptions::kMaxThreads) {
    return fail(ErrorCode::kInvalidArgument, "--threads must be at most " +
                                                 std::to_string(CpuBackendOptions::kMaxThreads) +
                                                 " (got " + std::to_string(f.threads) + ")");
  }
  o.backend = mapper::toBackendChoice(config->backend);
  o.batch_rays = f.batch_rays;
  return o;
}

}  // namespace raymap::cli
