// SPDX-License-Identifier: BSD-3-Clause
// raymap-load: drives a running raymapd like a robot would (a simulated lidar driver publishing
// PointCloud2 and odometry over DDS) and measures what comes back (GridMap period at the
// subscriber, how soon the first GridMap follows the first scan, the service's own latency and
// drop counters from its diagnostics). Prints JSON.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "platform/clock.hpp"
#include "platform/rt.hpp"
#include "src/driver/depth_playback.hpp"
#include "src/driver/lidar_playback.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/driver/simulated_lidar.hpp"
#include "src/security/secure_participant.hpp"
#include "src/sim/scene_file.hpp"
#include "tools/dds_driver/default_scene.hpp"
#include "tools/raymap/dds_cli.hpp"
#include "tools/raymap/json_output.hpp"

namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}

/// raymapd's figures as its diagnostics state them (strings of numbers); -1 when missing. The
/// counts among them are JSON integers (null when one is not finite: JSON has no NaN).
raymap::cli::Json raymapdFigures(const raymap::driver::DiagnosticsListener& d) {
  const auto value = [&](const char* key) { return d.number(key).value_or(-1.0); };
  const auto count = [&](const char* key) {
    const double v = value(key);
    return std::isfinite(v) ? raymap::cli::Json(std::llround(v)) : raymap::cli::Json();
  };
  return {
      {"latency_p50_ms", value("raymapd: height map/latency_p50_ms_total")},
      {"latency_p99_ms", value("raymapd: height map/latency_p99_ms_total")},
      {"latency_max_ms", value("raymapd: height map/latency_max_ms_total")},
      {"clouds_received", count("raymapd: pipeline/clouds_received")},
      {"clouds_dropped_overflow", count("raymapd: pipeline/clouds_dropped_overflow")},
      {"clouds_dropped_before_decode", count("raymapd: pipeline/clouds_dropped_before_decode")},
      {"scans_dropped_no_pose", count("raymapd: pipeline/scans_dropped_no_pose")},
      {"clouds_malformed", count("raymapd: pipeline/clouds_malformed")},
      {"scans_integrated", count("raymapd: pipeline/scans_integrated")},
      {"rays_integrated", count("raymapd: pipeline/rays_integrated")},
      {"cycles_late", count("raymapd: height map/cycles_late")},
      {"period_error_max_ms", value("raymapd: height map/period_error_max_ms_total")},
      {"scans_shed", count("raymapd: pipeline/scans_shed")},
      {"scans_cut_short", count("raymapd: pipeline/scans_cut_short")},
      {"points_shed", count("raymapd: pipeline/points_shed")},
      {"map_lock_hold_max_ms", value("raymapd: height map/map_lock_hold_max_ms_total")},
      {"map_lock_wait_max_ms", value("raymapd: height map/map_lock_wait_max_ms_total")},
      {"publish_lead_ms", value("raymapd: height map/publish_lead_ms")},
      {"level", count("raymapd: pipeline/level")},
      {"integrator_load_percent", count("raymapd: pipeline/integrator_load_percent")},
      {"generate_p99_ms", value("raymapd: height map/generate_p99_ms")},
      {"heightmap_lock_hold_p99_ms", value("raymapd: height map/heightmap_lock_hold_p99_ms")},
      {"sync_copy_bytes_p99", count("raymapd: height map/sync_copy_bytes_p99")},
      {"heightmap_copy_bytes_p99", count("raymapd: height map/heightmap_copy_bytes_p99")},
      {"heightmap_transfer_bytes_p99", count("raymapd: height map/heightmap_transfer_bytes_p99")},
  };
}

/// The command line (see addOptions for each one's meaning).
struct LoadOptions {
  std::string scene_path;  // default: yard.yaml, installed or in the source tree
  int beams = 128;
  int columns = 1024;
  double scan_rate = 10.0;
  double duration = 10.0;
  double warmup = 2.0;
  bool moving = false;
  int distinct = 4;
  int domain = -1;  // -1: $ROS_DOMAIN_ID, else 0
  std::string points_topic = "rt/points";
  std::string odom_topic = "rt/odom";
  std::string grid_topic = "rt/height_map";
  std::string diag_topic = "rt/diagnostics";
  std::string frame = "lidar";
  double period_nominal_s = 0.2;
  std::vector<std::string> sensors;
  double depth_rate = 0.0;
  int subscriber_priority = 0;
};

