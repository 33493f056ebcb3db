// SPDX-License-Identifier: BSD-3-Clause
// Writes a rosbag2 recording: a directory with metadata.yaml and one MCAP file in the "ros2"
// profile (ros2msg schemas holding the message definitions, cdr messages in chunks, message
// indexes and a summary), which `ros2 bag info`, `ros2 bag play` and Foxglove open.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "raymap/error.hpp"

namespace raymap::bag {

enum class ChunkCompression : std::uint8_t { kNone, kZstd, kLz4 };

/// @brief "none", "zstd", "lz4" → the compression; anything else is an error naming it.
Result<ChunkCompression> parseChunkCompression(const std::string& text);

/// @brief How the MCAP file is laid out.
struct RosbagWriterOptions {
  ChunkCompression compression = ChunkCompression::kNone;  ///< per chunk (rosbag2's default)
  std::size_t chunk_bytes = std::size_t{4} << 20;          ///< a chunk is closed once this large
};

/// @brief One bag being written. The directory is built under `<dir>.partial` and renamed to
/// `dir` by close(), so an interrupted recording never looks complete (the .partial directory
/// holds what was written up to the interruption; its MCAP lacks only the summary).
/// Not thread-safe; one writer thread. Allocates (not for a real-time thread).
class RosbagWriter {
 public:
  /// @brief Creates `<dir>.partial`; fails when `dir` exists (a bag is never overwritten).
  static Result<std::unique_ptr<RosbagWriter>> create(const std::string& dir,
                                                      const RosbagWriterOptions& options);
  virtual ~RosbagWriter() = default;

  /// @brief Adds a topic (ROS name "/points", ROS type "sensor_msgs/msg/PointCloud2", the QoS as
  /// rosbag2's offered_qos_profiles YAML). @return its id for write(); fails for a type raymap
  /// has no message definition for.
  virtual Result<std::uint32_t> addTopic(const std::string& topic, const std::string& type,
                                         const std::string& offered_qos_profiles) = 0;
  /// @brief One serialized message (CDR with its encapsulation header).
  virtual Expected<void, Error> write(std::uint32_t topic, std::int64_t log_time_ns,
                                      std::int64_t publish_time_ns,
                                      std::span<const std::byte> cdr) = 0;
  /// @brief Writes the last chunk, the summary and metadata.yaml, and renames the directory
  /// into place.
  virtual Expected<void, Error> close() = 0;

  virtual const std::string& partialPath() const noexcept = 0;
  virtual std::uint64_t messages() const noexcept = 0;
  virtual std::uint64_t bytes() const noexcept = 0;  ///< message bytes (before compression)
};

/// @brief rosbag2's offered_qos_profiles YAML for one publisher with this QoS (keep last
/// `depth`).
std::string offeredQosYaml(bool reliable, bool transient_local, int depth);

}  // namespace raymap::bag
