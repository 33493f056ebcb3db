// SPDX-License-Identifier: BSD-3-Clause
// raymapd with DDS Security (SROS2 keystores), end to end in separate processes on loopback: an
// authorised lidar and planner work as before; an unauthenticated participant on the same domain
// neither reads the maps nor puts clouds into them; an authenticated enclave without the
// permission cannot publish clouds or maps; nothing readable crosses the wire (a capture of the
// loopback traffic, with tcpdump, holds neither the clouds' frame_id nor the maps' bytes). The
// same scenario without security is the control that proves each check can fail.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "platform/clock.hpp"
#include "src/dds/topic_types.hpp"
#include "src/security/enclave_check.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

/// The lidar's frame_id: a string that appears in every cloud sent, looked for on the wire.
constexpr const char* kMarkerFrame = "lidar_wire_marker_5e7c1a";

/// A keystore for one domain with the enclaves of a small robot: raymapd, the lidar driver (its
/// clouds, odometry and transforms; it also reads the maps and diagnostics, as raymap-load does)
/// and a planner (reads maps and diagnostics only).
struct RobotKeystore {
  explicit RobotKeystore(std::uint32_t domain) : domain_id(domain) {
    security::KeystoreOptions options;
    options.domains = {domain, domain};
    created = static_cast<bool>(security::createKeystore(path(), options));
    security::EnclaveOptions enclave;
    enclave.domains = {domain, domain};
    const security::EnclaveGrant grants[] = {
        {"/raymap/raymapd",
         {"rt/height_map", "rt/diagnostics", "rt/raymap/occupied_voxels"},
         {"rt/points", "rt/odom", "rt/tf_static", "rt/height_map"}},
        {"/robot/driver",
         {"rt/points", "rt/odom", "rt/tf", "rt/tf_static"},
         {"rt/height_map", "rt/diagnostics"}},
        {"/robot/planner", {}, {"rt/height_map", "rt/diagnostics"}}};
    for (const security::EnclaveGrant& grant : grants) {
      created = created && static_cast<bool>(security::writePermissions(path(), grant, enclave));
    }
  }
  fs::path path() const { return dir.path() / "keystore"; }
  dds::SecurityFiles files(const char* enclave) const {
    security::SecurityConfig config;
    config.keystore = path().string();
    config.enclave = enclave;
    return security::enclaveFilesIn(security::enclaveFolder(config));
  }
  /// raymapd's `dds.security` section for this keystore.
  std::string section(const char* strategy = "Enforce") const {
    return "  security: {keystore: " + path().string() +
           ", enclave: /raymap/raymapd, strategy: " + strategy + "}\n";
  }

  TempDir dir;
  std::uint32_t domain_id = 0;
  bool created = false;
};

/// raymapd's configuration for these tests: the fixture's, with the marker frame and `security`
/// (a `dds.security` section, or "").
std::string securityTestConfig(std::uint32_t domain, const std::string& security) {
  return "map: {resolution: 0.1, window: [6, 6, 3]}\n"
         "backend: {name: cpu, threads: 2}\n"
         "pose: {source: odometry, topic: rt/odom, world_frame: odom, base_frame: base_link}\n"
         "sensors:\n"
         "  - {name: lidar, topic: rt/points, frame: " +
         std::string(kMarkerFrame) +
         ", min_range: 0.3, max_range: 20, max_points: 70000}\n"
         "heightmap: {rate_hz: 5, size: 12, base_height: 1.2}\n"
         "dds:\n  domain: " +
         std::to_string(domain) + "\n" + security;
}

/// The file's bytes ("" when it cannot be read).
std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