void addOptions(CLI::App& app, LoadOptions& o) {
  app.add_option("--scene", o.scene_path,
                 "scene file (its lidar and path are the defaults; default: the installed "
                 "share/raymap/scenes/yard.yaml)");
  app.add_option("--beams", o.beams, "lidar beams (128: an Ouster OS-1-128)");
  app.add_option("--columns", o.columns, "lidar columns per revolution");
  app.add_option("--scan-rate", o.scan_rate, "scans per second");
  app.add_option("--duration", o.duration, "seconds measured (after the warm-up)");
  app.add_option("--warmup", o.warmup, "seconds published before measuring");
  app.add_flag("--moving", o.moving, "follow the scene's path (default: stay at its start)");
  app.add_option("--distinct", o.distinct, "static: distinct scans cycled (noise differs)");
  app.add_option("--domain", o.domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, raymap::cli::kMaxDomainId));
  app.add_option("--points-topic", o.points_topic);
  app.add_option("--odom-topic", o.odom_topic);
  app.add_option("--grid-topic", o.grid_topic);
  app.add_option("--diagnostics-topic", o.diag_topic);
  app.add_option("--frame", o.frame, "frame_id of the clouds");
  app.add_option("--map-period", o.period_nominal_s, "raymapd's publish period, seconds");
  app.add_option("--sensors", o.sensors,
                 "lidar, depth (comma-separated; default: what the scene has). Depth cameras "
                 "publish Image + CameraInfo on rt/NAME/depth/{image_rect_raw,camera_info}, their "
                 "optical frames on rt/tf_static")
      ->delimiter(',')
      ->check(CLI::IsMember({"lidar", "depth"}));
  app.add_option("--depth-rate", o.depth_rate,
                 "frames per second of every depth camera (0: each "
                 "camera's own rate)");
  app.add_option(
         "--subscriber-priority", o.subscriber_priority,
         "SCHED_FIFO priority of the thread that takes the GridMaps (1-99; 0: normal), as a "
         "real-time planner's would run; refused without the privilege (reported). Its DDS "
         "receive thread takes its priority from CYCLONEDDS_URI: add "
         "config/cyclonedds-realtime-receive.xml (tools/bench does with this option)")
      ->check(CLI::Range(0, 99));
}

/// The scene and what of it runs: the lidar (resized as the options say, standing still unless
/// --moving) and/or the depth cameras.
struct Sensors {
  raymap::sim::SceneFile scene;
  raymap::sim::SimulationConfig simulation;
  bool lidar = false;
  bool depth = false;
};

raymap::Result<Sensors> loadSensors(LoadOptions& o) {
  using namespace raymap;
  if (o.scene_path.empty()) {
    auto found = driver::findDefaultScene("yard.yaml", RAYMAP_SOURCE_SCENES_DIR);
    if (!found) {
      return Unexpected(std::move(found).error());
    }
    o.scene_path = std::move(found).value();
  }
  auto scene_file = sim::loadSceneFile(o.scene_path);
  if (!scene_file) {
    return Unexpected(std::move(scene_file).error());
  }
  Sensors s{std::move(scene_file).value(), {}, false, false};
  const auto chosen = [&o](const char* name) {
    return std::find(o.sensors.begin(), o.sensors.end(), name) != o.sensors.end();
  };
  s.lidar = o.sensors.empty() ? s.scene.has_lidar : chosen("lidar");
  s.depth = o.sensors.empty() ? !s.scene.depth_cameras.empty() : chosen("depth");
  if (s.depth && s.scene.depth_cameras.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                "--sensors depth: " + o.scene_path + " has no depth_cameras");
  }
  s.simulation = s.scene.simulation;
  s.simulation.lidar.beams = o.beams;
  s.simulation.lidar.columns = o.columns;
  s.simulation.lidar.scan_period_s = 1.0 / o.scan_rate;
  if (!o.moving) {
    const sim::SensorPose start = s.simulation.path.at(s.simulation.path.startTime());
    s.simulation.path = sim::SensorPath::fromPoses({start}).value();
  }
  return s;
}

/// What one measurement saw: the GridMaps' arrivals within the measured window, the first
/// one's (warm-up included), and what was published within the window.
struct Measured {
  std::vector<std::int64_t> arrivals;
  std::int64_t first_map_ns = -1;
  std::uint64_t scans = 0;
  std::uint64_t frames = 0;
  std::uint64_t points = 0;
  bool subscriber_rt_refused = false;
};

/// GridMaps are taken by a thread of their own that blocks on them, as a planner's would: an
/// arrival is stamped when it wakes, not when the publishing loop next gets round to looking
/// (at 10x an OS-1-128 that loop spends most of its time writing scans, and stamping there added
/// its own delays to the measured period).
class GridMapTaker {
 public:
  GridMapTaker(raymap::driver::GridMapListener& grids, std::int64_t measure_from, int priority)
      : grids_(grids), measure_from_(measure_from), thread_([this, priority] { run(priority); }) {}
  GridMapTaker(const GridMapTaker&) = delete;
  GridMapTaker& operator=(const GridMapTaker&) = delete;
  ~GridMapTaker() { stop(); }
  /// Stops the thread and adds what it saw to `out` (once).
  void stop() {
    if (thread_.joinable()) {
      running_.store(false, std::memory_order_relaxed);
      thread_.join();
    }
  }
  void collect(Measured& out) {
    stop();
    out.arrivals = std::move(arrivals_);
    out.first_map_ns = first_map_ns_;
    out.subscriber_rt_refused = rt_refused_;
  }

