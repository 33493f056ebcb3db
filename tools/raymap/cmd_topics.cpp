// SPDX-License-Identifier: BSD-3-Clause
// `raymap topics`: the topics other participants publish or subscribe on a domain, with their
// types, endpoint counts and publisher QoS (a `ros2 topic list -t -v` without ROS).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "platform/signals.hpp"
#include "src/dds/discovery.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/security/secure_participant.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/dds_cli.hpp"
#include "tools/raymap/json_output.hpp"

namespace raymap::cli {
namespace {

struct TopicsFlags {
  int domain = -1;  ///< -1: $ROS_DOMAIN_ID or 0
  double wait_s = 1.5;
  bool json = false;
};

/// What the endpoints of one topic add up to.
struct TopicSummary {
  std::vector<std::string> types;  ///< DDS type names, distinct, in the order seen
  int publishers = 0;
  int subscribers = 0;
  int reliable_publishers = 0;
  int transient_local_publishers = 0;
};

/// "reliable", "best_effort", "mixed"; "" without publishers.
std::string publisherPolicy(int publishers, int with_first, const char* first, const char* second) {
  if (publishers == 0) {
    return "";
  }
  if (with_first == publishers) {
    return first;
  }
  return with_first == 0 ? second : "mixed";
}

std::string reliabilityText(const TopicSummary& s) {
  return publisherPolicy(s.publishers, s.reliable_publishers, "reliable", "best_effort");
}

std::string durabilityText(const TopicSummary& s) {
  return publisherPolicy(s.publishers, s.transient_local_publishers, "transient_local", "volatile");
}

std::string rosTypesText(const std::vector<std::string>& types) {
  std::string text;
  for (const std::string& type : types) {
    text += text.empty() ? "" : " | ";
    text += printableText(msgs::rosTypeName(type), true);
  }
  return text;
}

/// `null` for an empty text (a topic outside ROS's naming; the policies of a topic without
/// publishers).
Json textOrNull(const std::string& text) { return text.empty() ? Json() : Json(text); }

void printJson(const std::map<std::string, TopicSummary>& topics) {
  // One array, but each topic's object on a line of its own (as docs/cli.md shows it), so the
  // list reads and greps by topic: the array's brackets and commas are placed here, each object
  // is dumped compact.
  std::string out = "[";
  bool first = true;
  for (const auto& [name, s] : topics) {
    Json types = Json::array();
    for (const std::string& t : s.types) {
      types.push_back(printableText(msgs::rosTypeName(t), false));
    }
    const std::string ros_topic = msgs::rosTopicName(name);
    const std::string type = s.types.empty() ? std::string() : s.types.front();
    const Json j = {
        {"topic", printableText(name, false)},
        {"ros_topic", textOrNull(printableText(ros_topic, false))},
        {"type", printableText(msgs::rosTypeName(type), false)},
        {"dds_type", printableText(type, false)},
        {"types", types},
        {"known_type", dds::findTopicType(type) != nullptr},
        {"publishers", s.publishers},
        {"subscribers", s.subscribers},
        {"reliability", textOrNull(reliabilityText(s))},
        {"durability", textOrNull(durabilityText(s))},
    };
    out += first ? "\n  " : ",\n  ";
    out += dumpJson(j, JsonStyle::kCompact);
    first = false;
  }
  out += first ? "]\n" : "\n]\n";
  std::fputs(out.c_str(), stdout);
}

void printTable(const std::map<std::string, TopicSummary>& topics) {
  struct Row {
    std::string topic, ros_topic, type, publishers, subscribers, reliability;
  };
  std::vector<Row> rows;
  rows.push_back({"TOPIC", "ROS TOPIC", "TYPE", "PUB", "SUB", "RELIABILITY"});
  for (const auto& [name, s] : topics) {
    const std::string ros_topic = msgs::rosTopicName(name);
    const std::string reliability = reliabilityText(s);
    rows.push_back({printableText(name, true),
                    ros_topic.empty() ? "-" : printableText(ros_topic, true), rosTypesText(s.types),
                    std::to_string(s.publishers), std::to_string(s.subscribers),
                    reliability.empty() ? "-" : reliability});
  }
  std::size_t widths[3] = {0, 0, 0};
  for (const Row& row : rows) {
    widths[0] = std::max(widths[0], row.topic.size());
    widths[1] = std::max(widths[1], row.ros_topic.size());
    widths[2] = std::max(widths[2], row.type.size());
  }
  for (const Row& row : rows) {
    std::printf("%-*s  %-*s  %-*s  %3s  %3s  %s\n", static_cast<int>(widths[0]), row.topic.c_str(),
                static_cast<int>(widths[1]), row.ros_topic.c_str(), static_cast<int>(widths[2]),
                row.type.c_str(), row.publishers.c_str(), row.subscribers.c_str(),
                row.reliability.c_str());
  }
}

int runTopics(const TopicsFlags& flags) {
  auto domain = domainFromOptionOrEnvironment(flags.domain);
  if (!domain) {
    printError("topics", domain.error().message);
    return kExitUsage;
  }
  // Before the participant: Cyclone's threads inherit the blocked set, so a Ctrl-C during the
  // wait is taken here and ends the wait early.
  platform::ShutdownSignals signals = platform::ShutdownSignals::install();
  auto participant =
      security::openToolParticipant(*domain, "raymap topics", security::kToolsEnclave);
  if (!participant) {
    printError("topics", "domain " + std::to_string(*domain) + ": " + participant.error().message);
    return kExitFailure;
  }
  auto discovery = dds::Discovery::create(*participant);
  if (!discovery) {
    printError("topics", discovery.error().message);
    return kExitFailure;
  }
  // Discovery runs in Cyclone's threads; give it the time asked for (a signal cuts it short and
  // what was seen so far is listed).
  static_cast<void>(signals.waitNs(static_cast<std::int64_t>(std::min(flags.wait_s, 1e7) * 1e9)));

  std::map<std::string, TopicSummary> topics;  // sorted by DDS name
  for (const dds::DiscoveredEndpoint& e : discovery->endpoints()) {
    TopicSummary& s = topics[e.topic];
    if (std::find(s.types.begin(), s.types.end(), e.type) == s.types.end()) {
      s.types.push_back(e.type);
    }
    if (e.is_writer) {
      ++s.publishers;
      s.reliable_publishers += e.reliability == dds::Reliability::kReliable ? 1 : 0;
      s.transient_local_publishers += e.durability == dds::Durability::kTransientLocal ? 1 : 0;
    } else {
      ++s.subscribers;
    }
  }
  if (flags.json) {
    printJson(topics);
  } else if (topics.empty()) {
    std::printf("no topics seen in %s on domain %u\n", secondsText(flags.wait_s).c_str(), *domain);
  } else {
    printTable(topics);
  }
  return kExitOk;
}

}  // namespace

void addTopicsCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<TopicsFlags>();
  CLI::App* c = app.add_subcommand(
      "topics", "List the DDS/ROS 2 topics seen on a domain, with types and endpoints");
  c->add_option("--domain", flags->domain, "DDS domain (default: $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, kMaxDomainId));
  c->add_option("--wait", flags->wait_s, "Seconds to listen for discovery (default 1.5)")
      ->check(CLI::NonNegativeNumber);
  c->add_flag("--json", flags->json, "Print one JSON array");
  c->callback([flags, exit_code] { *exit_code = runTopics(*flags); });
}

}  // namespace raymap::cli