/// tcpdump capturing the UDP traffic of one DDS domain on the loopback interface (the ports
/// Cyclone maps the domain to: 7400 + 250 x domain and the 250 after) while it runs.
class LoopbackCapture {
 public:
  /// @return nullptr with `why` set when this machine cannot capture (no tcpdump, not root).
  static std::unique_ptr<LoopbackCapture> start(const TempDir& dir, std::uint32_t domain,
                                                std::string& why) {
    if (!fs::exists("/usr/bin/tcpdump")) {
      why = "tcpdump is not installed (tools/setup-debian.sh installs it)";
      return nullptr;
    }
    if (::geteuid() != 0) {
      why = "capturing packets needs root";
      return nullptr;
    }
    std::unique_ptr<LoopbackCapture> capture(new LoopbackCapture(dir, domain));
    const std::int64_t until = startWaitEndNs();
    while (platform::monotonicNowNs() < until && capture->process_->running()) {
      if (fileBytes(capture->log_).find("listening on") != std::string::npos) {
        return capture;
      }
      platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 20000000);
    }
    why = "tcpdump did not start: " + fileBytes(capture->log_);
    return nullptr;
  }
  /// @brief Stops the capture and returns the bytes captured.
  std::string finish() {
    process_->stop(SIGINT, kStopWait);
    return fileBytes(pcap_);
  }

 private:
  LoopbackCapture(const TempDir& dir, std::uint32_t domain)
      : pcap_(dir.file("lo.pcap")), log_(dir.file("tcpdump.log")) {
    const std::uint32_t first = 7400 + 250 * domain;
    // -U: each packet written at once (nothing is lost in tcpdump's buffer when it stops).
    // -Z root: tcpdump keeps the test's user, so that it dies with the test (DaemonProcess's
    // parent-death signal does not survive a change of user); -c: at most 100,000 packets
    // whatever happens (a run here sends a few thousand, about 80 MB).
    process_ = std::make_unique<DaemonProcess>(
        "/usr/bin/tcpdump",
        std::vector<std::string>{"-i", "lo", "-U", "-n", "-Z", "root", "-c", "100000", "-s", "0",
                                 "-w", pcap_, "udp", "portrange",
                                 std::to_string(first) + "-" + std::to_string(first + 249)},
        std::vector<std::string>{}, log_);
  }
  std::string pcap_, log_;
  std::unique_ptr<DaemonProcess> process_;
};

/// The first number named `key` in raymap-load's JSON report, its nested objects included (-1
/// when there is none). A report that is not JSON is a test failure.
double reportNumber(const std::string& report, const std::string& key) {
  const std::optional<Json> json = parseJson(report);
  const Json* value = json ? findFirst(*json, key) : nullptr;
  return value != nullptr && value->is_number() ? value->get<double>() : -1.0;
}

/// What one run of the scenario observed.
struct Observed {
  std::size_t planner_maps = 0;      ///< GridMaps the authorised side received
  double intruder_maps = -1;         ///< GridMaps the unauthenticated raymap-load received
  double intruder_diagnostics = -1;  ///< raymapd's clouds_received as the intruder read it
  std::string intruder_report;       ///< its report and standard error
  std::uint64_t lidar_scans = 0;     ///< clouds the authorised lidar published
  double clouds_received = -1;       ///< raymapd's count of clouds received
  double cloud_publishers = -1;      ///< writers of rt/points raymapd matched (the most seen)
  std::string security_level, security_message;
  bool captured = false;
  std::string capture_skipped;
  bool marker_on_wire = false;
  int map_windows = 0;               ///< 16-byte windows of the last map's first layer
  int map_windows_on_wire = 0;       ///< of those, found in the capture
  driver::ReceivedGridMap last_map;  ///< the authorised side's last GridMap
};

/// Whether two GridMaps are the same cell for cell in every layer but observed_count (which
/// counts the scans that went in): the same bits, NaN (unknown) included.
::testing::AssertionResult sameCells(const driver::ReceivedGridMap& a,
                                     const driver::ReceivedGridMap& b) {
  if (a.layers != b.layers || a.data.size() != b.data.size() || a.centre_x != b.centre_x ||
      a.centre_y != b.centre_y) {
    return ::testing::AssertionFailure() << "different layers or geometry";
  }
  for (std::size_t i = 0; i < a.layers.size(); ++i) {
    if (a.layers[i] == "observed_count") {
      continue;
    }
    if (a.data[i].size() != b.data[i].size() ||
        std::memcmp(a.data[i].data(), b.data[i].data(), a.data[i].size() * sizeof(float)) != 0) {
      std::size_t differ = 0;
      for (std::size_t c = 0; c < std::min(a.data[i].size(), b.data[i].size()); ++c) {
        if (std::memcmp(&a.data[i][c], &b.data[i][c], sizeof(float)) != 0) {
          ++differ;
        }
      }
      return ::testing::AssertionFailure() << "layer " << a.layers[i] << ": " << differ << " of "
                                           << a.data[i].size() << " cells differ";
    }
  }
  return ::testing::AssertionSuccess();
}

