// SPDX-License-Identifier: BSD-3-Clause
// DDS topics recorded as they arrive: each message's raw CDR bytes into a raymap record log (for
// replay bit for bit, docs/record-format.md) or a rosbag2 bag (MCAP, for ROS tools). The engine
// of `raymap record`.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "platform/signals.hpp"
#include "src/dds/discovery.hpp"
#include "src/dds/entities.hpp"
#include "src/replay/record_sink.hpp"

namespace raymap::replay {

/// @brief What to record (the options of `raymap record`, docs/cli.md; messages name them as
/// `record.<field>`).
struct RecordOptions {
  std::string output;  ///< the log file, or the bag's directory; written as .partial until done
  RecordFormat format = RecordFormat::kRecordLog;
  std::string compression = "none";  ///< bags: per-chunk compression none, zstd or lz4
  std::vector<std::string> topics;   ///< DDS topic names (rt/points); see msgs::ddsTopicName
  std::uint32_t domain = 0;
  double duration_s = 0.0;  ///< stop after this long (0: when a shutdown signal arrives)
  /// Called on run()'s thread with what the recorder does ("recording rt/points (...)").
  std::function<void(const std::string& line)> on_notice;
  /// Called on run()'s thread, once each, for publishers it cannot record (unknown type, a
  /// second type on a recorded topic).
  std::function<void(const std::string& warning)> on_warning;
  /// Called on run()'s thread about every 20 ms while recording: seconds, messages, bytes.
  std::function<void(double seconds, std::uint64_t messages, std::uint64_t bytes)> on_progress;
};

/// @brief One requested topic and what was recorded of it.
struct RecordedTopicStats {
  std::string topic;  ///< DDS name
  bool seen = false;  ///< a publisher of a type raymap knows was found
  std::string type;   ///< its DDS type name, when seen
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
};

/// @brief What a recording holds once closed.
struct RecordStats {
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
  std::vector<RecordedTopicStats> topics;  ///< the requested topics, in name order
};

/// @brief A recorder: discovers the requested topics' publishers (every 0.1 s), reads each
/// topic with its writers' QoS and writes what arrives. Not thread-safe: create and run it on one
/// thread. Not real-time: it writes files.
class TopicRecorder {
 public:
  /// @brief Opens the participant and the output (its .partial file). Errors name the output or
  /// the option.
  static Result<std::unique_ptr<TopicRecorder>> create(const RecordOptions& options);
  ~TopicRecorder();
  TopicRecorder(const TopicRecorder&) = delete;
  TopicRecorder& operator=(const TopicRecorder&) = delete;
  /// @brief The file being written until run() closes it (renamed to options.output then).
  const std::string& partialPath() const noexcept;
  /// @brief Records until duration_s has passed, `signals` reports a shutdown or requestStop()
  /// was called, then closes the output. On an error the .partial file stays: it holds what was
  /// recorded.
  Result<RecordStats> run(platform::ShutdownSignals signals);
  /// @brief Makes run() finish (within about 20 ms): what has arrived is written, the output
  /// closed. Thread-safe: for a program that records beside its own work.
  void requestStop() noexcept { stop_requested_.store(true, std::memory_order_relaxed); }

 private:
  struct Topic;
  explicit TopicRecorder(const RecordOptions& options);
  Result<void> discover();
  /// Starts reading `endpoint`'s topic with the QoS of all its writers in `endpoints`.
  Result<void> startTopic(const dds::DiscoveredEndpoint& endpoint,
                          const std::vector<dds::DiscoveredEndpoint>& endpoints, Topic& topic);
  void warnOnce(const std::string& topic, const std::string& type, const std::string& warning);
  Result<void> drain(Topic& topic);
  RecordStats stats() const;

  RecordOptions options_;
  std::optional<dds::Participant> participant_;
  std::optional<dds::Discovery> discovery_;
  std::optional<dds::Waitset> waitset_;
  std::unique_ptr<RecordSink> sink_;
  std::map<std::string, std::unique_ptr<Topic>> topics_;
  std::vector<Topic*> topics_by_token_;
  std::set<std::string> warned_;
  // Relaxed: a flag polled by run()'s loop that publishes no other data with it.
  std::atomic<bool> stop_requested_{false};
};

}  // namespace raymap::replay
