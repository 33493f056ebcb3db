// SPDX-License-Identifier: BSD-3-Clause
// `raymap record`: the raw CDR of DDS topics written to a raymap record log (docs/cli.md,
// docs/record-format.md), for replay bit for bit, or to a rosbag2 bag (MCAP) for ROS tools.
#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include <unistd.h>

#include "platform/clock.hpp"
#include "platform/signals.hpp"
#include "src/bag/rosbag_writer.hpp"
#include "src/dds/discovery.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/record/record_log_writer.hpp"
#include "src/security/secure_participant.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/dds_cli.hpp"

namespace raymap::cli {
namespace {

constexpr std::int32_t kRecordReaderDepth = 256;  // ~25 s of 10 Hz clouds if the disk stalls
constexpr int kTakeBatch = 32;
constexpr double kDiscoveryPeriod_s = 0.1;

struct RecordFlags {
  std::string output;
  std::string format = "rmlog";      ///< rmlog (bit-exact raw capture) or mcap (a rosbag2 bag)
  std::string compression = "none";  ///< mcap: per-chunk compression
  std::vector<std::string> topics = {"/points", "/odom", "/tf", "/tf_static"};
  int domain = -1;  // -1: $ROS_DOMAIN_ID, else 0
  double duration = 0.0;
  bool quiet = false;
};

/// A topic being recorded: its reader and its id in the log.
struct RecordedTopic {
  std::string type;
  std::optional<dds::RawReader> reader;
  std::uint32_t log_id = 0;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
};

/// Where the recording goes: raymap's own log, or a rosbag2 bag (MCAP).
class RecordSink {
 public:
  virtual ~RecordSink() = default;
  virtual Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                         bool reliable, bool latched) = 0;
  virtual Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns,
                             std::int64_t receive_monotonic_ns, std::int64_t source_unix_ns,
                             std::span<const std::byte> cdr) = 0;
  virtual Result<void> close() = 0;
  virtual const std::string& partialPath() const noexcept = 0;
  virtual std::uint64_t messages() const noexcept = 0;
  virtual std::uint64_t bytes() const noexcept = 0;
};

class RecordLogSink final : public RecordSink {
 public:
  explicit RecordLogSink(std::unique_ptr<record::RecordLogWriter> log) : log_(std::move(log)) {}
  Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                 bool reliable, bool latched) override {
    return log_->addTopic(
        dds_topic, type,
        reliable ? record::LogReliability::kReliable : record::LogReliability::kBestEffort,
        latched ? record::LogDurability::kTransientLocal : record::LogDurability::kVolatile);
  }
  Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns,
                     std::int64_t receive_monotonic_ns, std::int64_t source_unix_ns,
                     std::span<const std::byte> cdr) override {
    return log_->write(id, receive_unix_ns, receive_monotonic_ns, source_unix_ns, cdr);
  }
  Result<void> close() override { return log_->close(); }
  const std::string& partialPath() const noexcept override { return log_->partialPath(); }
  std::uint64_t messages() const noexcept override { return log_->messages(); }
  std::uint64_t bytes() const noexcept override { return log_->bytes(); }

 private:
  std::unique_ptr<record::RecordLogWriter> log_;
};

/// A rosbag2 bag: ROS topic names, log time = when it was received (as ros2 bag record does),
/// publish time = the writer's source timestamp.
class RosbagSink final : public RecordSink {
 public:
  explicit RosbagSink(std::unique_ptr<bag::RosbagWriter> bag) : bag_(std::move(bag)) {}
  Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                 bool reliable, bool latched) override {
    // Bags name types the ROS way (sensor_msgs/msg/PointCloud2), DDS the IDL way.
    const dds::KnownTopicType* known = dds::findTopicType(type);
    return bag_->addTopic(msgs::rosTopicName(dds_topic), known != nullptr ? known->ros_name : type,
                          bag::offeredQosYaml(reliable, latched, latched ? 1 : kRecordReaderDepth));
  }
  Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns, std::int64_t,
                     std::int64_t source_unix_ns, std::span<const std::byte> cdr) override {
    return bag_->write(id, receive_unix_ns, source_unix_ns, cdr);
  }
  Result<void> close() override { return bag_->close(); }
  const std::string& partialPath() const noexcept override { return bag_->partialPath(); }
  std::uint64_t messages() const noexcept override { return bag_->messages(); }
  std::uint64_t bytes() const noexcept override { return bag_->bytes(); }

 private:
  std::unique_ptr<bag::RosbagWriter> bag_;
};