/// 16-byte windows of a received map's first layer (its serialized floats as on the wire).
std::vector<std::string> mapWindows(const driver::ReceivedGridMap& map) {
  std::vector<std::string> windows;
  if (map.data.empty() || map.data.front().size() < 64) {
    return windows;
  }
  const std::vector<float>& layer = map.data.front();
  const char* bytes = reinterpret_cast<const char*>(layer.data());
  // Windows of four cells with data, spread over the layer: NaN (unknown) cells and constant
  // runs are in many messages.
  for (std::size_t cell = 0; cell + 4 <= layer.size() && windows.size() < 8; ++cell) {
    bool data = true;
    for (std::size_t i = cell; i < cell + 4; ++i) {
      data = data && std::isfinite(layer[i]) && (i == cell || layer[i] != layer[cell]);
    }
    if (data) {
      windows.emplace_back(bytes + cell * sizeof(float), 16);
      cell += layer.size() / 8;
    }
  }
  return windows;
}

/// raymapd (with `security_section`, or none) fed by the authorised robot (this process: a lidar
/// whose clouds carry kMarkerFrame and a map subscriber, both with the /robot/driver enclave when
/// `secure`) while an intruder without credentials (raymap-load: its own clouds and odometry,
/// and a map subscriber) runs on the same domain. Cyclone DDS 0.10 checks topics against the
/// permissions of a process's first participant on a domain, so each identity has a process.
Observed runScenario(const RobotKeystore& keystore, bool secure,
                     const std::string& security_section, bool with_intruder = true) {
  Observed seen;
  const std::uint32_t domain = keystore.domain_id;
  TempDir work;
  std::unique_ptr<LoopbackCapture> capture =
      LoopbackCapture::start(work, domain, seen.capture_skipped);
  seen.captured = capture != nullptr;
  RunningDaemon daemon(securityTestConfig(domain, security_section), false);
  const dds::SecurityFiles driver_files =
      secure ? keystore.files("/robot/driver") : dds::SecurityFiles{};
  RosSide robot(domain, 70000, driver_files, driver_files);
  EXPECT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  EXPECT_TRUE(robot.waitForService(kStartWaitS)) << daemon.log();
  // Without the intruder, a process that lasts about as long bounds the run.
  DaemonProcess intruder(
      "/bin/sh",
      {"-c", with_intruder ? "exec '" + std::string(RAYMAP_LOAD_PATH) + "' --domain " +
                                 std::to_string(domain) +
                                 " --beams 16 --columns 512 --warmup 1 --duration 4 > '" +
                                 work.file("intruder.json") + "'"
                           : std::string("exec sleep 6")},
      {}, work.file("intruder.log"));
  driver::PlaybackOptions options;
  options.frame = kMarkerFrame;
  // One scan, repeated exactly: after a few the map saturates (log-odds clamped), so the last
  // map does not depend on how many scans went in, and runs can be compared cell for cell.
  options.distinct_scans = 1;
  std::vector<driver::ReceivedGridMap> maps;
  driver::LidarPlayback lidar(yardLidar(16, 512, false), *robot.publisher, options);
  const std::int64_t t0 = platform::monotonicNowNs();
  lidar.start(t0, platform::realtimeNowNs());
  const std::int64_t end = t0 + static_cast<std::int64_t>(60e9);  // the intruder's run bounds it
  for (std::int64_t now = t0; now < end && intruder.running(); now = platform::monotonicNowNs()) {
    const std::int64_t due = lidar.publishDue(now);
    robot.grid_maps->poll(0, maps);
    robot.diagnostics->poll();
    seen.cloud_publishers =
        std::max(seen.cloud_publishers,
                 robot.diagnostics->number("raymapd: sensor lidar/publishers").value_or(-1));
    platform::sleepUntilMonotonicNs(std::min(due, now + 2000000));
  }
  seen.lidar_scans = lidar.scansPublished();
  robot.settle(2.5, &maps);  // a report after the last cloud: its counts include them all
  seen.planner_maps = maps.size();
  if (!maps.empty()) {
    seen.last_map = maps.back();
  }
  const std::string intruder_json = fileBytes(work.file("intruder.json"));
  seen.intruder_report = intruder_json + fileBytes(work.file("intruder.log"));
  if (with_intruder) {
    seen.intruder_maps = reportNumber(intruder_json, "maps_received");
    // raymap-load copies raymapd's diagnostics into its report: -1 when it read none.
    seen.intruder_diagnostics = reportNumber(intruder_json, "clouds_received");
  }
  const auto& values = robot.diagnostics->values();
  const auto value = [&](const std::string& key) {
    const auto it = values.find(key);
    return it == values.end() ? std::string() : it->second;
  };
  seen.clouds_received = robot.diagnostics->number("raymapd: sensor lidar/received").value_or(-1);
  seen.security_level = value("raymapd: security/level");
  seen.security_message = value("raymapd: security/message");
  expectCleanStop(daemon);
  if (capture != nullptr) {
    const std::string wire = capture->finish();
    seen.marker_on_wire = wire.find(kMarkerFrame) != std::string::npos;
    if (!maps.empty()) {
      for (const std::string& window : mapWindows(maps.back())) {
        ++seen.map_windows;
        if (wire.find(window) != std::string::npos) {
          ++seen.map_windows_on_wire;
        }
      }
    }
  }
  return seen;
}

