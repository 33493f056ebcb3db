// SPDX-License-Identifier: BSD-3-Clause
// `raymap replay`: recorded data published over DDS as the sensors and localisation of a live
// robot would (docs/cli.md).
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "platform/clock.hpp"
#include "src/bag/bag_reader.hpp"
#include "src/dds/topic_types.hpp"
#include "src/io/staged_outputs.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/replay/replay_session.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/dds_cli.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/option_names.hpp"

namespace raymap::cli {
namespace {

using replay::ReplayOptions;
using replay::ReplayProgress;
using replay::ReplaySession;
using replay::ReplayStats;

struct ReplayFlags {
  std::vector<std::string> inputs;
  std::string rate = "1";
  bool loop = false;
  double start = 0.0;
  double duration = 0.0;
  int domain = -1;  // -1: $ROS_DOMAIN_ID, else 0
  std::string trajectory;
  std::string sensor_offset = "0,0,0";
  double scan_period = io::RaySourceOptions::kDefaultScanPeriod;
  std::string cloud_topic = "/points";
  std::string odometry_topic = "/odom";
  std::string pose = "odometry";
  bool no_tf_static = false;
  std::string frame = "lidar";
  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  double pose_rate = 100.0;
  double wait = 10.0;
  std::string diagnostics_topic = "/diagnostics";
  unsigned max_ahead = 2;
  bool skip_damaged = false;
  bool include_outputs = false;
  std::string stats_json;
  bool quiet = false;
};

Result<ReplayOptions> toOptions(const ReplayFlags& f) {
  ReplayOptions o;
  o.inputs = f.inputs;
  if (f.rate == "max") {
    o.rate = 0.0;
  } else {
    try {
      std::size_t used = 0;
      o.rate = std::stod(f.rate, &used);
      if (used != f.rate.size() || !(o.rate > 0.0)) {
        throw std::invalid_argument(f.rate);
      }
    } catch (const std::exception&) {
      return fail(ErrorCode::kInvalidArgument,
                  "--rate: '" + f.rate + "' is not a positive number or 'max'");
    }
  }
  if (f.start < 0.0 || f.duration < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "--start and --duration must not be negative");
  }
  if (!(f.pose_rate > 0.0) || f.pose_rate > 10000.0) {
    return fail(ErrorCode::kInvalidArgument, "--pose-rate: must be in (0, 10000] Hz");
  }
  o.loop = f.loop;
  o.start_s = f.start;
  o.duration_s = f.duration;
  auto domain = domainFromOptionOrEnvironment(f.domain);
  if (!domain) {
    return Unexpected(std::move(domain).error());
  }
  o.domain = domain.value();
  o.source.trajectory_path = f.trajectory;
  o.source.scan_period_s = f.scan_period;
  auto offset = parseVector(f.sensor_offset, "--sensor-offset");
  if (!offset) {
    return Unexpected(offset.error());
  }
  o.source.sensor_offset = *offset;
  o.cloud_topic = msgs::ddsTopicName(f.cloud_topic);
  o.odometry_topic = msgs::ddsTopicName(f.odometry_topic);
  o.diagnostics_topic = msgs::ddsTopicName(f.diagnostics_topic);
  o.pose_odometry = f.pose == "odometry" || f.pose == "both";
  o.pose_tf = f.pose == "tf" || f.pose == "both";
  o.tf_static = !f.no_tf_static;
  o.frame = f.frame;
  o.world_frame = f.world_frame;
  o.base_frame = f.base_frame;
  o.pose_period_s = 1.0 / f.pose_rate;
  o.wait_s = f.wait;
  o.max_ahead = f.max_ahead;
  o.skip_damaged = f.skip_damaged;
  o.include_outputs = f.include_outputs;
  return o;
}

/// The progress line on stderr: rewritten in place every 0.5 s on a terminal, a line every 10 s
/// into a file or pipe (a log stays readable), and the summary at the end.
class ProgressLine {
 public:
  void operator()(const ReplayProgress& p) {
    const std::int64_t now = platform::monotonicNowNs();
    const std::int64_t every = terminal_ ? 500'000'000 : 10'000'000'000;
    if (!p.finished && now - last_ns_ < every) {
      return;
    }
    last_ns_ = now;
    const ReplayStats& s = p.stats;
    if (p.finished) {
      std::fprintf(stderr,
                   "%sraymap replay: finished %" PRIu64 " pass%s: %" PRIu64
                   " clouds, %.1f M points, %" PRIu64 " poses, %" PRIu64
                   " log messages; %.1f s of data in %.1f s, late max %.0f ms\n",
                   terminal_ ? "\r" : "", s.passes, s.passes == 1 ? "" : "es", s.scans,
                   static_cast<double>(s.points) * 1e-6, s.poses, s.messages, s.data_seconds,
                   p.elapsed_s, p.max_late_ms);
    } else {
      const std::string input(p.input);
      std::fprintf(stderr,
                   "%sraymap replay: %s %3.0f%% | pass %" PRIu64 " | %" PRIu64
                   " clouds, %.1f M points, %" PRIu64 " poses, %" PRIu64
                   " log messages | %.1f s of data in %.1f s | late max %.0f ms%s",
                   terminal_ ? "\r" : "", input.c_str(), 100.0 * p.input_fraction, s.passes + 1,
                   s.scans, static_cast<double>(s.points) * 1e-6, s.poses, s.messages,
                   s.data_seconds, p.elapsed_s, p.max_late_ms, terminal_ ? "   " : "\n");
    }
    std::fflush(stderr);
  }

