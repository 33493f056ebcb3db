// SPDX-License-Identifier: BSD-3-Clause
// The raymapd tests' shared set-up.
#include "tests/service/service_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "platform/clock.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/scene_truth.hpp"

namespace raymap::test {

double publishPeriodMs(const std::vector<driver::ReceivedGridMap>& maps, std::size_t first) {
  if (maps.size() < first + 2) {
    return 0.0;
  }
  const auto n = static_cast<double>(maps.size() - first);
  const double mean_index = (n - 1.0) / 2.0;
  const std::int64_t t0 = maps[first].arrival_ns;
  double mean_t = 0.0;
  for (std::size_t i = first; i < maps.size(); ++i) {
    mean_t += static_cast<double>(maps[i].arrival_ns - t0) / n;
  }
  double covariance = 0.0;
  double variance = 0.0;
  for (std::size_t i = first; i < maps.size(); ++i) {
    const double k = static_cast<double>(i - first) - mean_index;
    covariance += k * (static_cast<double>(maps[i].arrival_ns - t0) - mean_t);
    variance += k * k;
  }
  return covariance / variance * 1e-6;
}

std::size_t fewestMaps(double seconds, double startup_s) {
  const double publishing_ms = std::max(0.0, seconds - startup_s) * 1000.0;
  return static_cast<std::size_t>(publishing_ms / kSlowestPeriodMs);
}

void expectInOrderAtAboutFiveHertz(const std::vector<driver::ReceivedGridMap>& maps) {
  ASSERT_GE(maps.size(), 4U) << "too few GridMaps for a period";
  std::size_t older = 0;
  for (std::size_t i = 1; i < maps.size(); ++i) {
    older += maps[i].stamp_ns < maps[i - 1].stamp_ns ? 1U : 0U;
  }
  EXPECT_EQ(older, 0U) << "GridMaps whose stamp is older than the one before";
  EXPECT_GT(maps.back().stamp_ns, maps.front().stamp_ns) << "the data never moved on";
  // From the third map: the first cycles size the height map's buffers.
  const double period = publishPeriodMs(maps, 2);
  EXPECT_GE(period, kFastestPeriodMs) << maps.size() << " GridMaps";
  EXPECT_LE(period, kSlowestPeriodMs) << maps.size() << " GridMaps";
  std::printf("%zu GridMaps, mean period %.1f ms at the subscriber\n", maps.size(), period);
}

std::uint32_t uniqueDomain() {
  // Every test pins Cyclone DDS to loopback (tests/CMakeLists.txt sets it); without it the
  // traffic would leave the machine and large clouds would meet the default socket buffer.
  EXPECT_NE(std::getenv("CYCLONEDDS_URI"), nullptr)
      << "CYCLONEDDS_URI is not set: run the tests through ctest";
  // Domains are handed out in turn across the test processes (a counter in a file, under an
  // flock): two tests in a row never share one, so a participant the previous test left behind
  // (a killed process's lease outlives it, 10 s by default) is never matched by the next test's
  // readers; a domain comes back after kDomains others. Without the file: by process id.
  constexpr std::uint32_t kFirst = 200;
  constexpr std::uint32_t kDomains = 30;
  const std::string path =
      (std::filesystem::temp_directory_path() / "raymap-test-dds-domain-counter").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd >= 0 && ::flock(fd, LOCK_EX) == 0) {
    char text[24] = {};
    const ssize_t got = ::pread(fd, text, sizeof(text) - 1, 0);
    const unsigned long n = got > 0 ? std::strtoul(text, nullptr, 10) : 0UL;
    const std::string next = std::to_string((n + 1) % kDomains) + "\n";
    const bool saved = ::ftruncate(fd, 0) == 0 && ::pwrite(fd, next.data(), next.size(), 0) ==
                                                      static_cast<ssize_t>(next.size());
    ::flock(fd, LOCK_UN);
    ::close(fd);
    if (saved) {
      return kFirst + static_cast<std::uint32_t>(n % kDomains);
    }
  } else if (fd >= 0) {
    ::close(fd);
  }
  static std::uint32_t next = 0;
  return kFirst + (static_cast<std::uint32_t>(::getpid()) * 3 + next++) % kDomains;
}

