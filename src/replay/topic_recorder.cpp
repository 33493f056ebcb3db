// SPDX-License-Identifier: BSD-3-Clause
// TopicRecorder: discovery of the requested topics' publishers, one raw reader per topic with
// its writers' QoS, and the loop that writes what arrives.
#include "src/replay/topic_recorder.hpp"

#include <utility>

#include "platform/clock.hpp"
#include "src/dds/topic_types.hpp"
#include "src/security/secure_participant.hpp"

namespace raymap::replay {
namespace {

constexpr int kTakeBatch = 32;
constexpr std::int64_t kDiscoveryPeriodNs = 100'000'000;
constexpr std::int64_t kWaitNs = 20'000'000;  // the longest the loop sleeps between checks

/// The ROS names of the types raymap can record, for a warning about one it cannot.
std::string knownTypeNames() {
  std::string names;
  for (const dds::KnownTopicType& t : dds::knownTopicTypes()) {
    names += names.empty() ? "" : ", ";
    names += t.ros_name;
  }
  return names;
}

}  // namespace

/// A topic being recorded: its reader and its id in the output.
struct TopicRecorder::Topic {
  std::string type;
  std::optional<dds::RawReader> reader;
  std::uint32_t id = 0;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
};

TopicRecorder::TopicRecorder(const RecordOptions& options) : options_(options) {
  for (const std::string& topic : options.topics) {
    topics_.emplace(topic, std::make_unique<Topic>());
  }
}

TopicRecorder::~TopicRecorder() = default;

Result<std::unique_ptr<TopicRecorder>> TopicRecorder::create(const RecordOptions& options) {
  std::unique_ptr<TopicRecorder> r(new TopicRecorder(options));
  auto participant =
      security::openToolParticipant(options.domain, "raymap record", security::kToolsEnclave);
  if (!participant) {
    return Unexpected(std::move(participant).error());
  }
  r->participant_.emplace(std::move(participant).value());
  auto discovery = dds::Discovery::create(*r->participant_);
  if (!discovery) {
    return Unexpected(std::move(discovery).error());
  }
  r->discovery_.emplace(std::move(discovery).value());
  auto waitset = dds::Waitset::create(*r->participant_);
  if (!waitset) {
    return Unexpected(std::move(waitset).error());
  }
  r->waitset_.emplace(std::move(waitset).value());
  auto sink = openRecordSink(options.output, options.format, options.compression);
  if (!sink) {
    return Unexpected(std::move(sink).error());
  }
  r->sink_ = std::move(sink).value();
  return r;
}

const std::string& TopicRecorder::partialPath() const noexcept { return sink_->partialPath(); }

Result<RecordStats> TopicRecorder::run(platform::ShutdownSignals signals) {
  const std::int64_t start = platform::monotonicNowNs();
  std::int64_t next_discovery = start;
  for (;;) {
    const std::int64_t now = platform::monotonicNowNs();
    const double seconds = static_cast<double>(now - start) * 1e-9;
    if ((options_.duration_s > 0.0 && seconds >= options_.duration_s) ||
        stop_requested_.load(std::memory_order_relaxed) || signals.waitNs(0) != 0) {
      break;
    }
    if (now >= next_discovery) {
      if (auto added = discover(); !added) {
        return Unexpected(std::move(added).error());
      }
      next_discovery = now + kDiscoveryPeriodNs;
    }
    std::intptr_t triggered[16];
    const int n = waitset_->wait(kWaitNs, triggered);
    for (int i = 0; i < n; ++i) {
      if (triggered[i] == dds::Waitset::kWakeToken) {
        continue;
      }
      if (auto taken = drain(*topics_by_token_.at(static_cast<std::size_t>(triggered[i])));
          !taken) {
        return Unexpected(std::move(taken).error());
      }
    }
    if (options_.on_progress) {
      options_.on_progress(seconds, sink_->messages(), sink_->bytes());
    }
  }
  for (Topic* topic : topics_by_token_) {  // what arrived while stopping
    (void)drain(*topic);
  }
  if (auto closed = sink_->close(); !closed) {
    return Unexpected(std::move(closed).error());
  }
  return stats();
}

void TopicRecorder::warnOnce(const std::string& topic, const std::string& type,
                             const std::string& warning) {
  if (warned_.insert(topic + "\n" + type).second && options_.on_warning) {
    options_.on_warning(warning);
  }
}

Result<void> TopicRecorder::discover() {
  // One read of the built-in topics per round: the QoS check scans the same list.
  const std::vector<dds::DiscoveredEndpoint> endpoints = discovery_->endpoints();
  for (const dds::DiscoveredEndpoint& e : endpoints) {
    const auto found = topics_.find(e.topic);
    if (!e.is_writer || found == topics_.end()) {
      continue;
    }
    Topic& topic = *found->second;
    if (topic.reader) {
      if (e.type != topic.type) {
        warnOnce(e.topic, e.type,
                 e.topic + ": a publisher of type " + e.type +
                     " is ignored (the topic is recorded as " + topic.type + ")");
      }
      continue;
    }
    if (dds::findTopicType(e.type) == nullptr) {
      warnOnce(e.topic, e.type,
               e.topic + " has type " + e.type +
                   ", which raymap cannot record (known: " + knownTypeNames() + ")");
      continue;
    }
    if (auto started = startTopic(e, endpoints, topic); !started) {
      return started;
    }
  }
  return {};
}

Result<void> TopicRecorder::startTopic(const dds::DiscoveredEndpoint& e,
                                       const std::vector<dds::DiscoveredEndpoint>& endpoints,
                                       Topic& topic) {
  const dds::KnownTopicType* known = dds::findTopicType(e.type);
  // The reader takes the writers' QoS: a reliable reader would not match a best-effort writer,
  // a transient-local one only transient-local writers. Replay republishes with the same QoS.
  bool reliable = true;
  bool latched = true;
  for (const dds::DiscoveredEndpoint& w : endpoints) {
    if (w.is_writer && w.topic == e.topic && w.type == e.type) {
      reliable = reliable && w.reliability == dds::Reliability::kReliable;
      latched = latched && w.durability == dds::Durability::kTransientLocal;
    }
  }
  auto reader = dds::RawReader::create(
      *participant_, e.topic.c_str(), known->descriptor,
      reliable ? dds::Reliability::kReliable : dds::Reliability::kBestEffort, kRecordReaderDepth,
      latched ? dds::Durability::kTransientLocal : dds::Durability::kVolatile);
  if (!reader) {
    return Unexpected(std::move(reader).error());
  }
  auto id = sink_->addTopic(e.topic, e.type, reliable, latched);
  if (!id) {
    return Unexpected(std::move(id).error());
  }
  topic.type = e.type;
  topic.id = id.value();
  topic.reader.emplace(std::move(reader).value());
  const auto token = static_cast<std::intptr_t>(topics_by_token_.size());
  topics_by_token_.push_back(&topic);
  if (auto attached = waitset_->attach(topic.reader->handle(), token); !attached) {
    return Unexpected(std::move(attached).error());
  }
  if (options_.on_notice) {
    options_.on_notice("recording " + e.topic + " (" + known->ros_name + ", " +
                       (reliable ? "reliable" : "best effort") +
                       (latched ? ", transient local" : "") + ")");
  }
  return {};
}

Result<void> TopicRecorder::drain(Topic& topic) {
  Result<void> status{};
  for (;;) {
    const int taken = topic.reader->takeEach(
        [&](std::span<const std::byte> cdr, std::int64_t source_timestamp_ns) {
          if (!status) {
            return;
          }
          status = sink_->write(topic.id, platform::realtimeNowNs(), platform::monotonicNowNs(),
                                source_timestamp_ns, cdr);
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

RecordStats TopicRecorder::stats() const {
  RecordStats s;
  s.messages = sink_->messages();
  s.bytes = sink_->bytes();
  for (const auto& [name, topic] : topics_) {
    s.topics.push_back(
        {name, topic->reader.has_value(), topic->type, topic->messages, topic->bytes});
  }
  return s;
}

}  // namespace raymap::replay