TEST(SecureRaymapd, OnlyAuthorisedEnclavesReadAndWriteAndNothingIsReadableOnTheWire) {
  const RobotKeystore keystore(uniqueDomain());
  ASSERT_TRUE(keystore.created);
  const Observed secure = runScenario(keystore, true, keystore.section());
  // The authorised side gets the maps at 5 Hz; the intruder neither maps nor diagnostics.
  EXPECT_GE(secure.planner_maps, fewestMaps(5.0));
  EXPECT_EQ(secure.intruder_maps, 0.0) << secure.intruder_report;
  EXPECT_EQ(secure.intruder_diagnostics, -1.0) << secure.intruder_report;
  // raymapd matched only the authorised lidar, and every cloud it received was the lidar's.
  EXPECT_EQ(secure.cloud_publishers, 1.0);
  EXPECT_GT(secure.clouds_received, 0.0);
  EXPECT_LE(secure.clouds_received, static_cast<double>(secure.lidar_scans));
  EXPECT_EQ(secure.security_level, "0") << secure.security_message;
  EXPECT_NE(secure.security_message.find("enclave /raymap/raymapd"), std::string::npos)
      << secure.security_message;
  if (secure.captured) {
    EXPECT_FALSE(secure.marker_on_wire);
    EXPECT_GT(secure.map_windows, 0);
    EXPECT_EQ(secure.map_windows_on_wire, 0);
  }

  // The map fed by the authorised lidar alone is, cell for cell, the map with the intruder there.
  const Observed alone = runScenario(keystore, true, keystore.section(), false);
  ASSERT_FALSE(alone.last_map.data.empty());
  ASSERT_FALSE(secure.last_map.data.empty());
  EXPECT_TRUE(sameCells(secure.last_map, alone.last_map));

  // The control: the same without security. The intruder reads raymapd's topics and its clouds
  // reach raymapd; the capture shows the frame and the map's bytes (so each check above can
  // fail). Its odometry is a second pose source: raymapd then withholds most maps (ERROR), so
  // what the intruder reads is counted by the diagnostics it got.
  const Observed open = runScenario(keystore, false, "");
  EXPECT_GE(open.intruder_diagnostics, 0.0) << open.intruder_report;
  EXPECT_EQ(open.cloud_publishers, 2.0);
  EXPECT_GT(open.clouds_received, static_cast<double>(open.lidar_scans));
  if (!open.captured) {
    GTEST_SKIP() << "the wire was not captured: " << open.capture_skipped;
  }
  EXPECT_TRUE(open.marker_on_wire);
  EXPECT_GT(open.map_windows_on_wire, 0);
}