 private:
  bool terminal_ = ::isatty(STDERR_FILENO) != 0;
  std::int64_t last_ns_ = 0;
};

/// The library's warnings name its options by key (replay.rate); the user typed flags.
std::vector<std::string> warningsWithFlags(const std::vector<std::string>& warnings) {
  std::vector<std::string> shown;
  shown.reserve(warnings.size());
  for (const std::string& warning : warnings) {
    shown.push_back(withCliFlags(warning));
  }
  return shown;
}

Json statsJson(const ReplayStats& s) {
  return {
      {"passes", s.passes},
      {"clouds", s.scans},
      {"points", s.points},
      {"poses", s.poses},
      {"log_messages", s.messages},
      {"log_messages_undecodable", s.undecodable},
      {"logs_truncated", s.truncated_logs},
      {"origin_conflicts", s.origin_conflicts},
      {"feedback_timeouts", s.feedback_timeouts},
      {"data_seconds", s.data_seconds},
      {"wall_seconds", s.wall_seconds},
      {"max_late_ms", s.max_late_ms},
      {"stamp_zero_ns", s.stamp_zero_ns},
      {"warnings", warningsWithFlags(s.warnings)},
  };
}

int runReplay(const ReplayFlags& flags) {
  auto options = toOptions(flags);
  if (!options) {
    printError("replay", options.error().message);
    return kExitUsage;
  }
  if (!flags.quiet) {
    options->on_progress = ProgressLine();
    options->on_waiting = [wait_s = options->wait_s](const std::string& topic) {
      std::fprintf(stderr, "raymap replay: waiting up to %.0f s for a subscriber of %s\n", wait_s,
                   topic.c_str());
    };
  }
  io::StagedOutputs staged("replay");
  for (const std::string& input : flags.inputs) {
    staged.input(input, "the input");
  }
  staged.input(flags.trajectory, "--trajectory");
  std::string stats_temp;
  if (!flags.stats_json.empty() && flags.stats_json != "-") {
    auto temp = staged.add(flags.stats_json, "--stats-json");
    if (!temp) {
      printError("replay", temp.error().message);
      return exitCodeFor(temp.error());
    }
    stats_temp = std::move(*temp);
  }
  // Before the participant starts Cyclone's threads, so they inherit the blocked mask and
  // Ctrl-C / SIGTERM reach the replay loop (which then stops cleanly) and nothing else.
  const platform::ShutdownSignals signals = platform::ShutdownSignals::install();
  auto session = ReplaySession::create(*options, signals);
  if (!session) {
    printError("replay", session.error().message);
    return kExitFailure;
  }
  auto stats = session.value()->run();
  if (!stats) {
    const bool reads_bags = std::any_of(flags.inputs.begin(), flags.inputs.end(),
                                        [](const std::string& in) { return bag::isBag(in); });
    printError("replay", stats.error().message + bagDamageHint(reads_bags, stats.error()));
    return kExitFailure;
  }
  for (const std::string& warning : warningsWithFlags(stats.value().warnings)) {
    std::fprintf(stderr, "raymap replay: warning: %s\n", warning.c_str());
  }
  if (!flags.stats_json.empty()) {
    const std::string json = dumpJson(statsJson(stats.value()));
    if (flags.stats_json == "-") {
      std::printf("%s\n", json.c_str());
    } else if (auto written = writeTextFile(stats_temp, json); !written) {
      printError("replay", "--stats-json: " + written.error().message);
      return kExitFailure;
    } else if (auto committed = staged.commit(); !committed) {
      printError("replay", committed.error().message);
      return kExitFailure;
    }
  }
  return kExitOk;
}

}  // namespace