 private:
  void run(int priority) {
    if (priority > 0) {
      const raymap::platform::RtStatus status = raymap::platform::applyRealtime({priority, 0});
      rt_refused_ = status.scheduling != raymap::platform::RtOutcome::kApplied;
    }
    std::vector<raymap::driver::ReceivedGridMap> received;
    while (running_.load(std::memory_order_relaxed)) {
      received.clear();
      grids_.poll(50000000, received);
      for (const auto& r : received) {
        if (first_map_ns_ < 0) {
          first_map_ns_ = r.arrival_ns;
        }
        if (r.arrival_ns >= measure_from_) {
          arrivals_.push_back(r.arrival_ns);
        }
      }
    }
  }

  raymap::driver::GridMapListener& grids_;
  const std::int64_t measure_from_;
  // Written by the thread only; read after it is joined (the join orders them).
  std::vector<std::int64_t> arrivals_;
  std::int64_t first_map_ns_ = -1;
  bool rt_refused_ = false;
  std::atomic<bool> running_{true};
  std::thread thread_;  // last: starts once the members above exist
};

/// Publishes from t0 until the warm-up and the measured window have passed.
Measured measure(const LoadOptions& o, raymap::driver::LidarPlayback& playback,
                 raymap::driver::DepthPlayback* depth, raymap::driver::GridMapListener& grids,
                 raymap::driver::DiagnosticsListener& diagnostics, bool run_lidar,
                 std::int64_t t0) {
  using namespace raymap;
  const std::int64_t measure_from = t0 + static_cast<std::int64_t>(o.warmup * 1e9);
  const std::int64_t end = measure_from + static_cast<std::int64_t>(o.duration * 1e9);
  std::uint64_t scans_before = 0;
  std::uint64_t points_before = 0;
  std::uint64_t frames_before = 0;
  bool measuring = false;
  GridMapTaker taker(grids, measure_from, o.subscriber_priority);
  while (platform::monotonicNowNs() < end) {
    const std::int64_t now = platform::monotonicNowNs();
    if (!measuring && now >= measure_from) {
      measuring = true;
      scans_before = playback.scansPublished();
      points_before = playback.pointsPublished();
      frames_before = depth != nullptr ? depth->framesPublished() : 0;
    }
    std::int64_t due = run_lidar ? playback.publishDue(now) : now + 100000000;
    if (depth != nullptr) {
      due = std::min(due, depth->publishDue(now));
    }
    diagnostics.poll();
    platform::sleepUntilMonotonicNs(std::min(due, now + 2000000));
  }
  Measured m;
  taker.collect(m);
  m.scans = playback.scansPublished() - scans_before;
  m.frames = depth != nullptr ? depth->framesPublished() - frames_before : 0;
  m.points = playback.pointsPublished() - points_before;
  return m;
}

/// The JSON line: what was published, the GridMaps' period at the subscriber, raymapd's figures.
raymap::cli::Json resultJson(const LoadOptions& o, const Measured& m,
                             const raymap::driver::LidarPlayback& playback,
                             const raymap::driver::DepthPlayback* depth,
                             std::uint32_t points_per_scan,
                             const raymap::driver::DiagnosticsListener& diagnostics,
                             std::int64_t t0) {
  std::vector<double> errors_ms;
  std::vector<double> periods_ms;
  double mean_period_ms = 0.0;
  for (std::size_t i = 1; i < m.arrivals.size(); ++i) {
    const double p = static_cast<double>(m.arrivals[i] - m.arrivals[i - 1]) * 1e-6;
    errors_ms.push_back(std::fabs(p - o.period_nominal_s * 1e3));
    periods_ms.push_back(p);
  }
  if (m.arrivals.size() >= 2) {
    mean_period_ms = static_cast<double>(m.arrivals.back() - m.arrivals.front()) * 1e-6 /
                     static_cast<double>(m.arrivals.size() - 1);
  }
  const auto spread = [](const std::vector<double>& v) {
    return raymap::cli::Json{
        {"p50", quantile(v, 0.5)}, {"p99", quantile(v, 0.99)}, {"max", quantile(v, 1.0)}};
  };
  return {
      {"depth_frames_published", m.frames},
      {"depth_frames_published_total",
       depth != nullptr ? depth->framesPublished() : std::uint64_t{0}},
      {"scan_rate_hz", o.scan_rate},
      {"points_per_scan", points_per_scan},
      {"scans_published", m.scans},
      {"scans_published_total", playback.scansPublished()},
      {"points_per_s", static_cast<double>(m.points) / o.duration},
      {"maps_received", m.arrivals.size()},
      {"first_map_ms", m.first_map_ns < 0 ? -1.0 : static_cast<double>(m.first_map_ns - t0) * 1e-6},
      {"map_period_mean_ms", mean_period_ms},
      {"map_period_error_ms", spread(errors_ms)},
      {"map_period_ms", spread(periods_ms)},
      {"raymapd", raymapdFigures(diagnostics)},
  };
}