std::string serviceConfig(std::uint32_t domain, const std::string& extra,
                          std::uint32_t scan_slots) {
  std::string text =
      "map: {resolution: 0.1, window: [6, 6, 3]}\n"
      "backend: {name: cpu, threads: 2}\n"
      "pose: {source: odometry, topic: rt/odom, world_frame: odom, base_frame: base_link}\n"
      "sensors:\n"
      "  - {name: lidar, topic: rt/points, frame: lidar, min_range: 0.3, max_range: 20,\n"
      "     max_points: 70000}\n"
      "heightmap: {rate_hz: 5, size: 12, base_height: 1.2}\n"
      "dds: {domain: " +
      std::to_string(domain) +
      ", voxels_topic: rt/raymap/occupied_voxels}\n"
      "queues: {scan_slots: " +
      std::to_string(scan_slots) + "}\n";
  return text + extra;
}

RunningDaemon::RunningDaemon(const std::string& config_text, bool watchdog,
                             const std::vector<std::string>& launcher,
                             const std::vector<std::string>& environment) {
  const std::string config = dir.file("raymapd.yaml");
  std::ofstream(config) << config_text;
  std::vector<std::string> env = {"NOTIFY_SOCKET=" + notify.path()};
  if (watchdog) {
    // WatchdogSec=1s: systemd restarts a service that has not pinged for 1 s.
    env.push_back("WATCHDOG_USEC=1000000");
  }
  env.insert(env.end(), environment.begin(), environment.end());
  std::vector<std::string> command = launcher;
  command.insert(command.end(), {RAYMAPD_PATH, "--config", config});
  const std::string binary = command.front();
  command.erase(command.begin());
  process = std::make_unique<DaemonProcess>(binary, command, env, dir.file("raymapd.log"));
}

std::string RunningDaemon::log() const { return readFile(dir.file("raymapd.log")); }

std::string RunningDaemon::logOnceItHas(const std::string& text, double max_seconds) const {
  const std::int64_t until =
      platform::monotonicNowNs() + static_cast<std::int64_t>(max_seconds * 1e9);
  std::string text_now = log();
  while (text_now.find(text) == std::string::npos && platform::monotonicNowNs() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    text_now = log();
  }
  return text_now;
}

driver::SimulatedLidar yardLidar(int beams, int columns, bool moving) {
  auto file = sim::loadSceneFile(std::string(RAYMAP_SCENES_DIR) + "/yard.yaml");
  EXPECT_TRUE(file.has_value());
  sim::SimulationConfig simulation = file.value().simulation;
  simulation.lidar.beams = beams;
  simulation.lidar.columns = columns;
  if (!moving) {
    simulation.path =
        sim::SensorPath::fromPoses({simulation.path.at(simulation.path.startTime())}).value();
  }
  return driver::SimulatedLidar(file.value().scene, simulation);
}

RosSide::RosSide(std::uint32_t domain, std::uint32_t max_points,
                 const dds::SecurityFiles& publisher_security,
                 const dds::SecurityFiles& subscriber_security) {
  dds::DomainSettings pub_settings;
  pub_settings.security = publisher_security;
  dds::DomainSettings sub_settings;
  sub_settings.security = subscriber_security;
  auto pub = dds::Participant::create(domain, pub_settings);
  auto sub = dds::Participant::create(domain, sub_settings);
  EXPECT_TRUE(pub.has_value() && sub.has_value())
      << (pub ? std::string() : pub.error().message) << (sub ? "" : sub.error().message);
  publisher_participant.emplace(std::move(pub).value());
  subscriber_participant.emplace(std::move(sub).value());
  // Each endpoint's error said before value() stops the test (a refusal by DDS Security).
  const auto made = [](auto&& created) {
    if (!created) {
      std::fprintf(stderr, "RosSide: %s\n", created.error().message.c_str());
    }
    return std::move(created).value();
  };
  publisher = made(
      driver::DriverPublisher::create(*publisher_participant, "rt/points", "rt/odom", max_points));
  grid_maps = made(driver::GridMapListener::create(*subscriber_participant, "rt/height_map"));
  diagnostics =
      made(driver::DiagnosticsListener::create(*subscriber_participant, "rt/diagnostics"));
}