void addReplayCommand(CLI::App& app, int* exit_code) {
  auto f = std::make_shared<ReplayFlags>();
  CLI::App* c = app.add_subcommand(
      "replay", "Publish recorded data over DDS as a lidar driver and localisation would");
  c->add_option("inputs", f->inputs,
                "Ray-cloud PLY, point-cloud PLY (with --trajectory), raymap record logs or "
                "rosbag2 bags (directory, .mcap, .db3), played one after another")
      ->required()
      ->check(CLI::ExistingPath);
  c->add_option("--rate", f->rate,
                "Data seconds per second (2 = twice as fast), or 'max': as fast as raymapd "
                "keeps up (paced by its diagnostics)")
      ->capture_default_str();
  c->add_flag("--loop", f->loop, "Start over after the last input, until interrupted");
  c->add_option("--start", f->start, "Skip this many seconds of each input")->capture_default_str();
  c->add_option("--duration", f->duration, "Play this many seconds of each input (0 = all)")
      ->capture_default_str();
  c->add_option("--domain", f->domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, kMaxDomainId));
  c->add_option("--trajectory", f->trajectory,
                "Point clouds: sensor trajectory, lines 'time x y z [qw qx qy qz]'");
  c->add_option("--sensor-offset", f->sensor_offset,
                "Sensor position in the trajectory's body frame, metres: x,y,z")
      ->capture_default_str();
  c->add_option("--scan-period", f->scan_period,
                "Without a 'scan' property: seconds per scan (<= 0: one scan)")
      ->capture_default_str();
  c->add_option("--cloud-topic", f->cloud_topic, "PointCloud2 topic (ROS or DDS name)")
      ->capture_default_str();
  c->add_option("--odom-topic", f->odometry_topic, "nav_msgs/Odometry topic")
      ->capture_default_str();
  c->add_option("--pose", f->pose, "odometry, tf (world -> base on /tf) or both")
      ->check(CLI::IsMember({"odometry", "tf", "both"}))
      ->capture_default_str();
  c->add_flag("--no-tf-static", f->no_tf_static,
              "Do not latch the identity base -> sensor transform on /tf_static");
  c->add_option("--frame", f->frame, "frame_id of the clouds (the sensor frame)")
      ->capture_default_str();
  c->add_option("--world-frame", f->world_frame, "Parent frame of the pose")->capture_default_str();
  c->add_option("--base-frame", f->base_frame, "Child frame of the pose")->capture_default_str();
  c->add_option("--pose-rate", f->pose_rate, "Pose samples per second of data (Hz)")
      ->capture_default_str();
  c->add_option("--wait", f->wait,
                "Seconds to wait for a subscriber before publishing (data sent before a "
                "subscriber matches is lost)")
      ->capture_default_str();
  c->add_option("--diagnostics-topic", f->diagnostics_topic,
                "--rate max: where raymapd reports its progress")
      ->capture_default_str();
  c->add_option("--max-ahead", f->max_ahead,
                "--rate max: clouds published but not yet processed by raymapd")
      ->check(CLI::Range(1u, 64u))
      ->capture_default_str();
  c->add_flag("--skip-damaged", f->skip_damaged,
              "Bags: play what a damaged or cut-off bag holds (skipping to its next indexed "
              "chunk) instead of failing, and say what was skipped");
  c->add_flag("--include-outputs", f->include_outputs,
              "Logs and bags: also publish their diagnostic_msgs and grid_map_msgs topics (a "
              "mapping service's outputs; left out by default, beside a live service)");
  c->add_option("--stats-json", f->stats_json, "Write what was published as JSON ('-' = stdout)");
  c->add_flag("-q,--quiet", f->quiet, "No progress line");
  c->callback([f, exit_code] { *exit_code = runReplay(*f); });
}

}  // namespace raymap::cli
