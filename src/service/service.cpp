// SPDX-License-Identifier: BSD-3-Clause
// Service: start-up wiring and the four thread loops (see the header's design note).
#include "src/service/service.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "raymap/assert.hpp"
#include <unistd.h>

#include "platform/allocation_scope.hpp"
#include "platform/clock.hpp"
#include "platform/errno_text.hpp"
#include "platform/notify.hpp"
#include "platform/pi_mutex.hpp"
#include "platform/rt.hpp"
#include "platform/socket_buffers.hpp"
#include "platform/wakeup.hpp"
#include "src/dds/diagnostics_message.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/grid_map_message.hpp"
#include "src/dds/occupancy_grid_message.hpp"
#include "src/dds/point_cloud_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/heightmap/costmap.hpp"
#include "src/io/map_file.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/msgs/pose.hpp"
#include "src/pipeline/frame_writers.hpp"
#include "src/pipeline/heightmap_cycle.hpp"
#include "src/pipeline/integrator.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "src/pipeline/sensor_decoder.hpp"
#include "src/pipeline/stamp_gaps.hpp"
#include "src/pipeline/tf_router.hpp"
#include "src/service/daemon_security.hpp"
#include "src/service/diagnostics_reporter.hpp"
#include "src/service/log.hpp"
#include "src/service/pending_scans.hpp"
#include "src/service/scan_handoff.hpp"
#include "src/service/startup_checks.hpp"

namespace raymap::service {

using backends::createBackend;
using backends::CreatedBackend;
using backends::createHeightmapGenerator;
namespace {

constexpr int kTfPerMessage = 64;  // transforms decoded per TFMessage
constexpr int kTakePerWake = 16;   // samples taken per reader per wake-up

std::int64_t seconds(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

std::uint64_t cpuMask(const std::vector<int>& cpus) {
  std::uint64_t mask = 0;
  for (int cpu : cpus) {
    mask |= std::uint64_t{1} << cpu;
  }
  return mask;
}

// Waitset tokens: sensors are 0..n-1; the pose readers follow; then the depth cameras'
// CameraInfo readers, kCameraInfoToken + sensor.
constexpr std::intptr_t kOdometryToken = 1000;
constexpr std::intptr_t kTfToken = 1001;
constexpr std::intptr_t kTfStaticToken = 1002;
constexpr std::intptr_t kCameraInfoToken = 2000;

/// How one configured sensor's messages are decoded.
pipeline::SensorDecodeSettings decodeSettings(const SensorConfig& s) {
  pipeline::SensorDecodeSettings d;
  d.kind = s.kind == SensorKind::kDepth ? pipeline::SensorInputKind::kDepth
                                        : pipeline::SensorInputKind::kPointCloud;
  d.time_field = s.time_field;
  d.depth.downsample = s.downsample;
  d.depth.min_range_m = static_cast<float>(s.min_range_m);
  d.depth.max_range_m = static_cast<float>(s.max_range_m);
  d.depth.invalid_as_free = s.invalid_as_free;
  d.frame = s.frame;
  d.max_rate_hz = s.max_rate_hz;
  // The table covers every pixel; max_points counts the points after down-sampling.
  d.reserve_pixels = depthRayTablePixels(s);
  d.max_points = s.max_points;
  return d;
}

/// The publisher's timetable: publish instants t0 + k * period on the monotonic clock (absolute
/// deadlines do not drift, whatever each cycle costs), and the lead before each instant that
/// generation is given. The lead adapts to what generation has been taking (waiting for the map
/// included), so the publish instant holds when the integrator is saturated or the machine busy.
/// Publisher thread only; allocates nothing.
class PublishTimetable {
 public:
  PublishTimetable(std::int64_t period, std::int64_t lead_min, std::int64_t lead_max) noexcept
      : period_(period),
        lead_min_(lead_min),
        lead_max_(lead_max),
        lead_(lead_min),
        next_(platform::monotonicNowNs() + period) {}
  std::int64_t period() const noexcept { return period_; }
  std::int64_t next() const noexcept { return next_; }
  std::int64_t lead() const noexcept { return lead_; }
  /// Moves to the next publish instant; returns how many whole periods had already passed
  /// (skipped, not published in a burst; the previous publish is then no longer a period ago).
  std::int64_t advance() noexcept {
    next_ += period_;
    const std::int64_t now = platform::monotonicNowNs();
    if (now <= next_) {
      return 0;
    }
    const std::int64_t missed = (now - next_) / period_ + 1;
    next_ += missed * period_;
    previous_publish = 0;
    return missed;
  }
  /// Takes how long one generation took; the lead covers the worst of the last 8 and a half.
  void recordGenerate(std::int64_t ns) noexcept {
    recent_generate_[recent_next_++ % recent_generate_.size()] = ns;
    const std::int64_t worst = *std::max_element(recent_generate_.begin(), recent_generate_.end());
    lead_ = std::clamp(worst + worst / 2 + 2000000, lead_min_, lead_max_);
  }
  /// When the last map went out (0: not a period ago: a gap, a skip or none yet).
  std::int64_t previous_publish = 0;

 private:
  std::int64_t period_;
  std::int64_t lead_min_;
  std::int64_t lead_max_;
  std::int64_t lead_;
  std::int64_t next_;
  std::array<std::int64_t, 8> recent_generate_{};  // ns, the last 8 cycles
  std::size_t recent_next_ = 0;
};

}  // namespace

struct Service::Impl {
  DaemonConfig config;
  std::optional<VoxelMap> map;
  CreatedBackend backend;
  std::unique_ptr<heightmap::HeightmapGenerator> generator;
  platform::PiMutex map_mutex;
  std::unique_ptr<pipeline::ScanMailbox> mailbox;
  std::unique_ptr<pipeline::PoseQueue> poses;
  std::unique_ptr<pipeline::ArrivalQueue> arrivals;
  pipeline::LatestPosition latest;
  pipeline::PipelineStats stats;
  std::unique_ptr<pipeline::Integrator> integrator;
  std::unique_ptr<pipeline::HeightmapCycle> cycle;

  // DDS (destroyed before the participant: members are destroyed in reverse order).
  std::optional<dds::Participant> participant;
  std::vector<dds::RawReader> cloud_readers;  // PointCloud2 or Image, one per sensor
  std::vector<std::optional<dds::RawReader>> camera_info_readers;  // depth cameras
  std::optional<dds::RawReader> odometry_reader;
  std::optional<dds::RawReader> tf_reader;
  std::optional<dds::RawReader> tf_static_reader;
  std::optional<dds::Waitset> waitset;
  /// Ingest thread: scans held as received while a decoded one waits (drop before decode).
  /// Declared after the readers, so their buffers go back to Cyclone before the participant.
  std::unique_ptr<PendingScans> pending;
  std::optional<dds::Writer> grid_map_writer;
  std::optional<dds::Writer> diagnostics_writer;
  std::optional<dds::Writer> voxels_writer;
  std::optional<dds::Writer> costmap_writer;                   // dds.costmap_topic set
  std::unique_ptr<dds::OccupancyGridMessage> costmap_message;  // with its writer
  /// Matches writers of our height-map topic in other participants: another raymapd (or any
  /// other publisher) there is an ERROR (health).
  std::optional<dds::RawReader> map_publisher_watch;
  std::unique_ptr<dds::GridMapMessage> grid_map_message;
  std::unique_ptr<dds::PointCloudMessage> voxels_message;
  std::vector<float> voxels_xyz;
  std::unique_ptr<DiagnosticsReporter> reporter;