/// Waits (at most 5 s) for raymapd's readers of what is published.
void waitForReaders(const raymap::driver::DriverPublisher& publisher,
                    const raymap::driver::DepthPlayback* depth, bool run_lidar) {
  for (int i = 0; i < 100 && !((!run_lidar || publisher.matchedCloudReaders() > 0) &&
                               (depth == nullptr || depth->matched()));
       ++i) {
    raymap::platform::sleepUntilMonotonicNs(raymap::platform::monotonicNowNs() + 50000000);
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace raymap;
  CLI::App app{"raymap-load: publish a simulated lidar to raymapd and measure its GridMaps"};
  LoadOptions o;
  addOptions(app, o);
  CLI11_PARSE(app, argc, argv);
  const auto domain_id = cli::domainFromOptionOrEnvironment(o.domain);
  if (!domain_id) {
    std::fprintf(stderr, "raymap-load: %s\n", domain_id.error().message.c_str());
    return 2;
  }
  auto sensors = loadSensors(o);
  if (!sensors) {
    std::fprintf(stderr, "raymap-load: %s\n", sensors.error().message.c_str());
    return 2;
  }
  driver::SimulatedLidar lidar(sensors->scene.scene, sensors->simulation);
  auto participant =
      security::openToolParticipant(domain_id.value(), "raymap-load", security::kToolsEnclave);
  if (!participant) {
    std::fprintf(stderr, "raymap-load: %s\n", participant.error().message.c_str());
    return 1;
  }
  auto publisher = driver::DriverPublisher::create(participant.value(), o.points_topic,
                                                   o.odom_topic, lidar.pointsPerScan());
  auto grids = driver::GridMapListener::create(participant.value(), o.grid_topic);
  auto diagnostics = driver::DiagnosticsListener::create(participant.value(), o.diag_topic);
  if (!publisher || !grids || !diagnostics) {
    // Each refusal says why (a topic DDS Security does not allow names the permissions file).
    const std::string why = !publisher ? publisher.error().message
                            : !grids   ? grids.error().message
                                       : diagnostics.error().message;
    std::fprintf(stderr, "raymap-load: cannot create the DDS endpoints: %s\n", why.c_str());
    return 1;
  }
  driver::PlaybackOptions options;
  options.scan_rate_hz = o.scan_rate;
  options.distinct_scans = o.distinct;
  options.frame = o.frame.c_str();
  driver::LidarPlayback playback(lidar, *publisher.value(), options);
  std::unique_ptr<driver::DepthPlayback> depth;
  if (sensors->depth) {
    driver::DepthPlaybackOptions depth_options;
    depth_options.rate_hz = o.depth_rate;
    depth_options.odometry_rate_hz = sensors->lidar ? 0.0 : 50.0;  // the lidar's playback sends it
    auto created = driver::DepthPlayback::create(
        participant.value(), *publisher.value(), sensors->scene.scene, sensors->scene.depth_cameras,
        sensors->simulation.path, sensors->simulation.seed, depth_options);
    if (!created) {
      std::fprintf(stderr, "raymap-load: %s\n", created.error().message.c_str());
      return 2;
    }
    depth = std::move(created).value();
  }
  waitForReaders(*publisher.value(), depth.get(), sensors->lidar);
  const std::int64_t t0 = platform::monotonicNowNs();
  const std::int64_t wall0 = platform::realtimeNowNs();
  playback.start(t0, wall0);
  if (depth) {
    depth->start(t0, wall0);
  }
  const Measured measured =
      measure(o, playback, depth.get(), *grids.value(), *diagnostics.value(), sensors->lidar, t0);
  if (measured.subscriber_rt_refused) {
    std::fprintf(stderr, "raymap-load: --subscriber-priority %d refused: normal scheduling\n",
                 o.subscriber_priority);
  }
  // One more diagnostics report covers the end of the run.
  const std::int64_t settle = platform::monotonicNowNs() + 1200000000;
  while (platform::monotonicNowNs() < settle) {
    diagnostics.value()->poll();
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 50000000);
  }
  const cli::Json result = resultJson(o, measured, playback, depth.get(), lidar.pointsPerScan(),
                                      *diagnostics.value(), t0);
  std::printf("%s\n", cli::dumpJson(result).c_str());
  return 0;
}