Result<std::unique_ptr<RecordSink>> openSink(const RecordFlags& flags) {
  if (flags.format == "mcap") {
    auto compression = bag::parseChunkCompression(flags.compression);
    if (!compression) {
      return fail(ErrorCode::kInvalidArgument, "--compression: " + compression.error().message);
    }
    bag::RosbagWriterOptions options;
    options.compression = compression.value();
    auto bag = bag::RosbagWriter::create(flags.output, options);
    if (!bag) {
      return Unexpected(bag.error());
    }
    return std::unique_ptr<RecordSink>(std::make_unique<RosbagSink>(std::move(bag).value()));
  }
  if (flags.compression != "none") {
    return fail(ErrorCode::kInvalidArgument,
                "--compression applies to --format mcap (a .rmlog is raw capture)");
  }
  auto log = record::RecordLogWriter::create(flags.output);
  if (!log) {
    return Unexpected(log.error());
  }
  return std::unique_ptr<RecordSink>(std::make_unique<RecordLogSink>(std::move(log).value()));
}

class Recorder {
 public:
  Recorder(const RecordFlags& flags, platform::ShutdownSignals signals)
      : flags_(flags), signals_(signals) {
    for (const std::string& topic : flags.topics) {
      requested_.insert(msgs::ddsTopicName(topic));
    }
  }

  int run() {
    auto domain = domainFromOptionOrEnvironment(flags_.domain);
    if (!domain) {
      printError("record", domain.error().message);
      return kExitUsage;
    }
    auto participant =
        security::openToolParticipant(domain.value(), "raymap record", security::kToolsEnclave);
    if (!participant) {
      printError("record", participant.error().message);
      return kExitFailure;
    }
    participant_.emplace(std::move(participant).value());
    auto discovery = dds::Discovery::create(*participant_);
    if (!discovery) {
      printError("record", discovery.error().message);
      return kExitFailure;
    }
    discovery_.emplace(std::move(discovery).value());
    auto waitset = dds::Waitset::create(*participant_);
    if (!waitset) {
      printError("record", waitset.error().message);
      return kExitFailure;
    }
    waitset_.emplace(std::move(waitset).value());
    auto log = openSink(flags_);
    if (!log) {
      printError("record", log.error().message);
      return kExitFailure;
    }
    log_ = std::move(log).value();
    if (!flags_.quiet) {
      std::fprintf(stderr, "raymap record: writing %s (renamed to %s when stopped)\n",
                   log_->partialPath().c_str(), flags_.output.c_str());
    }
    const std::int64_t start = platform::monotonicNowNs();
    std::int64_t next_discovery = start;
    std::int64_t next_progress = start + 1'000'000'000;
    for (;;) {
      const std::int64_t now = platform::monotonicNowNs();
      if (flags_.duration > 0.0 && static_cast<double>(now - start) * 1e-9 >= flags_.duration) {
        break;
      }
      if (signals_.waitNs(0) != 0) {
        break;
      }
      if (now >= next_discovery) {
        if (auto added = discover(); !added) {
          printError("record", added.error().message);
          return kExitFailure;  // the .partial file stays: it holds what was recorded
        }
        next_discovery = now + static_cast<std::int64_t>(kDiscoveryPeriod_s * 1e9);
      }
      std::intptr_t triggered[16];
      const int n = waitset_->wait(20'000'000, triggered);
      for (int i = 0; i < n; ++i) {
        if (triggered[i] == dds::Waitset::kWakeToken) {
          continue;
        }
        if (auto taken = drain(*topics_by_token_.at(static_cast<std::size_t>(triggered[i])));
            !taken) {
          printError("record", taken.error().message);
          return kExitFailure;
        }
      }
      if (!flags_.quiet && now >= next_progress && ::isatty(STDERR_FILENO) != 0) {
        std::fprintf(stderr, "\rraymap record: %.0f s, %" PRIu64 " messages, %.1f MB   ",
                     static_cast<double>(now - start) * 1e-9, log_->messages(),
                     static_cast<double>(log_->bytes()) * 1e-6);
        std::fflush(stderr);
        next_progress = now + 1'000'000'000;
      }
    }
    for (auto& [name, topic] : topics_) {  // what arrived while stopping
      if (topic.reader) {
        (void)drain(topic);
      }
    }
    if (auto closed = log_->close(); !closed) {
      printError("record", closed.error().message);
      return kExitFailure;
    }
    summarise();
    return kExitOk;
  }

