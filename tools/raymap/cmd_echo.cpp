// SPDX-License-Identifier: BSD-3-Clause
// `raymap echo TOPIC`: subscribes to one topic with its publisher's QoS and prints each message
// (a `ros2 topic echo` for the types raymap knows, without ROS).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "platform/clock.hpp"
#include "platform/signals.hpp"
#include "src/dds/discovery.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/security/secure_participant.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/dds_cli.hpp"
#include "tools/raymap/echo_printers.hpp"

namespace raymap::cli {
namespace {

struct EchoFlags {
  std::string topic;
  int domain = -1;  ///< -1: $ROS_DOMAIN_ID or 0
  std::uint64_t count = 0;
  double duration_s = 0.0;
  double wait_s = 5.0;
  bool json = false;
};

/// History depth of echo's reader: room for a burst while a large message is printed.
constexpr std::int32_t kReaderDepth = 16;
/// How often the loops look at the shutdown signals (the longest a Ctrl-C waits).
constexpr std::int64_t kPollNs = 50'000'000;
constexpr double kPollS = 0.05;

std::string knownTypeList() {
  std::string list;
  for (const dds::KnownTopicType& type : dds::knownTopicTypes()) {
    list += list.empty() ? "" : ", ";
    list += type.ros_name;
  }
  return list;
}

/// Waits for a writer of `topic` in slices, so that SIGINT/SIGTERM stop the wait.
/// @return the writer; nullopt on timeout; sets `*interrupted` when a signal ended the wait.
std::optional<dds::DiscoveredEndpoint> waitForPublisher(dds::Discovery& discovery,
                                                        const std::string& topic, double wait_s,
                                                        platform::ShutdownSignals& signals,
                                                        bool* interrupted) {
  const std::int64_t deadline_ns =
      platform::monotonicNowNs() + static_cast<std::int64_t>(std::min(wait_s, 1e7) * 1e9);
  for (;;) {
    const double left_s = static_cast<double>(deadline_ns - platform::monotonicNowNs()) * 1e-9;
    auto writer = dds::waitForWriter(discovery, topic, std::clamp(left_s, 0.0, kPollS));
    if (writer) {
      return writer;
    }
    if (signals.waitNs(0) != 0) {
      *interrupted = true;
      return std::nullopt;
    }
    if (platform::monotonicNowNs() >= deadline_ns) {
      return std::nullopt;
    }
  }
}

/// The QoS that matches every publisher of `topic`. Best effort as soon as one writer is best
/// effort: a reliable reader would not match it, and a best-effort reader matches reliable
/// writers too. Transient-local only when every writer is (a latched /tf_static: its history
/// arrives too); such a reader would not match a volatile writer. Warns of writers of another
/// type.
struct ReaderQos {
  dds::Reliability reliability;
  dds::Durability durability;
};
ReaderQos matchingQos(dds::Discovery& discovery, const std::string& topic,
                      const dds::DiscoveredEndpoint& writer) {
  ReaderQos qos{writer.reliability, dds::Durability::kTransientLocal};
  for (const dds::DiscoveredEndpoint& other : discovery.endpoints()) {
    if (other.is_writer && other.topic == topic) {
      if (other.reliability == dds::Reliability::kBestEffort) {
        qos.reliability = dds::Reliability::kBestEffort;
      }
      if (other.durability != dds::Durability::kTransientLocal) {
        qos.durability = dds::Durability::kVolatile;
      }
      if (other.type != writer.type) {
        std::fprintf(stderr,
                     "raymap echo: warning: %s also has a publisher of type %s; reading it as "
                     "%s (the other does not match)\n",
                     topic.c_str(), other.type.c_str(), writer.type.c_str());
      }
    }
  }
  return qos;
}

/// The type to decode the writer's samples as; prints the error and returns nullptr when raymap
/// cannot read them.
const dds::KnownTopicType* decodableType(const std::string& topic,
                                         const dds::DiscoveredEndpoint& writer) {
  const dds::KnownTopicType* type = dds::findTopicType(writer.type);
  if (type == nullptr) {
    const std::string ros_type = msgs::rosTypeName(writer.type);
    printError("echo", topic + " has type " + writer.type +
                           (ros_type != writer.type ? " (" + ros_type + ")" : std::string()) +
                           ", which raymap cannot decode; known types: " + knownTypeList());
    return nullptr;
  }
  if (!writer.xcdr1) {
    printError("echo", "the publisher of " + topic + " (" + type->ros_name +
                           ") offers only XCDR2 data; raymap reads XCDR1, as ROS 2 does");
    return nullptr;
  }
  return type;
}

/// Prints each message taken and counts them. Called inside the reader's noexcept take:
/// nothing may escape.
struct SamplePrinter {
  const std::string& topic;
  const dds::KnownTopicType* type;
  EchoFormat format;
  std::uint64_t received = 0;
  std::uint64_t undecodable = 0;
  bool output_failed = false;