TEST(SecureRaymapd, AnEnclaveWithoutThePermissionCannotPublishCloudsOrMaps) {
  const RobotKeystore keystore(uniqueDomain());
  ASSERT_TRUE(keystore.created);
  dds::DomainSettings planner;
  planner.security = keystore.files("/robot/planner");
  auto participant = dds::Participant::create(keystore.domain_id, planner);
  ASSERT_TRUE(participant) << participant.error().message;
  for (const char* topic : {"rt/points", "rt/height_map"}) {
    auto writer = dds::Writer::create(
        *participant, topic,
        std::string(topic) == "rt/points" ? dds::pointCloud2Type() : dds::gridMapType(),
        dds::Reliability::kReliable, 1);
    ASSERT_FALSE(writer) << topic;
    // rt/points: no grant at all (its topic is refused); rt/height_map: subscribe only.
    const std::string& message = writer.error().message;
    EXPECT_NE(message.find("robot/planner/permissions.p7s: the enclave's permissions do not "
                           "allow publishing"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("\"" + std::string(topic) + "\""), std::string::npos) << message;
  }
}

TEST(SecureRaymapd, AnUnauthenticatedMapWriterIsNotSeenByRaymapd) {
  const RobotKeystore keystore(uniqueDomain());
  ASSERT_TRUE(keystore.created);
  RunningDaemon daemon(securityTestConfig(keystore.domain_id, keystore.section()), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  // This process has no credentials: its map writer is another publisher of rt/height_map that
  // raymapd (which reports such a writer as an ERROR) never hears.
  auto open = dds::Participant::create(keystore.domain_id);
  ASSERT_TRUE(open);
  auto second_writer = dds::Writer::create(*open, "rt/height_map", dds::gridMapType(),
                                           dds::Reliability::kReliable, 1);
  ASSERT_TRUE(second_writer);
  const TempDir work;
  const std::string enclave = "ROS_SECURITY_ENCLAVE_OVERRIDE=/robot/driver";
  // Standard output alone: the JSON report (its warnings go to standard error).
  const RunResult load =
      runProgram({"/usr/bin/env", "ROS_SECURITY_ENABLE=true", "ROS_SECURITY_STRATEGY=Enforce",
                  "ROS_SECURITY_KEYSTORE=" + keystore.path().string(), enclave, RAYMAP_LOAD_PATH,
                  "--domain", std::to_string(keystore.domain_id), "--beams", "16", "--columns",
                  "512", "--warmup", "1", "--duration", "3", "--frame", kMarkerFrame});
  EXPECT_EQ(load.exit_code, 0) << describe(load);
  EXPECT_GE(reportNumber(load.out, "maps_received"), static_cast<double>(fewestMaps(3.0)))
      << describe(load);
  EXPECT_EQ(second_writer->matchedReaders(), 0u);
  expectCleanStop(daemon);
  EXPECT_EQ(daemon.log().find("other publisher"), std::string::npos) << daemon.log();
}

/// `raymapd --check-config` on the security section: each unusable keystore is refused with
/// the file and the reason, as the service itself refuses to start.
class SecurityStartChecks : public ::testing::Test {
 protected:
  SecurityStartChecks() : keystore(uniqueDomain()) {}
  std::pair<int, std::string> check(const std::string& security_section) {
    const std::string config = dir.file("raymapd.yaml");
    std::ofstream(config) << securityTestConfig(keystore.domain_id, security_section);
    return runToCompletion(RAYMAPD_PATH, {"--check-config", config});
  }
  fs::path enclaveFile(const char* name) const {
    return keystore.path() / "enclaves/raymap/raymapd" / name;
  }
  RobotKeystore keystore;
  TempDir dir;
};

TEST_F(SecurityStartChecks, AGoodKeystorePassesAndIsSummarised) {
  ASSERT_TRUE(keystore.created);
  const auto [status, output] = check(keystore.section());
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("DDS Security: enclave /raymap/raymapd (subject CN=/raymap/raymapd"),
            std::string::npos)
      << output;
}

TEST_F(SecurityStartChecks, AMissingFileIsRefusedByName) {
  fs::remove(enclaveFile("cert.pem"));
  const auto [status, output] = check(keystore.section());
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("raymapd/cert.pem: cannot read the enclave's identity certificate"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("dds.security (Enforce)"), std::string::npos) << output;
}

TEST_F(SecurityStartChecks, AnExpiredIdentityIsRefusedWithItsDate) {
  security::EnclaveOptions expired;
  expired.domains = {keystore.domain_id, keystore.domain_id};
  const auto now = std::chrono::system_clock::now();
  expired.validity = {now - std::chrono::hours(48), now - std::chrono::hours(1)};
  fs::remove(enclaveFile("cert.pem"));  // a new identity, made expired
  fs::remove(enclaveFile("key.pem"));
  ASSERT_TRUE(security::createEnclave(keystore.path(), "/raymap/raymapd", expired));
  const auto [status, output] = check(keystore.section());
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("raymapd/cert.pem: the identity certificate expired on"), std::string::npos)
      << output;
}

TEST_F(SecurityStartChecks, AnIdentityOfAnotherCaIsRefused) {
  TempDir other_dir;
  security::KeystoreOptions options;
  options.domains = {keystore.domain_id, keystore.domain_id};
  ASSERT_TRUE(security::createKeystore(other_dir.path() / "k", options));
  ASSERT_TRUE(security::createEnclave(other_dir.path() / "k", "/raymap/raymapd",
                                      {options.domains, security::validityForDays(30)}));
  for (const char* name : {"cert.pem", "key.pem"}) {
    fs::remove(enclaveFile(name));
    fs::copy_file(other_dir.path() / "k/enclaves/raymap/raymapd" / name, enclaveFile(name));
  }
  const auto [status, output] = check(keystore.section());
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("is not signed by the identity CA"), std::string::npos) << output;
}