  // Ingest-thread state: each sensor's decoder (depth cameras: with their pixel rays).
  std::vector<pipeline::SensorDecoder> decoders;
  /// Writers of the base frame's transform on rt/tf (pose.source tf; ingest thread writes).
  pipeline::FrameWriters base_writers;
  /// Per sensor: gaps in the stamps of what arrives (ingest thread).
  std::array<pipeline::StampGaps, pipeline::kMaxSensors> stamp_gaps{};
  /// This process's UDP sockets, found once every reader exists (diagnostics thread).
  std::optional<platform::UdpDrops> udp_drops;
  // TF and the sensors' frames to base poses and extrinsics (ingest thread), into `poses`.
  std::unique_ptr<pipeline::TfRouter> tf_router;
  struct QueueSink final : pipeline::PoseSink {
    pipeline::PoseQueue* queue = nullptr;
    bool push(const pipeline::PoseUpdate& update) noexcept override { return queue->push(update); }
  } pose_sink;

  platform::SystemdNotifier notifier;
  platform::Wakeup integrator_wakeup;
  platform::Wakeup diagnostics_wakeup;  // stop() cuts the diagnostics period short
  // Orderings of the flags between the service's threads: `stopping` is stored with release by
  // stop() and loaded with acquire by each loop (it publishes nothing else; the threads are then
  // joined, which orders the rest). threads_set_up: each thread's release increment after its
  // set-up (its rt_refusals increment among it) pairs with start()'s acquire wait, after which
  // start() reads rt_refusals. last_publish_ns and backend_failing are values read for reports
  // and the watchdog (relaxed: nothing is published through them). Stop and start-up under
  // TSan: tests/service.
  std::atomic<bool> stopping{false};
  std::vector<std::thread> threads;
  RealtimeReport realtime;
  std::atomic<int> rt_refusals{0};
  std::atomic<int> threads_set_up{0};  // threads past their scheduling set-up (start() waits)
  std::atomic<std::int64_t> last_publish_ns{0};
  /// Backend failures at the last report (diagnostics thread writes): the publisher stops
  /// pinging the watchdog, so that systemd restarts the service.
  std::atomic<bool> backend_failing{false};

  /// Writers of the inputs, counted each report (diagnostics thread); `who` names them while an
  /// input has more than one (described again only when the counts change).
  InputPublishers input_publishers;
  char input_publishers_who[512] = {};

  /// What opening the participant decided, which the diagnostics report.
  struct Transport {
    ReceiveBufferPlan receive_buffer;
    security::SecurityOutcome security;
  };
  Expected<void, Error> createMapAndBackend();
  Expected<void, Error> planHeightmap(heightmap::HeightmapOptions& options,
                                      heightmap::HeightmapPlan& plan) const;
  pipeline::IntegratorSettings integratorSettings() const;
  void createPipeline(const heightmap::HeightmapOptions& options,
                      const heightmap::HeightmapPlan& plan);
  Result<Transport> openParticipant();
  Expected<void, Error> createSensorReaders();
  Expected<void, Error> createPoseReaders();
  Expected<void, Error> createMapWriters(const heightmap::HeightmapPlan& plan);
  void createReporter(const Transport& transport);

