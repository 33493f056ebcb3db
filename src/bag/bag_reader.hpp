// SPDX-License-Identifier: BSD-3-Clause
// rosbag2 recordings as a stream of serialized messages: a bag directory (metadata.yaml and its
// files), an MCAP file or a SQLite (.db3) file, read front to back in recording order.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"

namespace raymap::bag {

/// @brief One topic of a bag, as rosbag2 records it.
struct BagTopic {
  std::string name;                  ///< ROS name, e.g. "/points"
  std::string type;                  ///< ROS type, e.g. "sensor_msgs/msg/PointCloud2"
  std::string serialization_format;  ///< "cdr" for ROS 2 (MCAP: the channel's message encoding)
  /// The publishers' QoS as rosbag2 stores it (a YAML list, possibly empty).
  std::string offered_qos_profiles;
  std::string schema;  ///< the message definition when the bag carries it (MCAP), else empty
};

/// @brief One message, valid only during the callback that receives it.
struct BagMessage {
  std::uint32_t topic = 0;          ///< index into BagReader::topics()
  std::int64_t log_time_ns = 0;     ///< when the recorder received it (the bag's time base)
  std::uint64_t index = 0;          ///< 0-based, in reading order over the whole bag
  std::span<const std::byte> data;  ///< the serialized message (CDR with its 4-byte header)
};

/// @brief What a pass over the bag saw.
struct BagPass {
  std::uint64_t messages = 0;  ///< messages handed to the callback
  bool stopped = false;        ///< the callback asked to stop
  /// The file ends inside a record (a recording cut off by a crash or a full disk). Only with
  /// BagReadOptions::skip_damaged: otherwise that is an error (kTruncated).
  bool truncated = false;
  /// Only with BagReadOptions::skip_damaged: what was skipped as damaged or cut off, one line
  /// each naming the file, the offset, what was wrong and what was left unread.
  std::vector<std::string> damage;
};

/// @brief How to read a bag.
struct BagReadOptions {
  /// Damage (a chunk failing its checks, a record whose length runs past the data or over the
  /// chunks the file indexes, a file cut off) is an error naming the file, the offset and the
  /// reason, unless this is set: then what can be read is read, resuming at the next chunk the
  /// summary indexes, and BagPass::damage says what was skipped. Partial input is never passed
  /// off as whole.
  bool skip_damaged = false;
};

/// @brief Counts a bag states about itself (an MCAP summary's Statistics record), so that a
/// description does not need to read every message.
struct BagStatistics {
  std::uint64_t messages = 0;
  std::int64_t start_ns = 0;                  ///< earliest log time
  std::int64_t end_ns = 0;                    ///< latest log time
  std::vector<std::uint64_t> topic_messages;  ///< per topic, as topics() orders them
};

/// @brief Reads a bag front to back, any number of times (rewind() starts again). Messages come
/// in the order they were recorded: MCAP file order, SQLite by timestamp (as `ros2 bag play`
/// plays them). Errors name the file and, for a bad message or record, its index and offset.
/// Not thread-safe.
class BagReader {
 public:
  using Visitor = std::function<bool(const BagMessage&)>;  ///< false stops the pass

  virtual ~BagReader() = default;
  /// @brief The path given to openBag().
  virtual const std::string& path() const noexcept = 0;
  /// @brief "mcap" or "sqlite3".
  virtual const char* storage() const noexcept = 0;
  /// @brief Every topic of the bag (known before the first message).
  virtual const std::vector<BagTopic>& topics() const noexcept = 0;
  /// @brief Starts again at the first message.
  virtual Expected<void, Error> rewind() = 0;
  /// @brief The next message into `out` (its data valid until the next call).
  /// @return false at the end of the bag (or of what a truncated file holds: see pass()).
  virtual Result<bool> next(BagMessage& out) = 0;
  /// @brief What the current pass has seen so far (messages, truncation).
  virtual const BagPass& pass() const noexcept = 0;
  /// @brief Fraction of the current pass done, 0 to 1.
  virtual double progress() const noexcept = 0;
  /// @brief The bag's own statistics when it has them (an indexed MCAP file whose summary CRC
  /// checks), else nothing: then only reading every message counts them.
  virtual std::optional<BagStatistics> statistics() const { return std::nullopt; }
  /// @brief Problems found when opening that lose nothing but should be known (an MCAP file
  /// whose end or summary is damaged, read by a linear scan instead), each naming the file.
  virtual std::vector<std::string> openWarnings() const { return {}; }

  /// @brief rewind(), then every message to `visit`, in order, until it returns false.
  Result<BagPass> forEach(const Visitor& visit);
};

/// @brief True when `path` names a bag: a directory holding metadata.yaml or .mcap / .db3 files,
/// or a file ending in .mcap or .db3 (or starting with the MCAP magic), or in .mcap.zstd /
/// .db3.zstd (rosbag2's whole-file compression: refused by openBag, saying how to decompress).
bool isBag(const std::string& path);

/// @brief Opens a rosbag2 directory (its metadata.yaml lists the files, read in turn; without
/// one, its .mcap or .db3 files in name order, bag_2 before bag_10), an .mcap file or a .db3
/// file, and reads its topics.
Result<std::unique_ptr<BagReader>> openBag(const std::string& path,
                                           const BagReadOptions& options = {});

/// @brief Opens one MCAP file (any profile; rosbag2 writes "ros2").
Result<std::unique_ptr<BagReader>> openMcap(const std::string& path,
                                            const BagReadOptions& options = {});

/// @brief Opens one rosbag2 SQLite file (tables `topics` and `messages`), read-only.
Result<std::unique_ptr<BagReader>> openSqliteBag(const std::string& path);

/// @brief The index of topic `name` in `topics`, or -1.
int findTopic(const std::vector<BagTopic>& topics, const std::string& name) noexcept;

}  // namespace raymap::bag