TEST_F(SecurityStartChecks, PermissionsNotCoveringTheConfiguredTopicsAreRefused) {
  security::EnclaveOptions options;
  options.domains = {keystore.domain_id, keystore.domain_id};
  // Allowed to publish the map, not the diagnostics; not to read the clouds.
  ASSERT_TRUE(security::writePermissions(
      keystore.path(),
      {"/raymap/raymapd", {"rt/height_map"}, {"rt/odom", "rt/tf_static", "rt/height_map"}},
      options));
  const auto [status, output] = check(keystore.section());
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(
      output.find("raymapd/permissions.p7s: the permissions of CN=/raymap/raymapd on domain " +
                  std::to_string(keystore.domain_id) +
                  " do not allow: subscribe rt/points, publish rt/diagnostics"),
      std::string::npos)
      << output;
}

TEST_F(SecurityStartChecks, TheServiceRefusesToStartAsTheCheckDoes) {
  ASSERT_TRUE(keystore.created);
  fs::remove(enclaveFile("permissions.p7s"));
  const std::string config = dir.file("raymapd.yaml");
  std::ofstream(config) << securityTestConfig(keystore.domain_id, keystore.section());
  const auto [status, output] = runToCompletion(RAYMAPD_PATH, {"--config", config});
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("raymapd/permissions.p7s: cannot read the enclave's permissions"),
            std::string::npos)
      << output;
}

TEST_F(SecurityStartChecks, SystemdCredentialsServeAsTheEnclavesFolder) {
  ASSERT_TRUE(keystore.created);
  // What LoadCredential= makes: the six files (copies, not links) in a folder of their own.
  const fs::path credentials = dir.path() / "credentials";
  fs::create_directory(credentials);
  for (const char* name : {"cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem",
                           "governance.p7s", "permissions.p7s"}) {
    fs::copy_file(fs::canonical(enclaveFile(name)), credentials / name);
  }
  const std::string config = dir.file("raymapd.yaml");
  std::ofstream(config) << securityTestConfig(keystore.domain_id,
                                              "  security:\n"
                                              "    enclave_dir: ${CREDENTIALS_DIRECTORY}\n");
  const auto [status, output] = runToCompletion(
      "/usr/bin/env",
      {"CREDENTIALS_DIRECTORY=" + credentials.string(), RAYMAPD_PATH, "--check-config", config});
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("DDS Security: enclave files in " + credentials.string()),
            std::string::npos)
      << output;
  const auto [unset_status, unset_output] = runToCompletion(
      "/usr/bin/env", {"-u", "CREDENTIALS_DIRECTORY", RAYMAPD_PATH, "--check-config", config});
  EXPECT_EQ(unset_status, 2) << unset_output;
  EXPECT_NE(unset_output.find("dds.security.enclave_dir: CREDENTIALS_DIRECTORY is not set"),
            std::string::npos)
      << unset_output;
}

TEST_F(SecurityStartChecks, PermissiveWithoutKeysStartsAndWarns) {
  const std::string section =
      "  security: {keystore: " + (dir.path() / "none").string() + ", strategy: Permissive}\n";
  const auto [status, output] = check(section);
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("warning: running WITHOUT DDS Security"), std::string::npos) << output;

  // The service itself: running, its security status WARN, its systemd status says so.
  RunningDaemon daemon(securityTestConfig(keystore.domain_id, section), false);
  RosSide ros(keystore.domain_id, 70000);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  EXPECT_TRUE(ros.settleUntil(kStartWaitS, [&] {
    return ros.diagnostics->values().count("raymapd: security/level") != 0;
  }));
  const auto& values = ros.diagnostics->values();
  ASSERT_EQ(values.count("raymapd: security/level"), 1u);
  EXPECT_EQ(values.at("raymapd: security/level"), "1");
  EXPECT_NE(values.at("raymapd: security/message").find("running WITHOUT DDS Security"),
            std::string::npos);
  EXPECT_TRUE(daemon.notify.waitFor("security OFF (Permissive)", kStartWait, false).has_value());
  EXPECT_NE(
      daemon.logOnceItHas("running WITHOUT DDS Security").find("running WITHOUT DDS Security"),
      std::string::npos);
  expectCleanStop(daemon);
}

}  // namespace
}  // namespace raymap::test