  void applyThreadSettings(const char* name, const ThreadConfig& t);
  /// Counts the writers of every input (discovery's matched publications). @rt allocates only
  /// while an input has more than one writer and the counts have just changed.
  void countInputPublishers() noexcept;
  void ingestLoop();
  void integratorLoop();
  void publisherLoop();
  // publisherLoop()'s steps for one cycle.
  /// Generates the height map (and costmap) into their messages. @return whether there is a map
  /// to publish; `healthy` false when generation failed for a reason other than no pose
  bool generateMaps(PublishTimetable& timetable, bool& healthy);
  /// Writes the messages at the publish instant and counts them. @return false when a write
  /// failed
  bool writeMaps(PublishTimetable& timetable, std::int64_t cycle_index, std::int64_t voxels_every);
  void diagnosticsLoop();
  void receiveCloud(std::uint32_t sensor, dds::HeldSample& sample);
  void decodePending();
  void decodeCloud(std::uint32_t sensor, std::span<const std::byte> cdr, std::int64_t arrival_ns);
  /// ScanMailbox's release listener (integrator thread, done with a scan): wakes the ingest
  /// thread when it holds scans as received, to decode the oldest for the integrator.
  static void onScanReleased(void* context) noexcept;
  void onCameraInfo(std::uint32_t sensor, std::span<const std::byte> cdr);
  void onOdometry(std::span<const std::byte> cdr);
  void onTf(std::span<const std::byte> cdr, bool is_static, std::uint64_t writer);
  void publishVoxels(std::int64_t stamp_ns);
};

// ---------------------------------------------------------------- start-up

// Start-up in named steps (members of Impl, in the order create() calls them). Each returns an
// error that names the configuration file and key; nothing is started before all succeeded.

Expected<void, Error> Service::Impl::createMapAndBackend() {
  const std::string& file = config.path;
  MapConfig map_config = config.map;
  // The CPU keeps its once-per-scan bits outside the map; a device (or a fallback from one to
  // the CPU) needs the scan-mark layer.
  map_config.device_scan_marks = config.backend.name != "cpu";
  auto created = VoxelMap::create(map_config);
  if (!created) {
    return fail(created.error().code, file + ": map: " + created.error().message);
  }
  map.emplace(std::move(created).value());
  map->setWindowCentre({0.0, 0.0, 0.0});

  auto made = createBackend(*map, config.backend);
  if (!made) {
    return fail(made.error().code, file + ": backend: " + made.error().message);
  }
  backend = std::move(made).value();
  if (!backend.fallback_warning.empty()) {
    logLine(LogLevel::kWarning, "%s", backend.fallback_warning.c_str());
  }
  if (!backend.startup_warning.empty()) {
    logLine(LogLevel::kWarning, "%s", backend.startup_warning.c_str());
  }
  // The height map runs where the integration runs (a CPU fallback takes both to the CPU), on a
  // device in the backend's own context: it reads the map where integration left it.
  auto made_generator = createHeightmapGenerator(*backend.backend);
  if (!made_generator) {
    return fail(made_generator.error().code,
                config.path + ": backend: " + made_generator.error().message);
  }
  generator = std::move(made_generator).value().generator;
  return {};
}

Expected<void, Error> Service::Impl::planHeightmap(heightmap::HeightmapOptions& options,
                                                   heightmap::HeightmapPlan& plan) const {
  // The height-map request, checked once here so that the cycle cannot fail on it later.
  options.size = config.heightmap.size_m;
  options.mode = config.heightmap.mode;
  options.min_clearance = config.heightmap.min_clearance_m;
  options.floor_depth = config.heightmap.floor_depth_m;
  options.ceiling_height = config.heightmap.ceiling_height_m;
  options.virtual_surfaces = config.heightmap.virtual_surfaces;
  options.use_voxel_mean = config.map.voxel_mean;
  if (auto planned = heightmap::planHeightmap(*map, options, plan); !planned) {
    return fail(ErrorCode::kInvalidArgument,
                config.path + ": heightmap: " + planned.error().message);
  }
  return {};
}

pipeline::IntegratorSettings Service::Impl::integratorSettings() const {
  pipeline::IntegratorSettings settings;
  settings.batch_rays = config.queues.batch_rays;
  settings.batch_deadline_ns = seconds(config.queues.batch_deadline_s);
  settings.pose_wait_ns = seconds(config.pose.max_wait_s);
  settings.pose_hold_ns = seconds(config.pose.hold_s);
  settings.time_reset_ns = seconds(config.pose.time_reset_s);
  settings.max_pose_jump_m = config.pose.max_jump_m;
  settings.clear_on_jump = config.pose.clear_on_jump;
  settings.pose_history = config.pose.history;
  settings.max_lock_hold_ns = seconds(config.queues.max_lock_hold_s);
  settings.max_latency_ns = seconds(config.queues.max_latency_s);
  settings.publish_period_ns = seconds(1.0 / config.heightmap.rate_hz);
  settings.max_stride = config.queues.shed_subsample ? config.queues.max_subsample : 1u;
  settings.shed_always = config.queues.shed_always;
  return settings;
}

void Service::Impl::createPipeline(const heightmap::HeightmapOptions& options,
                                   const heightmap::HeightmapPlan& plan) {
  std::uint32_t max_points = 1;
  for (const SensorConfig& s : config.sensors) {
    max_points = std::max(max_points, s.max_points);
  }
  mailbox = std::make_unique<pipeline::ScanMailbox>(config.queues.scan_slots + 1, max_points);
  // The scan_slots scans that may wait do so as received; one is decoded when the integrator
  // is ready for it (drop before decode: docs/raymapd.md, Overflow).
  pending = std::make_unique<PendingScans>(config.queues.scan_slots);
  mailbox->setReleaseListener(&Impl::onScanReleased, this);
  poses = std::make_unique<pipeline::PoseQueue>(config.queues.pose_queue);
  arrivals = std::make_unique<pipeline::ArrivalQueue>(4096);
  std::vector<pipeline::SensorSettings> sensors;
  std::vector<std::string> frames;
  for (const SensorConfig& s : config.sensors) {
    pipeline::SensorSettings ss;
    ss.extrinsic = s.extrinsic;
    ss.filter.min_range_m = s.min_range_m;
    ss.filter.max_range_m = s.max_range_m;
    ss.max_time_offset_s = static_cast<float>(s.max_time_offset_s);
    sensors.push_back(ss);
    decoders.emplace_back(decodeSettings(s));
    frames.push_back(s.frame);
  }
  tf_router = std::make_unique<pipeline::TfRouter>(config.pose.world_frame, config.pose.base_frame,
                                                   frames, stats);
  pose_sink.queue = poses.get();
  integrator = std::make_unique<pipeline::Integrator>(
      *map, *backend.backend, map_mutex, *mailbox, *poses, *arrivals, latest, integratorSettings(),
      std::move(sensors), stats);
  cycle = std::make_unique<pipeline::HeightmapCycle>(*map, *backend.backend, map_mutex, *generator,
                                                     options, config.heightmap.base_height_m,
                                                     latest, *arrivals, stats);
  dds::GridLayerSet layers = dds::GridLayerSet::all(plan.grid.has_normals);
  if (!config.heightmap.layers.empty()) {
    layers = dds::GridLayerSet{};
    for (const std::string& name : config.heightmap.layers) {
      layers.add(*dds::gridLayerNamed(name));  // names checked when the file was read
    }
    RAYMAP_EXPECTS(!layers.hasNormals() || plan.grid.has_normals);  // checked with the file
  }
  grid_map_message =
      std::make_unique<dds::GridMapMessage>(plan.grid.cells_x, plan.grid.cells_y, layers);
}

Result<Service::Impl::Transport> Service::Impl::openParticipant() {
  // DDS: the sockets' receive buffer sized for the clouds (a Cyclone file that sets one wins).
  auto receive_buffer = planReceiveBuffer(config, platform::socketReceiveBufferCap());
  if (!receive_buffer) {
    return Unexpected(std::move(receive_buffer).error());
  }
  if (!receive_buffer->warning.empty()) {
    logLine(LogLevel::kWarning, "%s", receive_buffer->warning.c_str());
  }
  auto secure = resolveDaemonSecurity(config, std::time(nullptr));
  if (!secure) {
    return Unexpected(std::move(secure).error());
  }
  logLine(secure->warning.empty() ? LogLevel::kInfo : LogLevel::kWarning, "%s",
          secure->summary.c_str());
  if (!secure->warning.empty()) {
    logLine(LogLevel::kWarning, "%s", secure->warning.c_str());
  }
  dds::DomainSettings domain_settings;
  domain_settings.security = secure->files;
  domain_settings.receive_buffer_bytes = receive_buffer->bytes;
  domain_settings.repair_burst_bytes = std::uint64_t{config.dds.repair_burst_kb} * 1024;
  auto created = dds::Participant::create(config.dds.domain, domain_settings);
  if (!created) {
    // Cyclone reads its configuration when the participant is created: a bad one fails here.
    const std::string& uri = config.dds.cyclonedds_uri;
    return fail(created.error().code,
                uri.empty() ? config.where("dds.domain") + ": " + created.error().message
                            : config.where("dds.cyclonedds_uri") + " (" + uri +
                                  ") or dds.domain: " + created.error().message);
  }
  participant.emplace(std::move(created).value());
  auto made_waitset = dds::Waitset::create(*participant);
  if (!made_waitset) {
    return Unexpected(made_waitset.error());
  }
  waitset.emplace(std::move(made_waitset).value());
  return Transport{*std::move(receive_buffer), *std::move(secure)};
}

Expected<void, Error> Service::Impl::createSensorReaders() {
  const std::string& file = config.path;
  const dds::Participant& pp = *participant;
  camera_info_readers.resize(config.sensors.size());
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    const bool depth = s.kind == SensorKind::kDepth;
    auto reader = dds::RawReader::create(
        pp, s.topic.c_str(), depth ? dds::imageType() : dds::pointCloud2Type(),
        dds::Reliability::kBestEffort, static_cast<std::int32_t>(config.queues.scan_slots));
    if (!reader) {
      return fail(reader.error().code,
                  file + ": sensors[" + std::to_string(i) + "].topic: " + reader.error().message);
    }
    cloud_readers.push_back(std::move(reader).value());
    if (auto attached =
            waitset->attach(cloud_readers.back().handle(), static_cast<std::intptr_t>(i));
        !attached) {
      return Unexpected(attached.error());
    }
    if (!depth) {
      continue;
    }
    // Drivers publish CameraInfo best-effort beside each image (reliable writers match too).
    auto info = dds::RawReader::create(pp, s.camera_info_topic.c_str(), dds::cameraInfoType(),
                                       dds::Reliability::kBestEffort, 4);
    if (!info) {
      return fail(info.error().code, file + ": sensors[" + std::to_string(i) +
                                         "].camera_info_topic: " + info.error().message);
    }
    camera_info_readers[i].emplace(std::move(info).value());
    if (auto attached = waitset->attach(camera_info_readers[i]->handle(),
                                        kCameraInfoToken + static_cast<std::intptr_t>(i));
        !attached) {
      return Unexpected(attached.error());
    }
  }
  return {};
}

Expected<void, Error> Service::Impl::createPoseReaders() {
  const auto poseReader = [&](const std::string& topic, const dds_topic_descriptor_t* type,
                              std::intptr_t token, const char* key,
                              std::optional<dds::RawReader>& out) -> Expected<void, Error> {
    auto reader = dds::RawReader::create(*participant, topic.c_str(), type,
                                         dds::Reliability::kBestEffort, 256);
    if (!reader) {
      return fail(reader.error().code, config.path + ": " + key + ": " + reader.error().message);
    }
    out.emplace(std::move(reader).value());
    return waitset->attach(out->handle(), token);
  };
  if (auto r = config.pose.source == PoseConfig::Source::kOdometry
                   ? poseReader(config.pose.odometry_topic, dds::odometryType(), kOdometryToken,
                                "pose.topic", odometry_reader)
                   : poseReader("rt/tf", dds::tfMessageType(), kTfToken, "pose.source", tf_reader);
      !r) {
    return r;
  }
  // ROS latches /tf_static (reliable, transient-local): a reader of the same kind also gets the
  // transforms published before raymapd started (or restarted).
  auto reader =
      dds::RawReader::create(*participant, "rt/tf_static", dds::tfMessageType(),
                             dds::Reliability::kReliable, 100, dds::Durability::kTransientLocal);
  if (!reader) {
    return fail(reader.error().code, config.path + ": rt/tf_static: " + reader.error().message);
  }
  tf_static_reader.emplace(std::move(reader).value());
  return waitset->attach(tf_static_reader->handle(), kTfStaticToken);
}

Expected<void, Error> Service::Impl::createMapWriters(const heightmap::HeightmapPlan& plan) {
  const std::string& file = config.path;
  const dds::Participant& pp = *participant;
  auto grid_writer =
      dds::Writer::create(pp, config.dds.grid_map_topic.c_str(), dds::GridMapMessage::descriptor(),
                          dds::Reliability::kReliable, 1);
  if (!grid_writer) {
    return fail(grid_writer.error().code,
                file + ": dds.grid_map_topic: " + grid_writer.error().message);
  }
  grid_map_writer.emplace(std::move(grid_writer).value());
  auto diag_writer =
      dds::Writer::create(pp, config.dds.diagnostics_topic.c_str(),
                          dds::DiagnosticsMessage::descriptor(), dds::Reliability::kReliable, 1);
  if (!diag_writer) {
    return fail(diag_writer.error().code,
                file + ": dds.diagnostics_topic: " + diag_writer.error().message);
  }
  diagnostics_writer.emplace(std::move(diag_writer).value());
  if (!config.dds.voxels_topic.empty()) {
    auto voxels =
        dds::Writer::create(pp, config.dds.voxels_topic.c_str(),
                            dds::PointCloudMessage::descriptor(), dds::Reliability::kReliable, 1);
    if (!voxels) {
      return fail(voxels.error().code, file + ": dds.voxels_topic: " + voxels.error().message);
    }
    voxels_writer.emplace(std::move(voxels).value());
    voxels_message = std::make_unique<dds::PointCloudMessage>(config.dds.voxels_max_points);
    voxels_xyz.resize(std::size_t{config.dds.voxels_max_points} * 3);
  }
  if (!config.dds.costmap_topic.empty()) {
    // As Nav2's StaticLayer subscribes by default: reliable, transient-local, keep last 1 (a
    // costmap that starts later gets the latest at once).
    auto costmap = dds::Writer::create(
        pp, config.dds.costmap_topic.c_str(), dds::OccupancyGridMessage::descriptor(),
        dds::Reliability::kReliable, 1, dds::Durability::kTransientLocal);
    if (!costmap) {
      return fail(costmap.error().code, file + ": dds.costmap_topic: " + costmap.error().message);
    }
    costmap_writer.emplace(std::move(costmap).value());
    costmap_message =
        std::make_unique<dds::OccupancyGridMessage>(plan.grid.cells_x, plan.grid.cells_y);
  }
  auto watch =
      dds::RawReader::create(pp, config.dds.grid_map_topic.c_str(),
                             dds::GridMapMessage::descriptor(), dds::Reliability::kBestEffort, 1,
                             dds::Durability::kVolatile, dds::Origin::kOtherParticipants);
  if (!watch) {
    return fail(watch.error().code, file + ": dds.grid_map_topic: " + watch.error().message);
  }
  map_publisher_watch.emplace(std::move(watch).value());
  return {};
}

void Service::Impl::createReporter(const Transport& transport) {
  if (config.pose.source == PoseConfig::Source::kTf) {
    input_publishers.odometry_topic = "the transform to " + config.pose.base_frame + " on rt/tf";
    input_publishers.pose_key = "pose.base_frame";
  } else {
    input_publishers.odometry_topic = config.pose.odometry_topic;
  }
  ReporterSettings reporting;
  reporting.name = config.name;
  reporting.hardware_id = config.health.hardware_id;
  if (reporting.hardware_id.empty()) {
    char host[256] = {};
    if (::gethostname(host, sizeof(host) - 1) != 0 || host[0] == '\0') {
      std::snprintf(host, sizeof(host), "unknown-host");
    }
    reporting.hardware_id = std::string(host) + "/" + config.name;
  }
  reporting.backend = backend.backend->name();
  reporting.device = backend.backend->deviceName();
  reporting.publish_rate_hz = config.heightmap.rate_hz;
  reporting.report_rate_hz = config.dds.diagnostics_rate_hz;
  reporting.stale_after_s = config.health.stale_after_s;
  reporting.startup_grace_s = config.health.startup_grace_s;
  reporting.min_integrated_fraction = config.health.min_integrated_fraction;
  reporting.grid_map_topic = config.dds.grid_map_topic;
  reporting.receive_buffer_bytes = transport.receive_buffer.bytes;
  reporting.receive_buffer_wanted_bytes = transport.receive_buffer.wanted;
  reporting.security_warning = transport.security.warning;
  reporting.security_summary = transport.security.summary;
  reporting.secure = transport.security.secure();
  for (const SensorConfig& sensor : config.sensors) {
    reporting.sensor_frames.push_back(sensor.frame);
    reporting.sensors.push_back(
        {sensor.name, sensor.topic,
         sensor.kind == SensorKind::kDepth ? sensor.camera_info_topic : std::string(),
         sensor.max_rate_hz});
  }
  reporter = std::make_unique<DiagnosticsReporter>(stats, *mailbox, *poses, std::move(reporting),
                                                   platform::monotonicNowNs());
  reporter->countHeldScans(pending.get());
}

Result<std::unique_ptr<Service>> Service::create(const DaemonConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  if (!config.dds.cyclonedds_uri.empty()) {
    // Read by Cyclone when the participant's domain is created below.
    ::setenv("CYCLONEDDS_URI", config.dds.cyclonedds_uri.c_str(), 1);
  }
  if (auto ok = impl->createMapAndBackend(); !ok) {
    return Unexpected(std::move(ok).error());
  }
  heightmap::HeightmapOptions options;
  heightmap::HeightmapPlan plan;
  if (auto ok = impl->planHeightmap(options, plan); !ok) {
    return Unexpected(std::move(ok).error());
  }
  impl->createPipeline(options, plan);
  auto transport = impl->openParticipant();
  if (!transport) {
    return Unexpected(std::move(transport).error());
  }
  for (auto step : {&Impl::createSensorReaders, &Impl::createPoseReaders}) {
    if (auto ok = (impl.get()->*step)(); !ok) {
      return Unexpected(std::move(ok).error());
    }
  }
  if (auto ok = impl->createMapWriters(plan); !ok) {
    return Unexpected(std::move(ok).error());
  }
  impl->createReporter(*transport);
  return std::unique_ptr<Service>(new Service(std::move(impl)));
}

Service::Service(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}

Service::~Service() { stop(); }

const RealtimeReport& Service::realtime() const noexcept { return impl_->realtime; }

std::string Service::describe() const {
  const DaemonConfig& c = impl_->config;
  std::string sensors;
  for (const SensorConfig& s : c.sensors) {
    sensors += (sensors.empty() ? "" : ", ") + s.topic +
               (s.kind == SensorKind::kDepth ? " (depth, " + s.camera_info_topic + ")" : "");
  }
  const std::string device = impl_->backend.backend->deviceName();
  char line[512];
  std::snprintf(
      line, sizeof(line),
      "backend %s%s%s; sensors %s; pose from %s; height map %.0f x %.0f m at %g Hz "
      "on %s (domain %u)",
      impl_->backend.backend->name(), device.empty() ? "" : " on ", device.c_str(), sensors.c_str(),
      c.pose.source == PoseConfig::Source::kOdometry ? c.pose.odometry_topic.c_str() : "rt/tf",
      c.heightmap.size_m, c.heightmap.size_m, c.heightmap.rate_hz, c.dds.grid_map_topic.c_str(),
      c.dds.domain);
  return line;
}

// ---------------------------------------------------------------- threads

void Service::Impl::applyThreadSettings(const char* name, const ThreadConfig& t) {
  platform::nameCurrentThread(name);
  platform::RtRequest request;
  request.priority = t.priority;
  request.cpu_mask = cpuMask(t.cpus);
  const platform::RtStatus status = platform::applyRealtime(request);
  if (status.scheduling == platform::RtOutcome::kRefused ||
      status.affinity == platform::RtOutcome::kRefused) {
    rt_refusals.fetch_add(1);
  }
  // Start-up of the thread: not yet in its loop, so the log line is fine here.
  if (status.scheduling == platform::RtOutcome::kRefused) {
    logLine(LogLevel::kWarning,
            "%s thread: SCHED_FIFO priority %d refused (%s): running with normal scheduling. "
            "Give the service CAP_SYS_NICE or LimitRTPRIO, and no CPU accounting options in "
            "its unit (RT group scheduling).",
            name, t.priority, platform::errnoText(status.scheduling_errno).c_str());
  }
  if (status.affinity == platform::RtOutcome::kRefused) {
    logLine(LogLevel::kWarning, "%s thread: CPU affinity refused (%s): running on any CPU", name,
            platform::errnoText(status.affinity_errno).c_str());
  }
  threads_set_up.fetch_add(1, std::memory_order_release);
}

void Service::Impl::receiveCloud(std::uint32_t sensor, dds::HeldSample& sample) {
  stats.clouds_received.add();
  stats.sensors[sensor].received.add();
  if (const std::optional<std::int64_t> stamp = pipeline::headerStampNs(sample.bytes())) {
    // Best-effort readers are told of no loss: the gaps in the stamps say what went missing.
    if (const std::uint32_t missing = stamp_gaps[sensor].observe(*stamp); missing > 0) {
      stats.sensors[sensor].missing.add(missing);
    }
  }
  const std::int64_t arrival_ns = platform::monotonicNowNs();
  stats.last_cloud_received_ns.store(arrival_ns, std::memory_order_relaxed);
  if (decoders[sensor].overRateOnArrival(sample.bytes())) {
    stats.sensors[sensor].rate_limited.add();  // by configuration: not an input fault
    return;
  }
  if (integratorBusy(*pending, *mailbox)) {
    // The integrator is busy: this scan waits as received, and is decoded only if it is still
    // among the newest scan_slots when the integrator is ready for it (decodePending).
    platform::ForeignScope dds;  // a full ring gives its oldest buffer back to Cyclone
    if (pending->push(sensor, arrival_ns, std::move(sample))) {
      mailbox->noteDroppedUndecoded();
    }
    return;
  }
  decodeCloud(sensor, sample.bytes(), arrival_ns);
}

void Service::Impl::decodePending() {
  // When the integrator is busy, its next release wakes this thread again (onScanReleased).
  decodeHeldWhileReady(*pending, *mailbox, [this](PendingScans::Entry next) {
    decodeCloud(next.sensor, next.sample.bytes(), next.arrival_ns);
    platform::ForeignScope dds;
    next.sample.reset();
  });
}

void Service::Impl::onScanReleased(void* context) noexcept {
  auto* impl = static_cast<Impl*>(context);
  if (heldScansWait(*impl->pending)) {
    platform::ForeignScope dds;
    impl->waitset->wake();
  }
}

void Service::Impl::decodeCloud(std::uint32_t sensor, std::span<const std::byte> cdr,
                                std::int64_t arrival_ns) {
  pipeline::SensorCounters& counters = stats.sensors[sensor];
  pipeline::ScanSlot* slot = mailbox->acquire();
  if (slot == nullptr) {
    stats.clouds_malformed.add();  // unreachable with >= 2 slots; never block
    counters.rejected.add();
    return;
  }
  // This sensor's own max_points (the slots hold the largest of all sensors').
  const pipeline::DecodedScan decoded =
      decoders[sensor].decode(cdr, slot->buffer.first(std::min<std::size_t>(
                                       slot->buffer.size(), config.sensors[sensor].max_points)));
  if (decoded.outcome != pipeline::DecodeOutcome::kAccepted) {
    mailbox->abandon(slot);
  }
  switch (decoded.outcome) {
    case pipeline::DecodeOutcome::kAccepted:
      break;
    case pipeline::DecodeOutcome::kRateLimited:
      counters.rate_limited.add();  // by configuration: not an input fault
      return;
    case pipeline::DecodeOutcome::kMalformed:
    case pipeline::DecodeOutcome::kTooLarge:
      counters.rejected.add();
      if (decoded.outcome == pipeline::DecodeOutcome::kTooLarge) {
        stats.clouds_too_large.add();
      } else {
        stats.clouds_malformed.add();
      }
      if (config.sensors[sensor].kind == SensorKind::kDepth) {
        stats.images_rejected_by[static_cast<std::size_t>(decoded.image_error)].add();
      } else {
        stats.clouds_rejected_by[static_cast<std::size_t>(decoded.cloud_error)].add();
      }
      return;
    case pipeline::DecodeOutcome::kNoCameraInfo:
      counters.rejected.add();
      counters.no_camera_info.add();
      return;
    case pipeline::DecodeOutcome::kWrongFrame:
      counters.rejected.add();  // its extrinsic would be wrong
      stats.clouds_unknown_frame.add();
      if (!stats.wrong_frame_seen.load(std::memory_order_relaxed)) {
        // The first wrong frame, for the diagnostics' reason (written once, then published).
        std::memcpy(stats.wrong_frame, decoded.header.frame_id, sizeof(stats.wrong_frame));
        stats.wrong_frame_sensor = sensor;
        stats.wrong_frame_seen.store(true, std::memory_order_release);
      }
      return;
  }
  // /tf_static latched before a sensor's first cloud applies from it on (queued before the scan:
  // the integrator takes poses queued ahead of a scan first).
  tf_router->learnSensorFrame(sensor, decoded.header.frame_id, pose_sink);
  slot->header = decoded.header;
  slot->sensor = sensor;
  slot->arrival_ns = arrival_ns;
  stats.points_received.add(slot->header.points);
  stats.points_too_near.add(decoded.too_near);
  counters.accepted.add();
  mailbox->publish(slot);
  integrator_wakeup.notify();
}

void Service::Impl::onCameraInfo(std::uint32_t sensor, std::span<const std::byte> cdr) {
  pipeline::SensorCounters& counters = stats.sensors[sensor];
  counters.camera_info.add();
  if (auto taken = decoders[sensor].onCameraInfo(cdr); !taken) {
    counters.camera_info_bad.add();
    stats.camera_info_rejected_by[static_cast<std::size_t>(taken.error())].add();
  }
}

void Service::Impl::onOdometry(std::span<const std::byte> cdr) {
  auto odometry = msgs::decodeOdometry(cdr);
  if (!odometry) {
    stats.poses_malformed.add();
    return;
  }
  if (!poses->push(pipeline::baseInWorld(odometry.value()))) {
    stats.poses_dropped.add();
    return;
  }
  stats.poses_received.add();
  integrator_wakeup.notify();
}

void Service::Impl::onTf(std::span<const std::byte> cdr, bool is_static, std::uint64_t writer) {
  std::array<msgs::StampedTransform, kTfPerMessage> transforms;
  auto count = msgs::decodeTfMessage(cdr, transforms);
  if (!count) {
    stats.poses_malformed.add();
    return;
  }
  if (!is_static) {
    // /tf has many writers by design; two of the robot's base are two pose sources.
    for (std::size_t i = 0; i < count.value(); ++i) {
      if (config.pose.base_frame == transforms[i].child) {
        base_writers.seen(writer, platform::monotonicNowNs());
        break;
      }
    }
  }
  tf_router->onTransforms(std::span(transforms).first(count.value()), is_static, pose_sink);
  integrator_wakeup.notify();
}

void Service::Impl::ingestLoop() {
  applyThreadSettings("raymap-ingest", config.realtime.ingest);
  std::array<std::intptr_t, 64> triggered{};
  while (!stopping.load(std::memory_order_acquire)) {
    platform::RealtimeScope steady;
    int n = 0;
    {
      platform::ForeignScope dds;
      n = waitset->wait(100000000, triggered);  // 100 ms: re-checks `stopping`
    }
    for (int k = 0; k < n; ++k) {
      const std::intptr_t token = triggered[static_cast<std::size_t>(k)];
      if (token >= 0 && token < static_cast<std::intptr_t>(cloud_readers.size())) {
        const auto sensor = static_cast<std::uint32_t>(token);
        platform::ForeignScope dds;  // dds_takecdr; our callback counts again
        cloud_readers[sensor].takeEachHeld(
            [&](dds::HeldSample& sample) {
              platform::RealtimeScope ours;
              receiveCloud(sensor, sample);
            },
            kTakePerWake);
      } else if (token >= kCameraInfoToken &&
                 token < kCameraInfoToken + static_cast<std::intptr_t>(cloud_readers.size())) {
        const auto sensor = static_cast<std::uint32_t>(token - kCameraInfoToken);
        platform::ForeignScope dds;
        camera_info_readers[sensor]->takeEach(
            [&](std::span<const std::byte> cdr, std::int64_t) {
              // A new camera builds its pixel-ray table here (allocation-free up to the
              // reserved size; a few ms once): not counted as real-time work.
              onCameraInfo(sensor, cdr);
            },
            4);
      } else if (token == kOdometryToken) {
        odometry_reader->takeEach(
            [&](std::span<const std::byte> cdr, std::int64_t) { onOdometry(cdr); }, 256);
      } else if (token == kTfToken) {
        tf_reader->takeEachHeld(
            [&](dds::HeldSample& sample) { onTf(sample.bytes(), false, sample.writerHandle()); },
            256);
      } else if (token == kTfStaticToken) {
        platform::ForeignScope dds;
        tf_static_reader->takeEach(
            [&](std::span<const std::byte> cdr, std::int64_t) {
              platform::RealtimeScope ours;
              onTf(cdr, true, 0);
            },
            256);
      }
    }
    // After every wake-up, the integrator's take (kWakeToken) or a new scan alike.
    decodePending();
  }
  platform::ForeignScope dds;
  pending->clear();
}

void Service::Impl::integratorLoop() {
  applyThreadSettings("raymap-integr", config.realtime.integrator);
  constexpr std::int64_t kIdleCheckNs = 100000000;  // re-checks `stopping`
  while (!stopping.load(std::memory_order_acquire)) {
    platform::RealtimeScope steady;
    const std::int64_t now = platform::monotonicNowNs();
    const std::int64_t next = integrator->step(now);
    const std::int64_t wake = std::min(next, now + kIdleCheckNs);
    integrator_wakeup.waitUntilMonotonicNs(wake);
  }
  integrator->flush(platform::monotonicNowNs());
}

void Service::Impl::publishVoxels(std::int64_t stamp_ns) {
  // Only while someone listens: walking the window is not free.
  if (!voxels_writer || voxels_writer->matchedReaders() == 0) {  // no allocation: a status read
    return;
  }
  std::size_t n = 0;
  const std::size_t capacity = voxels_xyz.size() / 3;
  {
    std::lock_guard<platform::PiMutex> lock(map_mutex);
    // The walk reads the host store: a device backend makes it current first (the height-map
    // cycle reads the map on the device and no longer does).
    if (!backend.backend->synchronise()) {
      return;
    }
    const VoxelMap& m = *map;
    const RegionStore& store = m.store();
    const std::uint32_t per_region = m.geometry().voxelsPerRegion();
    const int layer = m.occupancyLayer();
    const float threshold = m.occupancy().threshold;
    for (std::uint32_t slot = 0; slot < store.capacity() && n < capacity; ++slot) {
      if (!store.inUse(slot)) {
        continue;
      }
      const Vec3i region = store.coordOf(slot);
      const float* occupancy = store.layerData<float>(slot, layer);
      for (std::uint32_t i = 0; i < per_region && n < capacity; ++i) {
        const float value = occupancy[i];
        if (std::isfinite(value) && value > threshold) {
          const Vec3d c = m.voxelCentre(m.voxelAt(region, i));
          voxels_xyz[3 * n + 0] = static_cast<float>(c.x);
          voxels_xyz[3 * n + 1] = static_cast<float>(c.y);
          voxels_xyz[3 * n + 2] = static_cast<float>(c.z);
          ++n;
        }
      }
    }
  }
  voxels_message->fill(std::span<const float>(voxels_xyz.data(), 3 * n), stamp_ns,
                       config.pose.world_frame.c_str());
  platform::ForeignScope dds;
  (void)voxels_writer->write(voxels_message->sample());
}

bool Service::Impl::generateMaps(PublishTimetable& timetable, bool& healthy) {
  const std::int64_t generate_started = platform::monotonicNowNs();
  auto generated = cycle->generate();
  timetable.recordGenerate(platform::monotonicNowNs() - generate_started);
  stats.publish_lead_us.store(timetable.lead() / 1000, std::memory_order_relaxed);
  if (!generated) {
    if (generated.error() != pipeline::CycleError::kNoPose) {
      stats.heightmap_errors.add();
      healthy = false;
    }
    return false;
  }
  // The stamp is the newest scan's (the data's own time, never the wall clock).
  grid_map_message->fill(cycle->heightMap(), cycle->dataStampNs(), config.pose.world_frame.c_str());
  if (costmap_message) {
    const heightmap::HeightMap& hm = cycle->heightMap();
    heightmap::computeCostmap(hm, config.costmap, costmap_message->cells());
    costmap_message->fill(hm.resolution, heightmap::costmapOrigin(hm), cycle->dataStampNs(),
                          config.pose.world_frame.c_str());
  }
  return true;
}

bool Service::Impl::writeMaps(PublishTimetable& timetable, std::int64_t cycle_index,
                              std::int64_t voxels_every) {
  const std::int64_t now = platform::monotonicNowNs();
  bool healthy = true;
  bool written = false;
  bool costmap_written = true;
  {
    platform::ForeignScope dds;  // Cyclone serialises into its own buffer
    written = grid_map_writer->write(grid_map_message->sample()).has_value();
    if (costmap_writer) {
      costmap_written = costmap_writer->write(costmap_message->sample()).has_value();
    }
  }
  if (costmap_writer) {
    (costmap_written ? stats.costmaps_published : stats.heightmap_errors).add();
    healthy = costmap_written;
  }
  if (written) {
    stats.maps_published.add();
    if (timetable.previous_publish != 0) {
      const std::int64_t error = std::llabs(now - timetable.previous_publish - timetable.period());
      stats.period_error_us.record(static_cast<std::uint64_t>(error / 1000));
    }
    timetable.previous_publish = now;
    last_publish_ns.store(now, std::memory_order_relaxed);
    cycle->recordPublished(now);
  } else {
    healthy = false;
  }
  if (cycle_index % voxels_every == 0) {
    publishVoxels(cycle->dataStampNs());
  }
  return healthy;
}

void Service::Impl::publisherLoop() {
  applyThreadSettings("raymap-publish", config.realtime.publisher);
  PublishTimetable timetable(seconds(1.0 / config.heightmap.rate_hz),
                             seconds(config.heightmap.publish_lead_s),
                             seconds(config.heightmap.publish_lead_max_s));
  stats.publish_lead_us.store(timetable.lead() / 1000, std::memory_order_relaxed);
  const std::int64_t stale_after = seconds(config.health.stale_after_s);
  const std::int64_t voxels_every =
      std::max<std::int64_t>(1, std::llround(config.heightmap.rate_hz / config.dds.voxels_rate_hz));
  std::int64_t cycle_index = 0;
  bool first_cycle = true;
  while (!stopping.load(std::memory_order_acquire)) {
    // The first successful cycle sizes the plan and the layers; every later one allocates nothing.
    std::optional<platform::RealtimeScope> steady;
    if (!first_cycle) {
      steady.emplace();
    }
    // The latency bound's timetable.
    stats.next_publish_ns.store(timetable.next(), std::memory_order_relaxed);
    platform::sleepUntilMonotonicNs(timetable.next() - timetable.lead());
    if (stopping.load(std::memory_order_acquire)) {
      break;
    }
    // A stale map (no scan integrated for health.stale_after_s, or none yet) is withheld: a
    // planner must not take the last map for the present, and a GridMap's stamp never pretends
    // to be fresh. Silence on the topic is what its timeouts detect.
    const std::int64_t last_scan = stats.last_scan_integrated_ns.load(std::memory_order_relaxed);
    if (last_scan == 0 || platform::monotonicNowNs() - last_scan > stale_after) {
      stats.maps_withheld.add();
      // The loop is alive and doing its job: the watchdog hears from it (a restart cannot make a
      // lidar publish, and systemd's start limit would leave the robot without a mapper).
      notifier.watchdog();
      timetable.previous_publish = 0;  // a gap is not a period
      (void)timetable.advance();
      continue;
    }
    bool healthy = true;
    const bool generated = generateMaps(timetable, healthy);
    first_cycle = first_cycle && !generated;
    if (platform::monotonicNowNs() > timetable.next()) {
      stats.cycles_late.add();
    }
    platform::sleepUntilMonotonicNs(timetable.next());
    if (generated) {
      healthy = writeMaps(timetable, ++cycle_index, voxels_every) && healthy;
    } else {
      timetable.previous_publish = 0;  // a gap is not a period
    }
    // The watchdog hears from the service only after a cycle that did its job on time, and not
    // while the backend fails (docs/raymapd.md, Health).
    if (healthy && !backend_failing.load(std::memory_order_relaxed)) {
      notifier.watchdog();
    }
    // Missed whole periods (the machine stalled) are skipped instead of published in a burst.
    if (const std::int64_t missed = timetable.advance(); missed > 0) {
      stats.cycles_late.add(static_cast<std::uint64_t>(missed));
    }
  }
}

void Service::Impl::countInputPublishers() noexcept {
  InputPublishers& p = input_publishers;
  bool changed = false;
  bool extra = false;
  const auto note = [&](std::uint32_t& slot, std::uint32_t n) {
    changed = changed || n != slot;
    extra = extra || n > 1;
    slot = n;
  };
  const auto count = [&](std::uint32_t& slot, const dds::RawReader& reader) {
    note(slot, reader.matchedWriters());
  };
  for (std::size_t i = 0; i < cloud_readers.size() && i < p.clouds.size(); ++i) {
    count(p.clouds[i], cloud_readers[i]);
    if (camera_info_readers[i]) {
      count(p.camera_info[i], *camera_info_readers[i]);
    }
  }
  if (odometry_reader) {
    count(p.odometry, *odometry_reader);
  } else if (tf_reader) {
    // By frame: the writers of base_frame's transform within the last second.
    note(p.odometry, base_writers.writers(platform::monotonicNowNs(), seconds(1.0)));
  }
  if (!extra) {
    input_publishers_who[0] = '\0';
  } else if (changed) {
    // Who they are, input by input. Cyclone allocates the discovery data it copies out: its
    // allocation, once per change of the writers, never in a steady state.
    platform::ForeignScope dds;
    char* out = input_publishers_who;
    const std::size_t size = sizeof(input_publishers_who);
    out[0] = '\0';
    const auto describe = [&](std::uint32_t n, const dds::RawReader& reader, const char* topic) {
      const std::size_t used = std::strlen(out);
      if (n <= 1 || used + 1 >= size) {
        return;
      }
      const int wrote =
          std::snprintf(out + used, size - used, "%s%s: ", used == 0 ? "" : "; ", topic);
      const std::size_t at =
          std::min(size - 1, used + static_cast<std::size_t>(std::max(wrote, 0)));
      reader.describeMatchedWriters(out + at, size - at);
    };
    for (std::size_t i = 0; i < cloud_readers.size() && i < p.clouds.size(); ++i) {
      describe(p.clouds[i], cloud_readers[i], config.sensors[i].topic.c_str());
      if (camera_info_readers[i]) {
        describe(p.camera_info[i], *camera_info_readers[i],
                 config.sensors[i].camera_info_topic.c_str());
      }
    }
    if (odometry_reader) {
      describe(p.odometry, *odometry_reader, config.pose.odometry_topic.c_str());
    } else if (tf_reader) {
      describe(p.odometry, *tf_reader, "rt/tf");  // every writer of /tf: the two are among them
    }
  }
  p.who = input_publishers_who;
}

void Service::Impl::diagnosticsLoop() {
  platform::nameCurrentThread("raymap-diag");
  const std::int64_t period = seconds(1.0 / config.dds.diagnostics_rate_hz);
  std::int64_t next = platform::monotonicNowNs() + period;
  while (!stopping.load(std::memory_order_acquire)) {
    diagnostics_wakeup.waitUntilMonotonicNs(next);
    next += period;
    if (stopping.load(std::memory_order_acquire)) {
      break;
    }
    platform::RealtimeScope steady;
    const std::int64_t now = platform::monotonicNowNs();
    countInputPublishers();
    stats.socket_drops.set(udp_drops->total());
    reporter->update(now, realtime, map_publisher_watch->matchedWriters(), &input_publishers);
    backend_failing.store(reporter->backendFailing(), std::memory_order_relaxed);
    const void* sample = reporter->message(platform::realtimeNowNs());
    {
      platform::ForeignScope dds;
      (void)diagnostics_writer->write(sample);
    }
    notifier.status(reporter->statusLine());
    reporter->logChanges();
  }
}

void Service::start() {
  Impl& s = *impl_;
  // Memory: every pool exists now; lock it in RAM where the limit allows.
  if (s.config.realtime.lock_memory) {
    const platform::MemoryLockStatus lock = platform::lockMemory();
    s.realtime.memory_locked = lock.locked;
    s.realtime.memory_lock_errno = lock.error_no;
    if (!lock.locked) {
      logLine(
          LogLevel::kWarning,
          "memory not locked (%s; RLIMIT_MEMLOCK %s): page faults may stall the real-time "
          "threads. Set LimitMEMLOCK=infinity in the unit.",
          platform::errnoText(lock.error_no).c_str(),
          lock.limit_bytes == std::numeric_limits<std::uint64_t>::max() ? "unlimited" : "finite");
    }
  }
  // Every socket exists now (the participant, its readers and writers).
  s.udp_drops.emplace(platform::UdpDrops::ofThisProcess());
  s.threads.emplace_back([&s] { s.ingestLoop(); });
  s.threads.emplace_back([&s] { s.integratorLoop(); });
  s.threads.emplace_back([&s] { s.publisherLoop(); });
  // Wait (at most 1 s) for the three real-time threads to apply their scheduling, so that READY
  // and the log carry the outcome.
  for (int i = 0; i < 500 && s.threads_set_up.load(std::memory_order_acquire) < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const RealtimeConfig& rt = s.config.realtime;
  const bool requested =
      rt.ingest.priority > 0 || rt.integrator.priority > 0 || rt.publisher.priority > 0;
  s.realtime.degraded = s.rt_refusals.load() > 0 || (rt.lock_memory && !s.realtime.memory_locked);
  char summary[256];
  std::snprintf(summary, sizeof(summary), "%s%s; memory %s",
                !requested                 ? "normal scheduling (none requested)"
                : s.rt_refusals.load() > 0 ? "REAL-TIME REFUSED: normal scheduling"
                                           : "SCHED_FIFO",
                requested && s.rt_refusals.load() == 0 ? " as configured" : "",
                s.realtime.memory_locked ? "locked" : "NOT locked");
  s.realtime.summary = summary;
  // The diagnostics thread starts only now: it reads s.realtime (summary, degraded) on every
  // report without a lock, so both must be final before it exists (ThreadSanitizer found it
  // reading the summary while this thread was still writing it).
  s.threads.emplace_back([&s] { s.diagnosticsLoop(); });
  char status[512];
  std::snprintf(status, sizeof(status), "mapping: %s, %g Hz; %s", s.backend.backend->name(),
                s.config.heightmap.rate_hz, summary);
  s.notifier.ready(status);
  logLine(s.realtime.degraded ? LogLevel::kWarning : LogLevel::kInfo, "started: %s",
          describe().c_str());
  logLine(s.realtime.degraded ? LogLevel::kWarning : LogLevel::kInfo, "real time: %s", summary);
}

void Service::stop() {
  if (!impl_) {
    return;
  }
  Impl& s = *impl_;
  if (s.threads.empty()) {
    return;
  }
  s.notifier.stopping();
  s.stopping.store(true, std::memory_order_release);
  s.waitset->wake();
  s.integrator_wakeup.notify();
  s.diagnostics_wakeup.notify();
  for (std::thread& t : s.threads) {
    t.join();
  }
  s.threads.clear();
  (void)s.backend.backend->synchronise();
}

Expected<void, Error> Service::saveMapIfConfigured() {
  const std::string& path = impl_->config.save_map_on_exit;
  if (path.empty()) {
    return {};
  }
  auto saved = io::saveMap(*impl_->map, path);
  if (saved) {
    return saved;
  }
  // The run's map is not lost because its folder went away or filled up: it goes where the
  // service keeps state (systemd's StateDirectory=), else the temporary folder, and the error
  // says where.
  std::vector<std::filesystem::path> folders;
  if (const char* state = std::getenv("STATE_DIRECTORY"); state != nullptr && *state != '\0') {
    const std::string first(state, std::strcspn(state, ":"));
    folders.emplace_back(first);
  }
  std::error_code ec;
  const std::filesystem::path temp = std::filesystem::temp_directory_path(ec);
  if (!ec) {
    folders.push_back(temp);
  }
  const std::string name = "raymapd-rescued-" + std::to_string(::getpid()) + "-" +
                           std::filesystem::path(path).filename().string();
  std::string tried;
  for (const std::filesystem::path& folder : folders) {
    const std::string rescue = (folder / name).string();
    auto copy = io::saveMap(*impl_->map, rescue);
    if (copy) {
      return fail(saved.error().code,
                  saved.error().message + "; the map was saved to " + rescue + " instead");
    }
    tried += "; saving it to " + rescue + " failed too: " + copy.error().message;
  }
  return fail(saved.error().code, saved.error().message + tried);
}

}  // namespace raymap::service