bool RosSide::waitForService(double timeout_s) {
  const std::int64_t end = platform::monotonicNowNs() + static_cast<std::int64_t>(timeout_s * 1e9);
  while (platform::monotonicNowNs() < end) {
    // The pose reader too (odometry or /tf, whichever the configuration takes): poses published
    // before it matched are lost, and the first scans would then have none (scans_dropped_no_pose).
    const std::uint32_t pose_readers =
        publisher->matchedOdometryReaders() + publisher->matchedTfReaders();
    if (publisher->matchedCloudReaders() > 0 && pose_readers > 0 &&
        grid_maps->matchedWriters() > 0) {
      return true;
    }
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 20000000);
  }
  return false;
}

void RosSide::play(const driver::SimulatedLidar& lidar, driver::PlaybackOptions options,
                   double seconds, std::vector<driver::ReceivedGridMap>& maps,
                   std::int64_t stamp_offset_ns) {
  driver::LidarPlayback playback(lidar, *publisher, options);
  const std::int64_t t0 = platform::monotonicNowNs();
  playback.start(t0, platform::realtimeNowNs() + stamp_offset_ns);
  const std::int64_t end = t0 + static_cast<std::int64_t>(seconds * 1e9);
  for (std::int64_t now = t0; now < end; now = platform::monotonicNowNs()) {
    const std::int64_t due = playback.publishDue(now);
    grid_maps->poll(0, maps);
    diagnostics->poll();
    platform::sleepUntilMonotonicNs(std::min(due, now + 2000000));
  }
}

void RosSide::settle(double seconds, std::vector<driver::ReceivedGridMap>* maps) {
  (void)settleUntil(
      seconds, [] { return false; }, maps);
}

bool RosSide::settleUntil(double max_seconds, const std::function<bool()>& done,
                          std::vector<driver::ReceivedGridMap>* maps) {
  const std::int64_t end =
      platform::monotonicNowNs() + static_cast<std::int64_t>(max_seconds * 1e9);
  std::vector<driver::ReceivedGridMap> ignored;
  while (platform::monotonicNowNs() < end) {
    grid_maps->poll(20000000, maps != nullptr ? *maps : ignored);
    diagnostics->poll();
    if (done()) {
      return true;
    }
  }
  return done();
}

HeightCheck checkHeights(const driver::ReceivedGridMap& map, const sim::Scene& scene) {
  HeightCheck check;
  const std::vector<float>* elevation = map.layer("elevation");
  const std::vector<float>* kind = map.layer("kind");
  if (elevation == nullptr || kind == nullptr) {
    return check;
  }
  const auto cells_x = static_cast<int>(std::lround(map.length_x / map.resolution));
  const auto cells_y = static_cast<int>(std::lround(map.length_y / map.resolution));
  for (int j = 0; j < cells_y; ++j) {
    for (int i = 0; i < cells_x; ++i) {
      const std::size_t c = static_cast<std::size_t>(i + j * cells_x);
      if ((*kind)[c] != 1.0f) {  // RM_HM_SURFACE
        continue;
      }
      const double x = map.centre_x + (0.5 * cells_x - i - 0.5) * map.resolution;
      const double y = map.centre_y + (0.5 * cells_y - j - 0.5) * map.resolution;
      const auto truth = unambiguousTruth(scene, {x, y, 0.0}, map.resolution, 0.0, 0.5);
      if (!truth) {
        continue;  // an object's edge: lidar noise puts its side into the next column
      }
      ++check.surfaces;
      if (std::fabs(static_cast<double>((*elevation)[c]) - truth->height) <= map.resolution) {
        ++check.within;
      }
    }
  }
  return check;
}

void expectCleanStop(RunningDaemon& daemon) {
  const auto stopped = daemon.process->stop(SIGTERM, kStopWait);
  ASSERT_TRUE(stopped.has_value());
  EXPECT_EQ(stopped->first, 0) << daemon.log();
}

}  // namespace raymap::test