 private:
  /// Starts recording requested topics that now have a writer of a type raymap knows.
  Result<void> discover() {
    // One read of the built-in topics per round: the QoS check below scans the same list.
    const std::vector<dds::DiscoveredEndpoint> endpoints = discovery_->endpoints();
    for (const dds::DiscoveredEndpoint& e : endpoints) {
      if (!e.is_writer || requested_.count(e.topic) == 0) {
        continue;
      }
      RecordedTopic& topic = topics_[e.topic];
      if (topic.reader) {
        if (e.type != topic.type && warned_.insert(e.topic + "\n" + e.type).second) {
          std::fprintf(stderr,
                       "raymap record: warning: %s: a publisher of type %s is ignored (the topic "
                       "is recorded as %s)\n",
                       e.topic.c_str(), e.type.c_str(), topic.type.c_str());
        }
        continue;
      }
      const dds::KnownTopicType* known = dds::findTopicType(e.type);
      if (known == nullptr) {
        if (warned_.insert(e.topic + "\n" + e.type).second) {
          std::string names;
          for (const dds::KnownTopicType& t : dds::knownTopicTypes()) {
            names += names.empty() ? "" : ", ";
            names += t.ros_name;
          }
          std::fprintf(stderr,
                       "raymap record: warning: %s has type %s, which raymap cannot record "
                       "(known: %s)\n",
                       e.topic.c_str(), e.type.c_str(), names.c_str());
        }
        continue;
      }
      // The reader takes the writers' QoS: a reliable reader would not match a best-effort
      // writer, a transient-local one only transient-local writers. Replay republishes with
      // the same QoS.
      bool all_reliable = true, all_latched = true;
      for (const dds::DiscoveredEndpoint& w : endpoints) {
        if (w.is_writer && w.topic == e.topic && w.type == e.type) {
          all_reliable = all_reliable && w.reliability == dds::Reliability::kReliable;
          all_latched = all_latched && w.durability == dds::Durability::kTransientLocal;
        }
      }
      auto reader = dds::RawReader::create(
          *participant_, e.topic.c_str(), known->descriptor,
          all_reliable ? dds::Reliability::kReliable : dds::Reliability::kBestEffort,
          kRecordReaderDepth,
          all_latched ? dds::Durability::kTransientLocal : dds::Durability::kVolatile);
      if (!reader) {
        return Unexpected(std::move(reader).error());
      }
      auto id = log_->addTopic(e.topic, e.type, all_reliable, all_latched);
      if (!id) {
        return Unexpected(std::move(id).error());
      }
      topic.type = e.type;
      topic.log_id = id.value();
      topic.reader.emplace(std::move(reader).value());
      const auto token = static_cast<std::intptr_t>(topics_by_token_.size());
      topics_by_token_.push_back(&topic);
      if (auto attached = waitset_->attach(topic.reader->handle(), token); !attached) {
        return Unexpected(std::move(attached).error());
      }
      if (!flags_.quiet) {
        std::fprintf(stderr, "raymap record: recording %s (%s, %s%s)\n", e.topic.c_str(),
                     known->ros_name, all_reliable ? "reliable" : "best effort",
                     all_latched ? ", transient local" : "");
      }
    }
    return {};
  }

  /// Takes everything the topic's reader holds into the log.
  Result<void> drain(RecordedTopic& topic) {
    Result<void> status{};
    for (;;) {
      const int taken = topic.reader->takeEach(
          [&](std::span<const std::byte> cdr, std::int64_t source_timestamp_ns) {
            if (!status) {
              return;
            }
            status = log_->write(topic.log_id, platform::realtimeNowNs(),
                                 platform::monotonicNowNs(), source_timestamp_ns, cdr);
            ++topic.messages;
            topic.bytes += cdr.size();
          },
          kTakeBatch);
      if (!status) {
        return status;
      }
      if (taken < kTakeBatch) {
        return {};
      }
    }
  }

  void summarise() {
    if (flags_.quiet) {
      return;
    }
    if (::isatty(STDERR_FILENO) != 0) {
      std::fprintf(stderr, "\r%80s\r", "");
    }
    std::fprintf(stderr, "raymap record: wrote %s: %" PRIu64 " messages, %.1f MB\n",
                 flags_.output.c_str(), log_->messages(),
                 static_cast<double>(log_->bytes()) * 1e-6);
    for (const std::string& name : requested_) {
      const auto found = topics_.find(name);
      if (found == topics_.end() || !found->second.reader) {
        std::fprintf(stderr, "  %-28s no publisher of a known type seen\n", name.c_str());
      } else {
        std::fprintf(stderr, "  %-28s %8" PRIu64 " messages  %10.1f MB\n", name.c_str(),
                     found->second.messages, static_cast<double>(found->second.bytes) * 1e-6);
      }
    }
  }

  RecordFlags flags_;
  platform::ShutdownSignals signals_;
  std::set<std::string> requested_;
  std::optional<dds::Participant> participant_;
  std::optional<dds::Discovery> discovery_;
  std::optional<dds::Waitset> waitset_;
  std::unique_ptr<RecordSink> log_;
  std::map<std::string, RecordedTopic> topics_;  // node-based: pointers stay valid
  std::vector<RecordedTopic*> topics_by_token_;
  std::set<std::string> warned_;
};

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
    const platform::ShutdownSignals signals = platform::ShutdownSignals::install();
    Recorder recorder(*f, signals);
    *exit_code = recorder.run();
  });
}

}  // namespace raymap::cli
