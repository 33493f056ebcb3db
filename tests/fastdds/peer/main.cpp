// SPDX-License-Identifier: BSD-3-Clause
// raymap-fastdds-peer: raymapd's ROS 2 neighbours as Fast DDS 2.9 nodes would be (rmw_fastrtps's
// configuration, the stock socket buffers), on loopback (or, with --discovery stock, in a
// network namespace with multicast): `publish` is a lidar driver with
// odometry and /tf_static, `subscribe` a planner taking GridMaps and costmaps and a monitor
// taking diagnostics. Prints one JSON object of what it did (tests/fastdds, docs/fastdds-peer.md).
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>

#include "tests/fastdds/peer/json_result.hpp"
#include "tests/fastdds/peer/peer_participant.hpp"
#include "tests/fastdds/peer/publish_mode.hpp"
#include "tests/fastdds/peer/stop_signal.hpp"
#include "tests/fastdds/peer/subscribe_mode.hpp"

namespace {

using raymap::fastdds_peer::Json;

/// Fast DDS logs to standard output by default, where the JSON goes: send its warnings and
/// errors to standard error instead.
void logToStandardError() {
  using eprosima::fastdds::dds::Log;
  Log::ClearConsumers();
  Log::RegisterConsumer(std::make_unique<eprosima::fastdds::dds::StdoutErrConsumer>());
  Log::SetVerbosity(Log::Warning);
}

std::uint32_t domainFromEnvironment() {
  const char* text =
      std::getenv("ROS_DOMAIN_ID");  // NOLINT(concurrency-mt-unsafe): start-up, one thread
  return text == nullptr ? 0U : static_cast<std::uint32_t>(std::strtoul(text, nullptr, 10));
}

/// The JSON on standard output, and into `path` too when one is given.
bool emit(const Json& result, const std::string& path) {
  // One line; bytes from the wire that are not UTF-8 become U+FFFD rather than an exception.
  const std::string line = result.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
  std::fputs(line.c_str(), stdout);
  std::fflush(stdout);
  if (path.empty()) {
    return true;
  }
  std::ofstream file(path);
  file << line;
  return static_cast<bool>(file);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace raymap::fastdds_peer;
  CLI::App app{"raymap-fastdds-peer: raymapd's ROS 2 neighbours as Fast DDS 2.9 nodes"};
  app.require_subcommand(1);
  std::uint32_t domain = domainFromEnvironment();
  std::uint32_t buffer_bytes = 0;
  std::string output;
  app.add_option("--domain", domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, 232));
  app.add_option("--buffer-bytes", buffer_bytes,
                 "UDP send and receive buffer sizes (0: the OS default, as rmw_fastrtps leaves "
                 "them; for comparison runs)");
  app.add_option("--output", output, "also write the JSON to this file");
  std::string enclave_dir;
  app.add_option("--enclave-dir", enclave_dir,
                 "DDS Security with this SROS2 enclave folder's files (as rmw_fastrtps with "
                 "ROS_SECURITY_ENABLE=true); default: none");
  Discovery discovery = Discovery::kLoopback;
  app.add_option("--discovery", discovery,
                 "loopback: unicast on 127.0.0.1 only (default); stock: Fast DDS's own transports "
                 "and multicast discovery, only inside a network namespace of the test's own")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, Discovery>{{"loopback", Discovery::kLoopback},
                                           {"stock", Discovery::kStock}},
          CLI::ignore_case));

  PublishOptions publish;
  CLI::App* publish_command =
      app.add_subcommand("publish", "a lidar driver: /tf_static, odometry and PointCloud2");
  publish_command->add_option("--seconds", publish.seconds, "how long to publish");
  publish_command->add_option("--scan-rate", publish.scan_rate_hz, "scans per second")
      ->check(CLI::PositiveNumber);
  publish_command->add_option("--odometry-rate", publish.odometry_rate_hz, "odometry per second")
      ->check(CLI::PositiveNumber);
  publish_command->add_option("--speed", publish.speed_mps, "the robot's speed along x, m/s");
  publish_command->add_flag(
      "--clouds-after-tf-static", publish.clouds_after_tf_static,
      "start the lidar once the readers of /tf_static have acknowledged the transform (as on a "
      "robot whose /tf_static was latched before the lidar driver started)");
  publish_command
      ->add_option("--readers", publish.readers,
                   "with --clouds-after-tf-static: wait for this many readers of "
                   "/tf_static and of the clouds")
      ->check(CLI::Range(1, 100));
  publish_command
      ->add_option("--odometry-tail-s", publish.odometry_tail_s,
                   "go on publishing odometry this long after the last cloud")
      ->check(CLI::NonNegativeNumber);
  publish_command->add_option("--beams", publish.lidar.beams)->check(CLI::Range(1, 1024));
  publish_command->add_option("--columns", publish.lidar.columns)->check(CLI::Range(1, 8192));
  publish_command->add_option("--points-topic", publish.points_topic);
  publish_command->add_option("--odom-topic", publish.odom_topic);

  SubscribeOptions subscribe;
  CLI::App* subscribe_command =
      app.add_subcommand("subscribe", "GridMaps, costmaps and diagnostics from raymapd");
  subscribe_command->add_option("--seconds", subscribe.seconds, "how long to subscribe");
  subscribe_command->add_option(
      "--until", subscribe.until,
      "end once this many GridMaps, costmaps and diagnostic arrays (after the first GridMap) "
      "each arrived (0: never)");
  subscribe_command->add_option("--min-maps", subscribe.min_maps,
                                "with --until: end only once this many GridMaps arrived too");
  subscribe_command->add_flag("--from-match", subscribe.from_match,
                              "count --seconds from when raymapd's GridMap writer matched");
  subscribe_command->add_option("--grid-topic", subscribe.grid_topic);
  subscribe_command->add_option("--costmap-topic", subscribe.costmap_topic);
  subscribe_command->add_option("--diagnostics-topic", subscribe.diagnostics_topic);
  CLI11_PARSE(app, argc, argv);

  logToStandardError();
  installStopHandlers();
  std::string error;
  auto participant = PeerParticipant::create(domain, discovery, buffer_bytes, enclave_dir, error);
  if (!participant) {
    std::fprintf(stderr, "raymap-fastdds-peer: %s\n", error.c_str());
    return 1;
  }
  const bool publishing = publish_command->parsed();
  Json result = {
      {"mode", publishing ? "publish" : "subscribe"},
      {"domain", domain},
      {"buffer_bytes", buffer_bytes},
      {"discovery", discovery == Discovery::kLoopback ? "loopback" : "stock"},
  };
  const bool ran = publishing ? runPublish(*participant, publish, result)
                              : runSubscribe(*participant, subscribe, result);
  participant.reset();
  if (!emit(result, output)) {
    std::fprintf(stderr, "raymap-fastdds-peer: cannot write %s\n", output.c_str());
    return 1;
  }
  return ran ? 0 : 1;
}
