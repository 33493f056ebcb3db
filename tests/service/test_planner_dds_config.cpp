// SPDX-License-Identifier: BSD-3-Clause
// The Cyclone DDS configuration shipped for a planner (config/cyclonedds-realtime-receive.xml):
// loaded after the loopback file, a separate subscriber process (`raymap echo`) receives
// raymapd's height maps, and its receive path runs in one receive thread at SCHED_FIFO 50 (the
// file's point: Cyclone 0.10 cannot set the scheduling of the "recvUC" thread it starts
// otherwise). What this buys in period at the subscriber is the benchmarks' to record
// (docs/benchmarks.md, "The period a real-time subscriber sees").
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <sched.h>

#include "platform/clock.hpp"
#include "platform/rt.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

struct ThreadScheduling {
  int policy = -1;
  int priority = -1;
};

/// The threads of process `pid` by name (the first of each name), with their scheduling.
std::map<std::string, ThreadScheduling> threadsOf(pid_t pid) {
  std::map<std::string, ThreadScheduling> threads;
  const std::string task_dir = "/proc/" + std::to_string(pid) + "/task";
  std::error_code error;  // the process may have ended: then no threads
  for (const auto& entry : std::filesystem::directory_iterator(task_dir, error)) {
    const std::string tid = entry.path().filename().string();
    std::ifstream comm(entry.path() / "comm");
    std::string name;
    if (!std::getline(comm, name)) {
      continue;  // the thread ended meanwhile
    }
    const auto id = static_cast<pid_t>(std::stoi(tid));
    ThreadScheduling scheduling;
    scheduling.policy = sched_getscheduler(id);
    sched_param param{};
    if (sched_getparam(id, &param) == 0) {
      scheduling.priority = param.sched_priority;
    }
    threads.emplace(name, scheduling);
  }
  return threads;
}

/// Waits until process `pid` has a thread named `name` (Cyclone starts them while the
/// participant is created); returns every thread then.
std::map<std::string, ThreadScheduling> waitForThread(DaemonProcess& process,
                                                      const std::string& name) {
  const std::int64_t until = startWaitEndNs();
  std::map<std::string, ThreadScheduling> threads;
  while (process.running() && platform::monotonicNowNs() < until) {
    threads = threadsOf(process.pid());
    if (threads.count(name) != 0) {
      return threads;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return threads;
}

/// Waits until `raymap echo` has found raymapd's writer (its first line on standard error,
/// written to `stderr_path`, comes after the participant, every Cyclone thread and discovery);
/// returns its threads then (none if it exited or did not get there within kStartWait).
std::map<std::string, ThreadScheduling> threadsOnceReading(DaemonProcess& echo,
                                                           const std::string& stderr_path) {
  const std::int64_t until = startWaitEndNs();
  while (echo.running() && platform::monotonicNowNs() < until) {
    std::ifstream err(stderr_path);
    std::string line;
    if (std::getline(err, line) && line.rfind("raymap echo: rt/height_map", 0) == 0) {
      return threadsOf(echo.pid());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return {};
}

bool realtimeAllowed() {
  bool allowed = false;
  std::thread probe([&] {
    allowed = platform::applyRealtime({50, 0}).scheduling == platform::RtOutcome::kApplied;
  });
  probe.join();
  return allowed;
}

}  // namespace

TEST(PlannerDdsConfig, ARealTimeSubscriberTakesTheMapsThroughOneRealTimeReceiveThread) {
  if (!realtimeAllowed()) {
    GTEST_SKIP() << "SCHED_FIFO 50 is not allowed here: Cyclone would abort the subscriber";
  }
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read before this test starts any thread
  const char* base_uri = std::getenv("CYCLONEDDS_URI");
  ASSERT_NE(base_uri, nullptr) << "the tests pin Cyclone DDS to loopback";
  const std::uint32_t domain = uniqueDomain();
  TempDir dir;

  // Without the file: Cyclone's unicast receive thread "recvUC", at normal priority; this is
  // what the file is for (and shows that the inspection below sees Cyclone's threads).
  {
    DaemonProcess echo(
        RAYMAP_CLI_PATH,
        {"echo", "rt/height_map", "--domain", std::to_string(domain), "--wait", "60"},
        {std::string("CYCLONEDDS_URI=") + base_uri}, (dir.path() / "plain.err").string());
    const auto threads = waitForThread(echo, "recvUC");
    ASSERT_EQ(threads.count("recvUC"), 1u) << "threads: " << threads.size();
    EXPECT_EQ(threads.at("recvUC").policy, SCHED_OTHER);
    echo.stop(SIGKILL, kStopWait);
  }

  RunningDaemon daemon(serviceConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS)) << daemon.log();

  // The planner: a process of its own with the shipped file after the network one.
  const std::string uri =
      std::string(base_uri) + ",file://" RAYMAP_CONFIG_DIR "/cyclonedds-realtime-receive.xml";
  DaemonProcess echo(
      RAYMAP_CLI_PATH,
      {"echo", "rt/height_map", "--domain", std::to_string(domain), "--count", "3", "--wait", "60"},
      {"CYCLONEDDS_URI=" + uri}, (dir.path() / "realtime.err").string());
  const auto threads = threadsOnceReading(echo, (dir.path() / "realtime.err").string());
  ASSERT_EQ(threads.count("recv"), 1u) << "the subscriber did not start its receive thread";
  EXPECT_EQ(threads.count("recvUC"), 0u) << "a receive thread the file cannot schedule";
  EXPECT_EQ(threads.at("recv").policy, SCHED_FIFO);
  EXPECT_EQ(threads.at("recv").priority, 50);
  ASSERT_EQ(threads.count("dq.user"), 1u);
  EXPECT_EQ(threads.at("dq.user").policy, SCHED_FIFO);
  EXPECT_EQ(threads.at("dq.user").priority, 50);

  // And it receives the maps: echo exits 0 after three.
  std::vector<driver::ReceivedGridMap> maps;
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, /*moving=*/false);
  const std::int64_t until = startWaitEndNs();
  while (echo.running() && platform::monotonicNowNs() < until) {
    ros.play(lidar, driver::PlaybackOptions{}, 1.0, maps);
  }
  const auto status = echo.stop(SIGTERM, kStopWait);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->first, 0) << "raymap echo with the real-time file did not take 3 maps";
  expectCleanStop(daemon);
}

}  // namespace raymap::test