  void operator()(std::span<const std::byte> cdr, std::int64_t source_timestamp_ns) noexcept {
    try {
      ++received;
      EchoSample sample{topic, type, cdr};
      sample.index = received;
      sample.arrival_unix_ns = platform::realtimeNowNs();
      sample.arrival_monotonic_ns = platform::monotonicNowNs();
      sample.source_timestamp_ns = source_timestamp_ns;
      auto text = formatSample(sample, format);
      if (!text) {
        ++undecodable;
        printError("echo", topic + " message #" + std::to_string(received) + " (" + type->ros_name +
                               ", " + std::to_string(cdr.size()) +
                               " bytes) does not decode: " + text.error().message);
        return;
      }
      // Flushed per message: scripts read the stream live.
      if (std::fputs(text->c_str(), stdout) < 0 || std::fflush(stdout) != 0) {
        output_failed = true;
      }
    } catch (const std::exception& e) {
      ++undecodable;
      std::fprintf(stderr, "raymap echo: error: %s message #%llu: %s\n", topic.c_str(),
                   static_cast<unsigned long long>(received), e.what());
    }
  }
};

/// Prints messages until --count, --duration, SIGINT/SIGTERM or a closed standard output.
int printMessages(const EchoFlags& flags, const std::string& topic, const dds::KnownTopicType* type,
                  dds::RawReader& reader, dds::Waitset& waitset,
                  platform::ShutdownSignals& signals) {
  SamplePrinter printer{topic, type, flags.json ? EchoFormat::kJsonLines : EchoFormat::kHuman};
  const std::int64_t start_ns = platform::monotonicNowNs();
  const std::int64_t end_ns =
      flags.duration_s > 0.0
          ? start_ns + static_cast<std::int64_t>(std::min(flags.duration_s, 1e7) * 1e9)
          : INT64_MAX;
  const auto done = [&] {
    return (flags.count > 0 && printer.received >= flags.count) ||
           platform::monotonicNowNs() >= end_ns || printer.output_failed;
  };
  while (!done()) {
    std::intptr_t tokens[2];
    const std::int64_t timeout_ns = std::min(kPollNs, end_ns - platform::monotonicNowNs());
    static_cast<void>(waitset.wait(timeout_ns, tokens));
    const std::uint64_t left = flags.count > 0 ? flags.count - printer.received : 16;
    const int max_samples = static_cast<int>(std::min<std::uint64_t>(left, 16));
    const int taken = reader.takeEach(printer, max_samples);
    if (taken < 0) {
      printError("echo", "reading " + topic + ": " + dds_strretcode(taken));
      return kExitFailure;
    }
    if (signals.waitNs(0) != 0) {
      break;
    }
  }
  if (printer.output_failed) {
    printError("echo", "standard output closed or unwritable; stopping");
    return kExitFailure;
  }
  if (!flags.json || printer.undecodable > 0) {
    std::fprintf(stderr, "raymap echo: %llu message%s from %s, %llu undecodable\n",
                 static_cast<unsigned long long>(printer.received),
                 printer.received == 1 ? "" : "s", topic.c_str(),
                 static_cast<unsigned long long>(printer.undecodable));
  }
  return kExitOk;
}

int runEcho(const EchoFlags& flags) {
  const std::string topic = msgs::ddsTopicName(flags.topic);
  if (topic.empty()) {
    printError("echo",
               "TOPIC is empty: give a DDS name (rt/height_map) or a ROS name (/height_map)");
    return kExitUsage;
  }
  auto domain = domainFromOptionOrEnvironment(flags.domain);
  if (!domain) {
    printError("echo", domain.error().message);
    return kExitUsage;
  }
  // Before the participant: Cyclone's threads inherit the blocked set, so SIGINT/SIGTERM wait
  // for this thread to take them and the loop below ends cleanly.
  platform::ShutdownSignals signals = platform::ShutdownSignals::install();
  auto participant = security::openToolParticipant(*domain, "raymap echo", security::kToolsEnclave);
  if (!participant) {
    printError("echo", "domain " + std::to_string(*domain) + ": " + participant.error().message);
    return kExitFailure;
  }
  auto discovery = dds::Discovery::create(*participant);
  if (!discovery) {
    printError("echo", discovery.error().message);
    return kExitFailure;
  }

  bool interrupted = false;
  const auto writer = waitForPublisher(*discovery, topic, flags.wait_s, signals, &interrupted);
  if (interrupted) {
    return kExitOk;
  }
  if (!writer) {
    printError("echo", "no publisher of " + topic + " seen in " + secondsText(flags.wait_s) +
                           " on domain " + std::to_string(*domain) +
                           " (raymap topics lists the topics)");
    return kExitFailure;
  }
  const dds::KnownTopicType* type = decodableType(topic, *writer);
  if (type == nullptr) {
    return kExitFailure;
  }
  const ReaderQos qos = matchingQos(*discovery, topic, *writer);
  auto reader = dds::RawReader::create(*participant, topic.c_str(), type->descriptor,
                                       qos.reliability, kReaderDepth, qos.durability);
  if (!reader) {
    printError("echo", reader.error().message);
    return kExitFailure;
  }
  auto waitset = dds::Waitset::create(*participant);
  if (!waitset) {
    printError("echo", waitset.error().message);
    return kExitFailure;
  }
  constexpr std::intptr_t kReaderToken = 1;
  if (auto attached = waitset->attach(reader->handle(), kReaderToken); !attached) {
    printError("echo", attached.error().message);
    return kExitFailure;
  }
  if (!flags.json) {
    std::fprintf(stderr, "raymap echo: %s (%s, %s) on domain %u\n", topic.c_str(), type->ros_name,
                 qos.reliability == dds::Reliability::kReliable ? "reliable" : "best effort",
                 *domain);
  }
  return printMessages(flags, topic, type, *reader, *waitset, signals);
}

}  // namespace

void addEchoCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<EchoFlags>();
  CLI::App* c = app.add_subcommand(
      "echo", "Print the messages of a DDS/ROS 2 topic of a type raymap knows (see docs/cli.md)");
  c->add_option("topic", flags->topic, "DDS topic (rt/height_map) or ROS topic (/height_map)")
      ->required();
  c->add_option("--domain", flags->domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, kMaxDomainId));
  c->add_option("--count", flags->count, "Stop after N messages (0 = no limit)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--duration", flags->duration_s,
                "Stop after S seconds of reading (0 = until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--wait", flags->wait_s, "Seconds to wait for a publisher (default 5)")
      ->check(CLI::NonNegativeNumber);
  c->add_flag("--json", flags->json, "One JSON object per message and line (JSON Lines)");
  c->callback([flags, exit_code] { *exit_code = runEcho(*flags); });
}

}  // namespace raymap::cli
