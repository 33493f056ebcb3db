// SPDX-License-Identifier: BSD-3-Clause
// DDS endpoints that behave like the ROS 2 nodes around raymapd: a lidar driver and odometry
// publisher (best-effort, no type information), and independent subscribers of the GridMap and
// diagnostics topics that deserialise with Cyclone's own generated code.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/dds/entities.hpp"
#include "src/dds/point_cloud_message.hpp"
#include "src/io/trajectory.hpp"
#include "src/msgs/point_cloud.hpp"

namespace raymap::driver {

/// @brief Publishes PointCloud2 (x, y, z, intensity, t, ring: Ouster-like) and nav_msgs/Odometry,
/// best-effort like a driver's SensorDataQoS. Thread-safety: one thread.
class DriverPublisher {
 public:
  static Result<std::unique_ptr<DriverPublisher>> create(const dds::Participant& participant,
                                                         const std::string& cloud_topic,
                                                         const std::string& odometry_topic,
                                                         std::uint32_t max_points);
  /// @brief Grows the preallocated cloud to hold `points` (allocates; never shrinks).
  void reserveCloud(std::uint32_t points);
  /// @pre points.size() <= the capacity (create()'s max_points or reserveCloud())
  void publishCloud(std::span<const msgs::ScanPoint> points, std::span<const std::uint16_t> rings,
                    std::int64_t stamp_ns, const char* frame_id);
  void publishOdometry(std::int64_t stamp_ns, const io::Pose& pose, const char* world_frame,
                       const char* base_frame);
  /// @brief The same pose as one transform world -> base on `rt/tf` (as a localisation stack
  /// broadcasts it).
  void publishTf(std::int64_t stamp_ns, const io::Pose& pose, const char* world_frame,
                 const char* base_frame);
  /// @brief One static transform parent -> child on `rt/tf_static`, latched (reliable,
  /// transient-local, as ROS's static_transform_publisher): late readers get it too.
  void publishTfStatic(const io::Pose& pose, const char* parent, const char* child);
  /// @brief One static edge of a TF tree (frames: NUL-terminated, alive during the call).
  struct StaticEdge {
    io::Pose pose;  ///< the child in the parent
    const char* parent = nullptr;
    const char* child = nullptr;
  };
  /// @brief Several static transforms in one TFMessage on `rt/tf_static`, as
  /// robot_state_publisher sends them: the latched (keep last 1) sample holds them all.
  void publishTfStatic(std::span<const StaticEdge> edges);
  /// @brief The cloud writer, to send hand-built (e.g. deliberately malformed) PointCloud2
  /// samples (sensor_msgs_msg_dds__PointCloud2_) in tests.
  dds::Writer& cloudWriter() noexcept { return *cloud_writer_; }
  std::uint32_t matchedCloudReaders() const noexcept { return cloud_writer_->matchedReaders(); }
  /// @brief Readers of the odometry topic, and of rt/tf.
  std::uint32_t matchedOdometryReaders() const noexcept {
    return odometry_writer_->matchedReaders();
  }
  std::uint32_t matchedTfReaders() const noexcept { return tf_writer_->matchedReaders(); }

 private:
  DriverPublisher() = default;
  std::optional<dds::Writer> cloud_writer_;
  std::optional<dds::Writer> odometry_writer_;
  std::optional<dds::Writer> tf_writer_;
  std::optional<dds::Writer> tf_static_writer_;
  std::unique_ptr<dds::PointCloudMessage> cloud_;
};

/// @brief A received GridMap, deserialised by Cyclone (independent of raymap's encoder).
struct ReceivedGridMap {
  std::int64_t arrival_ns = 0;  ///< monotonic clock of the receiving process
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  double resolution = 0.0, length_x = 0.0, length_y = 0.0;
  double centre_x = 0.0, centre_y = 0.0;
  std::vector<std::string> layers;
  std::vector<std::string> basic_layers;
  std::vector<std::vector<float>> data;  ///< per layer, column-major
  std::vector<std::string> dim_labels;   ///< of the first layer
  std::vector<std::uint32_t> dim_sizes, dim_strides;
  /// @brief Layer `name` or nullptr.
  const std::vector<float>* layer(const std::string& name) const;
};

/// @brief Reliable GridMap subscriber. Thread-safety: one thread.
class GridMapListener {
 public:
  static Result<std::unique_ptr<GridMapListener>> create(const dds::Participant& participant,
                                                         const std::string& topic);
  ~GridMapListener();
  GridMapListener(const GridMapListener&) = delete;
  GridMapListener& operator=(const GridMapListener&) = delete;
  /// @brief Takes what has arrived (waits up to timeout_ns for the first); returns how many.
  int poll(std::int64_t timeout_ns, std::vector<ReceivedGridMap>& out);
  std::uint32_t matchedWriters() const noexcept;

 private:
  GridMapListener() = default;
  dds_entity_t topic_ = 0, reader_ = 0, waitset_ = 0, condition_ = 0;
};

/// @brief diagnostic_msgs/DiagnosticArray subscriber keeping the latest value of every key as
/// "status name/key". Thread-safety: one thread.
class DiagnosticsListener {
 public:
  static Result<std::unique_ptr<DiagnosticsListener>> create(const dds::Participant& participant,
                                                             const std::string& topic);
  ~DiagnosticsListener();
  DiagnosticsListener(const DiagnosticsListener&) = delete;
  DiagnosticsListener& operator=(const DiagnosticsListener&) = delete;
  /// @brief Takes what has arrived; returns how many arrays.
  int poll();
  const std::map<std::string, std::string>& values() const noexcept { return values_; }
  /// @brief A numeric value, or nullopt when absent or not a number.
  std::optional<double> number(const std::string& key) const;

 private:
  DiagnosticsListener() = default;
  dds_entity_t topic_ = 0, reader_ = 0;
  std::map<std::string, std::string> values_;
};

}  // namespace raymap::driver
