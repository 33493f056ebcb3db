// SPDX-License-Identifier: BSD-3-Clause
// raymap-load: drives a running raymapd like a robot would (a simulated lidar driver publishing
// PointCloud2 and odometry over DDS) and measures what comes back (GridMap period at the
// subscriber, how soon the first GridMap follows the first scan, the service's own latency and
// drop counters from its diagnostics). Prints JSON.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
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

}  // namespace

int main(int argc, char** argv) {
  using namespace raymap;
  CLI::App app{"raymap-load: publish a simulated lidar to raymapd and measure its GridMaps"};
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
  app.add_option("--scene", scene_path,
                 "scene file (its lidar and path are the defaults; default: the installed "
                 "share/raymap/scenes/yard.yaml)");
  app.add_option("--beams", beams, "lidar beams (128: an Ouster OS-1-128)");
  app.add_option("--columns", columns, "lidar columns per revolution");
  app.add_option("--scan-rate", scan_rate, "scans per second");
  app.add_option("--duration", duration, "seconds measured (after the warm-up)");
  app.add_option("--warmup", warmup, "seconds published before measuring");
  app.add_flag("--moving", moving, "follow the scene's path (default: stay at its start)");
  app.add_option("--distinct", distinct, "static: distinct scans cycled (noise differs)");
  app.add_option("--domain", domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, cli::kMaxDomainId));
  app.add_option("--points-topic", points_topic);
  app.add_option("--odom-topic", odom_topic);
  app.add_option("--grid-topic", grid_topic);
  app.add_option("--diagnostics-topic", diag_topic);
  app.add_option("--frame", frame, "frame_id of the clouds");
  app.add_option("--map-period", period_nominal_s, "raymapd's publish period, seconds");
  app.add_option("--sensors", sensors,
                 "lidar, depth (comma-separated; default: what the scene has). Depth cameras "
                 "publish Image + CameraInfo on rt/NAME/depth/{image_rect_raw,camera_info}, their "
                 "optical frames on rt/tf_static")
      ->delimiter(',')
      ->check(CLI::IsMember({"lidar", "depth"}));
  app.add_option("--depth-rate", depth_rate,
                 "frames per second of every depth camera (0: each "
                 "camera's own rate)");
  app.add_option(
         "--subscriber-priority", subscriber_priority,
         "SCHED_FIFO priority of the thread that takes the GridMaps (1-99; 0: normal), as a "
         "real-time planner's would run; refused without the privilege (reported). Its DDS "
         "receive thread takes its priority from CYCLONEDDS_URI: add "
         "config/cyclonedds-realtime-receive.xml (tools/bench does with this option)")
      ->check(CLI::Range(0, 99));
  CLI11_PARSE(app, argc, argv);

  const auto domain_id = cli::domainFromOptionOrEnvironment(domain);
  if (!domain_id) {
    std::fprintf(stderr, "raymap-load: %s\n", domain_id.error().message.c_str());
    return 2;
  }
  if (scene_path.empty()) {
    auto found = driver::findDefaultScene("yard.yaml", RAYMAP_SOURCE_SCENES_DIR);
    if (!found) {
      std::fprintf(stderr, "raymap-load: %s\n", found.error().message.c_str());
      return 2;
    }
    scene_path = std::move(found).value();
  }
  auto scene_file = sim::loadSceneFile(scene_path);
  if (!scene_file) {
    std::fprintf(stderr, "raymap-load: %s\n", scene_file.error().message.c_str());
    return 2;
  }
  const bool run_lidar = sensors.empty()
                             ? scene_file.value().has_lidar
                             : std::find(sensors.begin(), sensors.end(), "lidar") != sensors.end();
  const bool run_depth = sensors.empty()
                             ? !scene_file.value().depth_cameras.empty()
                             : std::find(sensors.begin(), sensors.end(), "depth") != sensors.end();
  if (run_depth && scene_file.value().depth_cameras.empty()) {
    std::fprintf(stderr, "raymap-load: --sensors depth: %s has no depth_cameras\n",
                 scene_path.c_str());
    return 2;
  }
  sim::SimulationConfig simulation = scene_file.value().simulation;
  simulation.lidar.beams = beams;
  simulation.lidar.columns = columns;
  simulation.lidar.scan_period_s = 1.0 / scan_rate;
  if (!moving) {
    const sim::SensorPose start = simulation.path.at(simulation.path.startTime());
    simulation.path = sim::SensorPath::fromPoses({start}).value();
  }
  driver::SimulatedLidar lidar(scene_file.value().scene, simulation);

  auto participant =
      security::openToolParticipant(domain_id.value(), "raymap-load", security::kToolsEnclave);
  if (!participant) {
    std::fprintf(stderr, "raymap-load: %s\n", participant.error().message.c_str());
    return 1;
  }
  auto publisher = driver::DriverPublisher::create(participant.value(), points_topic, odom_topic,
                                                   lidar.pointsPerScan());
  auto grids = driver::GridMapListener::create(participant.value(), grid_topic);
  auto diagnostics = driver::DiagnosticsListener::create(participant.value(), diag_topic);
  if (!publisher || !grids || !diagnostics) {
    // Each refusal says why (a topic DDS Security does not allow names the permissions file).
    const std::string why = !publisher ? publisher.error().message
                            : !grids   ? grids.error().message
                                       : diagnostics.error().message;
    std::fprintf(stderr, "raymap-load: cannot create the DDS endpoints: %s\n", why.c_str());
    return 1;
  }

  driver::PlaybackOptions options;
  options.scan_rate_hz = scan_rate;
  options.distinct_scans = distinct;
  options.frame = frame.c_str();
  driver::LidarPlayback playback(lidar, *publisher.value(), options);
  std::unique_ptr<driver::DepthPlayback> depth;
  if (run_depth) {
    driver::DepthPlaybackOptions depth_options;
    depth_options.rate_hz = depth_rate;
    depth_options.odometry_rate_hz = run_lidar ? 0.0 : 50.0;  // the lidar's playback sends it
    auto created = driver::DepthPlayback::create(
        participant.value(), *publisher.value(), scene_file.value().scene,
        scene_file.value().depth_cameras, simulation.path, simulation.seed, depth_options);
    if (!created) {
      std::fprintf(stderr, "raymap-load: %s\n", created.error().message.c_str());
      return 2;
    }
    depth = std::move(created).value();
  }
  // Wait for raymapd's readers (discovery).
  for (int i = 0; i < 100 && !((!run_lidar || publisher.value()->matchedCloudReaders() > 0) &&
                               (!depth || depth->matched()));
       ++i) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 50000000);
  }
  const std::int64_t t0 = platform::monotonicNowNs();
  const std::int64_t wall0 = platform::realtimeNowNs();
  playback.start(t0, wall0);
  if (depth) {
    depth->start(t0, wall0);
  }
  std::uint64_t frames_before = 0;
  const std::int64_t measure_from = t0 + static_cast<std::int64_t>(warmup * 1e9);
  const std::int64_t end = measure_from + static_cast<std::int64_t>(duration * 1e9);
  std::uint64_t scans_before = 0;
  std::uint64_t points_before = 0;
  bool measuring = false;
  std::vector<std::int64_t> arrivals;
  std::int64_t first_map_ns = -1;  // the first GridMap's arrival, warm-up included
  // GridMaps are taken by a thread of their own that blocks on them, as a planner's would: an
  // arrival is stamped when it wakes, not when the publishing loop below next gets round to
  // looking (at 10x an OS-1-128 that loop spends most of its time writing scans, and stamping
  // there added its own delays to the measured period).
  std::mutex arrivals_mutex;
  std::atomic<bool> subscribing{true};
  std::atomic<bool> subscriber_rt_refused{false};
  std::thread subscriber([&] {
    if (subscriber_priority > 0) {
      const platform::RtStatus status = platform::applyRealtime({subscriber_priority, 0});
      subscriber_rt_refused.store(status.scheduling != platform::RtOutcome::kApplied);
    }
    std::vector<driver::ReceivedGridMap> received;
    while (subscribing.load(std::memory_order_relaxed)) {
      received.clear();
      grids.value()->poll(50000000, received);
      const std::lock_guard<std::mutex> lock(arrivals_mutex);
      for (const auto& r : received) {
        if (first_map_ns < 0) {
          first_map_ns = r.arrival_ns;
        }
        if (r.arrival_ns >= measure_from) {
          arrivals.push_back(r.arrival_ns);
        }
      }
    }
  });
  while (platform::monotonicNowNs() < end) {
    const std::int64_t now = platform::monotonicNowNs();
    if (!measuring && now >= measure_from) {
      measuring = true;
      scans_before = playback.scansPublished();
      points_before = playback.pointsPublished();
      frames_before = depth ? depth->framesPublished() : 0;
    }
    std::int64_t due = run_lidar ? playback.publishDue(now) : now + 100000000;
    if (depth) {
      due = std::min(due, depth->publishDue(now));
    }
    diagnostics.value()->poll();
    platform::sleepUntilMonotonicNs(std::min(due, now + 2000000));
  }
  subscribing.store(false, std::memory_order_relaxed);
  subscriber.join();
  if (subscriber_rt_refused.load()) {
    std::fprintf(stderr, "raymap-load: --subscriber-priority %d refused: normal scheduling\n",
                 subscriber_priority);
  }
  const std::uint64_t published = playback.scansPublished() - scans_before;
  const std::uint64_t frames = depth ? depth->framesPublished() - frames_before : 0;
  const std::uint64_t points = playback.pointsPublished() - points_before;
  // One more diagnostics report covers the end of the run.
  const std::int64_t settle = platform::monotonicNowNs() + 1200000000;
  while (platform::monotonicNowNs() < settle) {
    diagnostics.value()->poll();
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 50000000);
  }

  std::vector<double> errors_ms;
  std::vector<double> periods_ms;
  double mean_period_ms = 0.0;
  for (std::size_t i = 1; i < arrivals.size(); ++i) {
    const double p = static_cast<double>(arrivals[i] - arrivals[i - 1]) * 1e-6;
    errors_ms.push_back(std::fabs(p - period_nominal_s * 1e3));
    periods_ms.push_back(p);
  }
  if (arrivals.size() >= 2) {
    mean_period_ms = static_cast<double>(arrivals.back() - arrivals.front()) * 1e-6 /
                     static_cast<double>(arrivals.size() - 1);
  }
  const auto spread = [](const std::vector<double>& v) {
    return cli::Json{
        {"p50", quantile(v, 0.5)}, {"p99", quantile(v, 0.99)}, {"max", quantile(v, 1.0)}};
  };
  const cli::Json result = {
      {"depth_frames_published", frames},
      {"depth_frames_published_total", depth ? depth->framesPublished() : std::uint64_t{0}},
      {"scan_rate_hz", scan_rate},
      {"points_per_scan", lidar.pointsPerScan()},
      {"scans_published", published},
      {"scans_published_total", playback.scansPublished()},
      {"points_per_s", static_cast<double>(points) / duration},
      {"maps_received", arrivals.size()},
      {"first_map_ms", first_map_ns < 0 ? -1.0 : static_cast<double>(first_map_ns - t0) * 1e-6},
      {"map_period_mean_ms", mean_period_ms},
      {"map_period_error_ms", spread(errors_ms)},
      {"map_period_ms", spread(periods_ms)},
      {"raymapd", raymapdFigures(*diagnostics.value())},
  };
  std::printf("%s\n", cli::dumpJson(result).c_str());
  return 0;
}
