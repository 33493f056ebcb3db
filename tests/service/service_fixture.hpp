// SPDX-License-Identifier: BSD-3-Clause
// What the raymapd tests share: a unique DDS domain per test, a configuration written for it,
// and the ROS-like endpoints (a simulated lidar driver, GridMap and diagnostics subscribers).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "src/dds/entities.hpp"
#include "src/driver/lidar_playback.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/driver/simulated_lidar.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/support/fake_notify_socket.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {

// Tests check behaviour, with bounds that a machine ten times slower than the development VM
// still meets (a sanitizer build on a busy 2-core CI runner); the precise periods, latencies and
// times are the benchmarks' to record (docs/testing.md).

/// @brief How long a test waits for raymapd's READY=1 and for DDS discovery, which normally take
/// well under a second. The waits end as soon as the event happens.
inline constexpr std::chrono::seconds kStartWait{30};
inline constexpr double kStartWaitS = static_cast<double>(kStartWait.count());

/// @brief The monotonic instant (nanoseconds) kStartWait from now: where a polling wait for
/// start-up or discovery gives up.
inline std::int64_t startWaitEndNs() {
  return platform::monotonicNowNs() + static_cast<std::int64_t>(kStartWaitS * 1e9);
}

/// @brief The mean publish period a test accepts from raymapd at heightmap.rate_hz 5 (nominal
/// 200 ms), in milliseconds: a factor of two either way. Publish instants are absolute deadlines
/// on the monotonic clock, so a slow or busy machine keeps the period at 200 ms and only a stall
/// of whole periods (skipped, never caught up in a burst) lengthens it; a wrong rate (10 Hz, the
/// diagnostics' 1 Hz), bursts, or maps that stop coming fall outside. The period's precision is
/// recorded by tools/bench/run-daemon-benchmarks.sh and run-overload-benchmarks.sh
/// (map_period_mean_ms, map_period_error_ms) and by tools/soak.sh.
inline constexpr double kFastestPeriodMs = 100.0;
inline constexpr double kSlowestPeriodMs = 400.0;

/// @brief The fewest GridMaps a test expects from `seconds` of publishing at 5 Hz: the whole
/// time at the slowest accepted period, less `startup_s` before the first map (the first scans
/// going in, the next publish instant) when the maps start with the input.
std::size_t fewestMaps(double seconds, double startup_s = 1.0);

/// @brief Expects `maps` (as received, oldest first) in order and at about 5 Hz: no map older
/// than the one before it, the data moving on over the run, and a mean period between
/// kFastestPeriodMs and kSlowestPeriodMs. Equal stamps are allowed: a map's stamp is its newest
/// scan's, and a cycle in which no new scan went in (on a slow machine a period can pass without
/// one) republishes the same data.
void expectInOrderAtAboutFiveHertz(const std::vector<driver::ReceivedGridMap>& maps);

/// @brief A DDS domain in 200..229 that the tests before this one did not use: handed out in
/// turn across test processes (the end-to-end tests run one at a time; the unit DDS tests use
/// 100 + pid % 100, the CLI ones 20..99).
std::uint32_t uniqueDomain();

/// @brief raymapd configuration for the tests: CPU backend, 12 m height map at 5 Hz, one lidar on
/// rt/points in frame "lidar", odometry on rt/odom; `extra` is appended (YAML sections that are
/// not already present).
std::string serviceConfig(std::uint32_t domain, const std::string& extra = "",
                          std::uint32_t scan_slots = 4);

/// @brief The publishing period of `maps` from the subscriber's arrival times, milliseconds: the
/// slope of a least-squares line through (index, arrival) from maps[first] on, so one message
/// delivered late (a loaded machine, the sanitizer build) moves it by a fraction of its delay
/// instead of the delay divided by the count, as the mean of first-to-last would. 0 with fewer
/// than two maps from `first`.
double publishPeriodMs(const std::vector<driver::ReceivedGridMap>& maps, std::size_t first);

/// @brief The yard scene with its lidar set to `beams` x `columns`, moving along its path or not.
driver::SimulatedLidar yardLidar(int beams, int columns, bool moving);

/// @brief raymapd started on `config_text` (written to a temporary folder) with a fake systemd
/// notify socket; `watchdog` sets WATCHDOG_USEC to 1 s. `launcher` runs it (e.g. `ip netns exec
/// NAME`: raymapd is then its argument), `environment` adds NAME=value variables.
struct RunningDaemon {
  RunningDaemon(const std::string& config_text, bool watchdog,
                const std::vector<std::string>& launcher = {},
                const std::vector<std::string>& environment = {});
  std::string log() const;
  /// @brief The log once it contains `text`, polled until then or for at most `max_seconds`
  /// (then as it is). raymapd publishes a report before it logs the report's line, so a test
  /// that has just received the report may read the log a moment too early.
  std::string logOnceItHas(const std::string& text, double max_seconds = kStartWaitS) const;

  TempDir dir;
  FakeNotifySocket notify;
  std::unique_ptr<DaemonProcess> process;
};

/// @brief Stops the service with SIGTERM and expects a clean exit (status 0).
void expectCleanStop(RunningDaemon& daemon);

/// @brief The test's side of the DDS graph, in its own participants (the publisher and the
/// subscribers are independent of each other, like separate ROS nodes).
struct RosSide {
  /// @param publisher_security, subscriber_security DDS Security of each participant (the
  ///        files of its enclave; empty: none)
  explicit RosSide(std::uint32_t domain, std::uint32_t max_points,
                   const dds::SecurityFiles& publisher_security = {},
                   const dds::SecurityFiles& subscriber_security = {});
  std::optional<dds::Participant> publisher_participant;
  std::optional<dds::Participant> subscriber_participant;
  std::unique_ptr<driver::DriverPublisher> publisher;
  std::unique_ptr<driver::GridMapListener> grid_maps;
  std::unique_ptr<driver::DiagnosticsListener> diagnostics;
  /// @brief Waits until raymapd's cloud and pose readers and its height-map writer are matched
  /// (discovery), up to `timeout_s`.
  bool waitForService(double timeout_s);
  /// @brief Plays `lidar` for `seconds`, collecting GridMaps and diagnostics meanwhile; the
  /// recording's stamps start `stamp_offset_ns` from the wall clock now (negative: in the past,
  /// as a bag played again).
  void play(const driver::SimulatedLidar& lidar, driver::PlaybackOptions options, double seconds,
            std::vector<driver::ReceivedGridMap>& maps, std::int64_t stamp_offset_ns = 0);
  /// @brief Polls diagnostics for `seconds` (reports come at 1 Hz).
  void settle(double seconds, std::vector<driver::ReceivedGridMap>* maps = nullptr);
  /// @brief Polls like settle() until `done` returns true, at most `max_seconds`: for what
  /// raymapd reports once it has happened (a report with every scan in, a status turned stale),
  /// which a slow machine reports later. @return whether `done` became true.
  bool settleUntil(double max_seconds, const std::function<bool()>& done,
                   std::vector<driver::ReceivedGridMap>* maps = nullptr);
};

/// @brief How a received GridMap's heights compare with the scene's truth.
struct HeightCheck {
  int surfaces = 0;  ///< surface cells with an unambiguous truth
  int within = 0;    ///< of those, within one voxel of it
};

/// @brief Every surface cell of a received GridMap (grid_map order: column-major, (0, 0) at the
/// +x/+y corner) against the scene's exact surface (reference: the ground, clearance 0.5 m).
HeightCheck checkHeights(const driver::ReceivedGridMap& map, const sim::Scene& scene);

}  // namespace raymap::test
