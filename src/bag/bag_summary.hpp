// SPDX-License-Identifier: BSD-3-Clause
// What a rosbag2 recording holds: its topics, their types, message counts and bytes, and its
// time span, as `ros2 bag info` describes it (`raymap info BAG`, the Python module).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/bag/bag_reader.hpp"

namespace raymap::bag {

/// @brief One topic of a bag and what it holds.
struct TopicSummary {
  BagTopic topic;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;  ///< serialized bytes (CDR with its header); 0 when from_summary
};

/// @brief A bag described (value type). Times are log times (when the recorder received each
/// message), in nanoseconds since the Unix epoch.
struct BagSummary {
  std::string storage;  ///< "mcap" or "sqlite3"
  std::vector<TopicSummary> topics;
  std::uint64_t messages = 0;
  std::int64_t start_ns = 0;  ///< earliest log time (0 without messages)
  std::int64_t end_ns = 0;    ///< latest log time (0 without messages)
  /// The counts are those an indexed MCAP file states in its summary (no message was read, so
  /// bytes are unknown); false: counted from the messages themselves.
  bool from_summary = false;
  bool truncated = false;  ///< the recording ends inside a record (read up to there)
  /// What a reader should know, one line each naming the file: problems found on opening that
  /// lose nothing, and the damage skipped while counting (configuration keys as in the library's
  /// messages: "bag.skip_damaged").
  std::vector<std::string> warnings;

  /// @brief end_ns - start_ns in seconds (0 without messages).
  double durationSeconds() const noexcept {
    return messages > 0 ? static_cast<double>(end_ns - start_ns) * 1e-9 : 0.0;
  }
};

/// @brief Describes the bag at `path` (a rosbag2 directory, .mcap or .db3). An indexed MCAP
/// file's summary is believed unless `count_messages` is set (no need to read gigabytes); else
/// every message is read, which also gives the bytes per topic. A damaged bag is described as
/// far as it can be read, the damage listed in the warnings; a bag that cannot be opened is an
/// error naming the file and the reason. Thread-safe (each call opens the bag itself).
Result<BagSummary> summariseBag(const std::string& path, bool count_messages);

}  // namespace raymap::bag
