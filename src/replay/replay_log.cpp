// SPDX-License-Identifier: BSD-3-Clause
// ReplaySession::playLog: the messages of a raymap record log written back unchanged, on their
// recorded topics and QoS, at their recorded spacing.
#include <cstring>

#include "src/dds/topic_types.hpp"
#include "src/record/record_log_reader.hpp"
#include "src/replay/replay_session.hpp"

namespace raymap::replay {
namespace {

constexpr std::int32_t kLogWriterDepth = 16;

/// A scan: a point cloud or a depth image (paced against raymapd's progress with --rate max).
bool isPointCloud(const std::string& type) {
  return type == "sensor_msgs::msg::dds_::PointCloud2_" || type == "sensor_msgs::msg::dds_::Image_";
}

}  // namespace

bool ReplaySession::leavesOutServiceOutput(const std::string& path, const std::string& topic,
                                           const std::string& type) {
  const bool output = type.find("DiagnosticArray") != std::string::npos ||
                      type.find("grid_map_msgs") != std::string::npos;
  if (!output || options_.include_outputs) {
    return false;
  }
  stats_.warnings.push_back(
      path + ": topic " + topic + " (" + type +
      ") is not replayed: it is what a mapping service publishes, and "
      "would stand beside the live one's (replay.include_outputs replays it)");
  return true;
}

Result<dds::CdrWriter*> ReplaySession::logWriter(const std::string& topic, const std::string& type,
                                                 bool reliable, bool transient_local) {
  if (auto found = log_writers_.find(topic); found != log_writers_.end()) {
    return &found->second;
  }
  const dds::KnownTopicType* known = dds::findTopicType(type);
  if (known == nullptr) {
    return nullptr;  // a type this raymap cannot publish (a newer recorder): skipped
  }
  auto writer = dds::CdrWriter::create(
      *participant_, topic.c_str(), known->descriptor,
      reliable ? dds::Reliability::kReliable : dds::Reliability::kBestEffort, kLogWriterDepth,
      transient_local ? dds::Durability::kTransientLocal : dds::Durability::kVolatile);
  if (!writer) {
    return Unexpected(std::move(writer).error());
  }
  return &log_writers_.emplace(topic, std::move(writer).value()).first->second;
}

ReplaySession::Sent ReplaySession::sendRecorded(dds::CdrWriter& writer, bool cloud, double t,
                                                std::span<const std::byte> cdr,
                                                double& played_until_s) {
  if (cloud && !waitForRoom()) {
    return Sent::kStopped;
  }
  const double replay_s = pass_offset_s_ + t - options_.start_s;
  if (!clock_.waitUntil(replay_s)) {
    return Sent::kStopped;
  }
  if (!writer.write(cdr).has_value()) {
    ++stats_.undecodable;
    return Sent::kRefused;
  }
  ++stats_.messages;
  stats_.scans += cloud ? 1 : 0;
  stats_.data_seconds += std::max(0.0, replay_s - played_until_s);
  played_until_s = std::max(played_until_s, replay_s);
  return Sent::kSent;
}

void ReplaySession::TopicWriters::add(std::size_t index, dds::CdrWriter* writer, bool scan,
                                      const std::string& topic) {
  if (writers.size() <= index) {
    writers.resize(index + 1, nullptr);
    scans.resize(index + 1, false);
    warned.resize(index + 1, false);
  }
  writers[index] = writer;
  scans[index] = scan;
  if (writer != nullptr && scan && first_scan == nullptr) {
    first_scan = writer;
    first_scan_topic = topic;
  }
}

bool ReplaySession::waitForScanSubscriber(const TopicWriters& topics) {
  dds::CdrWriter* first = topics.first_scan;
  return first == nullptr ||
         waitForSubscriber([first] { return first->matchedReaders(); }, topics.first_scan_topic);
}

ReplaySession::Sent ReplaySession::playRecorded(TopicWriters& topics, std::size_t index, double t,
                                                std::span<const std::byte> cdr,
                                                double& played_until_s, const std::string& path,
                                                std::uint64_t number, const std::string& topic,
                                                const std::string& type) {
  const Sent sent =
      sendRecorded(*topics.writers[index], topics.scans[index], t, cdr, played_until_s);
  if (sent == Sent::kRefused && !topics.warned[index]) {
    topics.warned[index] = true;
    stats_.warnings.push_back(path + ": message " + std::to_string(number) + " on " + topic +
                              " is not a valid " + type +
                              " or could not be sent: skipped (and any more like it)");
  }
  return sent;
}

Result<ReplaySession::TopicWriters> ReplaySession::logTopicWriters(
    const std::string& path, const std::vector<record::LogTopic>& topics) {
  TopicWriters out;
  for (const record::LogTopic& topic : topics) {
    if (leavesOutServiceOutput(path, topic.name, topic.type)) {
      out.add(topic.id, nullptr, false, topic.name);
      continue;
    }
    auto writer =
        logWriter(topic.name, topic.type, topic.reliability == record::LogReliability::kReliable,
                  topic.durability == record::LogDurability::kTransientLocal);
    if (!writer) {
      return Unexpected(std::move(writer).error());
    }
    if (writer.value() == nullptr) {
      stats_.warnings.push_back(path + ": topic " + topic.name + " has type " + topic.type +
                                ", which this raymap cannot publish: its messages are skipped");
    }
    out.add(topic.id, writer.value(), isPointCloud(topic.type), topic.name);
  }
  return out;
}

Result<void> ReplaySession::playLog(const std::string& path) {
  // One pass over the file first: every topic's writer exists before the first message, so
  // discovery is done when the data starts, and the summary gives the progress total.
  auto summary = record::RecordLogReader::summarize(path);
  if (!summary) {
    return Unexpected(std::move(summary).error());
  }
  auto topics = logTopicWriters(path, summary.value().topics);
  if (!topics) {
    return Unexpected(std::move(topics).error());
  }
  if (!waitForScanSubscriber(*topics)) {
    return {};
  }
  auto opened = record::RecordLogReader::open(path);
  if (!opened) {
    return Unexpected(std::move(opened).error());
  }
  record::RecordLogReader& reader = *opened.value();
  std::optional<std::int64_t> first_receive_ns;
  double played_until_s = pass_offset_s_;
  for (;;) {
    auto next = reader.next();
    if (!next) {
      return Unexpected(std::move(next).error());
    }
    if (!next.value()) {
      break;
    }
    const record::LogMessage& message = *next.value();
    if (!first_receive_ns) {
      first_receive_ns = message.receive_monotonic_ns;
    }
    const double t = static_cast<double>(message.receive_monotonic_ns - *first_receive_ns) * 1e-9;
    if (t < options_.start_s) {
      continue;
    }
    if (options_.duration_s > 0.0 && t >= options_.start_s + options_.duration_s) {
      break;
    }
    if (topics->at(message.topic_id) == nullptr) {
      continue;
    }
    const record::LogTopic* topic = reader.topic(message.topic_id);
    if (playRecorded(*topics, message.topic_id, t, message.cdr, played_until_s, path,
                     reader.messagesRead(), topic != nullptr ? topic->name : "?",
                     topic != nullptr ? topic->type : "?") == Sent::kStopped) {
      return {};
    }
    reportProgress(reader.progress(), path);
  }
  if (reader.truncation()) {
    ++stats_.truncated_logs;
    stats_.warnings.push_back(
        path + ": the recording was interrupted: " + reader.truncation()->what + "; replayed the " +
        std::to_string(reader.truncation()->complete_messages) + " complete messages before it");
  }
  pass_offset_s_ = played_until_s + kGapBetweenInputsSeconds;
  return {};
}

}  // namespace raymap::replay
