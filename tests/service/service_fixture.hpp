// SPDX-License-Identifier: BSD-3-Clause
// What the raymapd tests share: a unique DDS domain per test, a configuration written for it,
// and the ROS-like endpoints (a simulated lidar driver, GridMap and diagnostics subscribers).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/dds/entities.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/support/fake_notify_socket.hpp"
#include "tests/support/temp_dir.hpp"
#include "tools/dds_driver/lidar_playback.hpp"
#include "tools/dds_driver/ros_endpoints.hpp"
#include "tools/dds_driver/simulated_lidar.hpp"

namespace raymap::test {

/// @brief A DDS domain no other test uses at the same time (tests of this folder run serially,
/// other test executables use 100 + pid % 100).
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
/// notify socket; `watchdog` sets WATCHDOG_USEC to 1 s.
struct RunningDaemon {
  RunningDaemon(const std::string& config_text, bool watchdog);
  std::string log() const;

  TempDir dir;
  FakeNotifySocket notify;
  std::unique_ptr<DaemonProcess> process;
};

/// @brief The test's side of the DDS graph, in its own participants (the publisher and the
/// subscribers are independent of each other, like separate ROS nodes).
struct RosSide {
  explicit RosSide(std::uint32_t domain, std::uint32_t max_points);
  std::optional<dds::Participant> publisher_participant;
  std::optional<dds::Participant> subscriber_participant;
  std::unique_ptr<driver::DriverPublisher> publisher;
  std::unique_ptr<driver::GridMapListener> grid_maps;
  std::unique_ptr<driver::DiagnosticsListener> diagnostics;
  /// @brief Waits until raymapd's cloud and pose readers and its height-map writer are matched
  /// (discovery), up to `timeout_s`.
  bool waitForService(double timeout_s);
  /// @brief Plays `lidar` for `seconds`, collecting GridMaps and diagnostics meanwhile.
  void play(const driver::SimulatedLidar& lidar, driver::PlaybackOptions options, double seconds,
            std::vector<driver::ReceivedGridMap>& maps);
  /// @brief Polls diagnostics for `seconds` (reports come at 1 Hz).
  void settle(double seconds, std::vector<driver::ReceivedGridMap>* maps = nullptr);
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
