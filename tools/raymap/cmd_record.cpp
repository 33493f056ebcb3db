// SPDX-License-Identifier: BSD-3-Clause
// `raymap record`: the raw CDR of DDS topics written to a raymap record log (docs/cli.md,
// docs/record-format.md), for replay bit for bit, or to a rosbag2 bag (MCAP) for ROS tools. The
// recorder is src/replay's TopicRecorder; this file parses, prints and maps the exit status.
#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include "platform/signals.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/replay/topic_recorder.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/dds_cli.hpp"

namespace raymap::cli {
namespace {

struct RecordFlags {
  std::string output;
  std::string format = "rmlog";      ///< rmlog (bit-exact raw capture) or mcap (a rosbag2 bag)
  std::string compression = "none";  ///< mcap: per-chunk compression
  std::vector<std::string> topics = {"/points", "/odom", "/tf", "/tf_static"};
  int domain = -1;  // -1: $ROS_DOMAIN_ID, else 0
  double duration = 0.0;
  bool quiet = false;
};

/// The recorder's lines on stderr: what it records, warnings, and on a terminal a progress line
/// rewritten every second.
void addPrinters(replay::RecordOptions& options, bool quiet) {
  options.on_warning = [](const std::string& warning) {
    std::fprintf(stderr, "raymap record: warning: %s\n", warning.c_str());
  };
  if (quiet) {
    return;
  }
  options.on_notice = [](const std::string& line) {
    std::fprintf(stderr, "raymap record: %s\n", line.c_str());
  };
  if (::isatty(STDERR_FILENO) != 0) {
    options.on_progress = [next_s = 1.0](double seconds, std::uint64_t messages,
                                         std::uint64_t bytes) mutable {
      if (seconds >= next_s) {
        std::fprintf(stderr, "\rraymap record: %.0f s, %" PRIu64 " messages, %.1f MB   ", seconds,
                     messages, static_cast<double>(bytes) * 1e-6);
        std::fflush(stderr);
        next_s = seconds + 1.0;
      }
    };
  }
}

void printSummary(const std::string& output, const replay::RecordStats& stats) {
  if (::isatty(STDERR_FILENO) != 0) {
    std::fprintf(stderr, "\r%80s\r", "");
  }
  std::fprintf(stderr, "raymap record: wrote %s: %" PRIu64 " messages, %.1f MB\n", output.c_str(),
               stats.messages, static_cast<double>(stats.bytes) * 1e-6);
  for (const replay::RecordedTopicStats& topic : stats.topics) {
    if (!topic.seen) {
      std::fprintf(stderr, "  %-28s no publisher of a known type seen\n", topic.topic.c_str());
    } else {
      std::fprintf(stderr, "  %-28s %8" PRIu64 " messages  %10.1f MB\n", topic.topic.c_str(),
                   topic.messages, static_cast<double>(topic.bytes) * 1e-6);
    }
  }
}

int runRecord(const RecordFlags& flags, platform::ShutdownSignals signals) {
  auto domain = domainFromOptionOrEnvironment(flags.domain);
  if (!domain) {
    printError("record", domain.error().message);
    return kExitUsage;
  }
  replay::RecordOptions options;
  options.output = flags.output;
  options.format =
      flags.format == "mcap" ? replay::RecordFormat::kMcapBag : replay::RecordFormat::kRecordLog;
  options.compression = flags.compression;
  for (const std::string& topic : flags.topics) {
    options.topics.push_back(msgs::ddsTopicName(topic));
  }
  options.domain = domain.value();
  options.duration_s = flags.duration;
  addPrinters(options, flags.quiet);
  auto recorder = replay::TopicRecorder::create(options);
  if (!recorder) {
    printError("record", recorder.error().message);
    return kExitFailure;
  }
  if (!flags.quiet) {
    std::fprintf(stderr, "raymap record: writing %s (renamed to %s when stopped)\n",
                 recorder.value()->partialPath().c_str(), flags.output.c_str());
  }
  auto stats = recorder.value()->run(signals);
  if (!stats) {
    printError("record", stats.error().message);
    return kExitFailure;  // the .partial file stays: it holds what was recorded
  }
  if (!flags.quiet) {
    printSummary(flags.output, stats.value());
  }
  return kExitOk;
}

}  // namespace

void addRecordCommand(CLI::App& app, int* exit_code) {
  auto f = std::make_shared<RecordFlags>();
  CLI::App* c = app.add_subcommand(
      "record", "Record DDS topics (raw CDR) into a log that raymap replay plays back");
  c->add_option("-o,--output", f->output,
                "Log file to write (.rmlog), or with --format mcap the rosbag2 directory")
      ->required();
  c->add_option("--format", f->format,
                "rmlog (raymap's log, bit-exact replay) or mcap (a rosbag2 bag for ROS tools)")
      ->check(CLI::IsMember({"rmlog", "mcap"}))
      ->capture_default_str();
  c->add_option("--compression", f->compression, "--format mcap: chunk compression none|zstd|lz4")
      ->capture_default_str();
  c->add_option("-t,--topic", f->topics,
                "Topic to record (ROS or DDS name; repeat the option). Default: /points /odom "
                "/tf /tf_static")
      ->capture_default_str();
  c->add_option("--domain", f->domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, kMaxDomainId));
  c->add_option("--duration", f->duration, "Stop after this many seconds (0 = at Ctrl-C)")
      ->capture_default_str();
  c->add_flag("-q,--quiet", f->quiet, "Print only errors and warnings");
  c->callback([f, exit_code] {
    // Before the participant starts Cyclone's threads: SIGINT/SIGTERM reach the loop, which
    // then closes the log cleanly.
    *exit_code = runRecord(*f, platform::ShutdownSignals::install());
  });
}

}  // namespace raymap::cli
