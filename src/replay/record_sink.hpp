// SPDX-License-Identifier: BSD-3-Clause
// Where a recording of DDS topics goes: raymap's record log or a rosbag2 bag, behind one
// interface, so the recorder writes either the same way.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "raymap/error.hpp"

namespace raymap::replay {

/// The recorder's readers keep this many samples per topic (about 25 s of 10 Hz clouds if the
/// disk stalls); a bag states it as the topic's offered history depth.
inline constexpr std::int32_t kRecordReaderDepth = 256;

/// @brief The formats a recording can take.
enum class RecordFormat : std::uint8_t {
  kRecordLog,  ///< raymap's log (.rmlog): the bytes and both receive clocks, replayed bit for bit
  kMcapBag,    ///< a rosbag2 bag of MCAP files (ROS topic and type names)
};

/// @brief An open recording. Written as `partialPath()` and renamed to its name by close().
/// Not thread-safe.
class RecordSink {
 public:
  virtual ~RecordSink() = default;
  /// @brief A topic by its DDS name and type, with the QoS its writers offered; returns its id.
  virtual Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                         bool reliable, bool latched) = 0;
  /// @brief One message: receive times (Unix and monotonic, ns), the writer's source timestamp
  /// (Unix ns) and its CDR bytes.
  virtual Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns,
                             std::int64_t receive_monotonic_ns, std::int64_t source_unix_ns,
                             std::span<const std::byte> cdr) = 0;
  virtual Result<void> close() = 0;
  virtual const std::string& partialPath() const noexcept = 0;
  virtual std::uint64_t messages() const noexcept = 0;
  virtual std::uint64_t bytes() const noexcept = 0;
};

/// @brief Creates `output` in `format`; `compression` (none, zstd, lz4) applies to bags only.
/// Errors name the output, or the option by key (record.compression).
Result<std::unique_ptr<RecordSink>> openRecordSink(const std::string& output, RecordFormat format,
                                                   const std::string& compression);

}  // namespace raymap::replay
