// SPDX-License-Identifier: BSD-3-Clause
// ReplaySession::playBag: a rosbag2 recording published as `ros2 bag play` would, without ROS:
// each topic on its DDS name with the QoS it was recorded with, at the recorded spacing.
#include <algorithm>
#include <string_view>

#include "src/bag/bag_reader.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/replay/replay_session.hpp"

namespace raymap::replay {
namespace {

/// The value of `key:` in the first profile of rosbag2's offered_qos_profiles YAML, or -1.
int qosValue(std::string_view yaml, std::string_view key) {
  const std::size_t at = yaml.find(std::string(key) + ":");
  if (at == std::string_view::npos) {
    return -1;
  }
  std::size_t i = at + key.size() + 1;
  while (i < yaml.size() && yaml[i] == ' ') {
    ++i;
  }
  int value = 0;
  bool digits = false;
  while (i < yaml.size() && yaml[i] >= '0' && yaml[i] <= '9') {
    value = value * 10 + (yaml[i++] - '0');
    digits = true;
  }
  return digits ? value : -1;
}

/// Why nothing of `reader` can be played: each topic with its type and what stops it.
std::string unplayableTopics(const bag::BagReader& reader) {
  std::string list;
  for (const bag::BagTopic& topic : reader.topics()) {
    const bool cdr = topic.serialization_format.empty() || topic.serialization_format == "cdr";
    list += (list.empty() ? "" : ", ") + topic.name + " (" + topic.type +
            (cdr ? "" : " in " + topic.serialization_format) + ")";
  }
  std::string known;
  for (const dds::KnownTopicType& type : dds::knownTopicTypes()) {
    known += (known.empty() ? "" : ", ") + std::string(type.ros_name);
  }
  return reader.path() + ": nothing to play: none of its topics has a type raymap publishes (" +
         (list.empty() ? "it has no topic" : "its topics: " + list) + "; raymap publishes " +
         known + " in cdr)";
}

}  // namespace

Result<ReplaySession::TopicWriters> ReplaySession::bagTopicWriters(const std::string& path,
                                                                   const bag::BagReader& reader) {
  // rmw's QoS enums: reliability 1 = reliable, 2 = best effort; durability 1 = transient local.
  // A bag without profiles plays reliable and volatile (ros2 bag play's default), /tf_static
  // transient local as its publishers latch it.
  TopicWriters out;
  std::size_t index = 0;
  for (const bag::BagTopic& topic : reader.topics()) {
    const std::size_t at = index++;
    if (leavesOutServiceOutput(path, topic.name, topic.type)) {
      out.add(at, nullptr, false, topic.name);
      continue;
    }
    const dds::KnownTopicType* known = dds::findTopicType(topic.type);
    const bool cdr = topic.serialization_format.empty() || topic.serialization_format == "cdr";
    dds::CdrWriter* writer = nullptr;
    if (known != nullptr && cdr) {
      const int reliability = qosValue(topic.offered_qos_profiles, "reliability");
      const int durability = qosValue(topic.offered_qos_profiles, "durability");
      const bool latched = durability == 1 || (durability < 0 && topic.name == "/tf_static");
      auto created =
          logWriter(msgs::ddsTopicName(topic.name), known->dds_name, reliability != 2, latched);
      if (!created) {
        return Unexpected(std::move(created).error());
      }
      writer = created.value();
    }
    if (writer == nullptr) {
      stats_.warnings.push_back(path + ": topic " + topic.name + " has type " + topic.type +
                                (cdr ? "" : " in " + topic.serialization_format) +
                                ", which this raymap cannot publish: its messages are skipped");
    }
    // Scans: point clouds and depth images (paced against raymapd's progress when unpaced).
    const bool scan =
        topic.type == "sensor_msgs/msg/PointCloud2" || topic.type == "sensor_msgs/msg/Image";
    out.add(at, writer, scan, topic.name);
  }
  return out;
}

Result<void> ReplaySession::playBag(const std::string& path) {
  bag::BagReadOptions read;
  read.skip_damaged = options_.skip_damaged;
  auto opened = bag::openBag(path, read);
  if (!opened) {
    return Unexpected(std::move(opened).error());
  }
  bag::BagReader& reader = *opened.value();
  for (const std::string& warning : reader.openWarnings()) {
    stats_.warnings.push_back(warning);
  }
  // Every topic's writer exists before the first message, so discovery is done when data starts.
  auto topics = bagTopicWriters(path, reader);
  if (!topics) {
    return Unexpected(std::move(topics).error());
  }
  // A replay that can send nothing is a failure, never a quiet success.
  if (std::none_of(topics->writers.begin(), topics->writers.end(),
                   [](const dds::CdrWriter* w) { return w; })) {
    return fail(ErrorCode::kInvalidArgument, unplayableTopics(reader));
  }
  if (!waitForScanSubscriber(*topics)) {
    return {};
  }
  if (auto rewound = reader.rewind(); !rewound) {
    return Unexpected(std::move(rewound).error());
  }
  std::optional<std::int64_t> first_ns;
  double played_until_s = pass_offset_s_;
  std::uint64_t playable = 0;  // messages on topics that have a writer
  bag::BagMessage message;
  for (;;) {
    auto next = reader.next(message);
    if (!next) {
      return Unexpected(std::move(next).error());
    }
    if (!next.value()) {
      break;
    }
    playable += topics->at(message.topic) != nullptr ? 1u : 0u;
    if (!first_ns) {
      first_ns = message.log_time_ns;
    }
    // Log times may step back a little (several recorder threads): never wait backwards.
    const double t = std::max(0.0, static_cast<double>(message.log_time_ns - *first_ns) * 1e-9);
    if (t < options_.start_s) {
      continue;
    }
    if (options_.duration_s > 0.0 && t >= options_.start_s + options_.duration_s) {
      break;
    }
    if (topics->at(message.topic) == nullptr) {
      continue;
    }
    const bag::BagTopic& topic = reader.topics()[message.topic];
    if (playRecorded(*topics, message.topic, t, message.data, played_until_s, path, message.index,
                     topic.name, topic.type) == Sent::kStopped) {
      return {};
    }
    reportProgress(reader.progress(), path);
  }
  if (playable == 0) {
    return fail(ErrorCode::kInvalidArgument,
                path + ": nothing to play: its topics of types raymap publishes hold no message");
  }
  if (reader.pass().truncated) {
    ++stats_.truncated_logs;
  }
  for (const std::string& damage : reader.pass().damage) {
    stats_.warnings.push_back("replay.skip_damaged: " + damage);
  }
  pass_offset_s_ = played_until_s + kGapBetweenInputsSeconds;
  return {};
}

}  // namespace raymap::replay
