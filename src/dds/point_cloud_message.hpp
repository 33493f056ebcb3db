// SPDX-License-Identifier: BSD-3-Clause
// A sensor_msgs/PointCloud2 sample preallocated for a fixed number of points and a fixed field
// layout, filled without allocating: occupied-voxel output, or a lidar-driver-like publisher
// (replay, tests).
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include <dds/dds.h>

#include "src/msgs/point_cloud.hpp"

namespace raymap::dds {

/// @brief Which fields the cloud carries. x, y, z (FLOAT32, offsets 0, 4, 8) always; then, in
/// this order and each 4-byte aligned: intensity FLOAT32, t UINT32 (nanoseconds after the header
/// stamp, as Ouster drivers send it), ring UINT16 (+ 2 bytes padding).
struct CloudLayout {
  bool intensity = false;
  bool time = false;
  bool ring = false;
  /// Rows of an organised cloud (height); 1 = unorganised. fill() then needs a point count that
  /// is a multiple of `rows` and publishes width = count / rows.
  std::uint32_t rows = 1;
};

/// @brief A little-endian PointCloud2 (is_bigendian false, row_step = width * point_step,
/// is_dense = no NaN point) with room for `capacity` points.
/// Thread-safety: none; fill() and write from one thread. Move-only.
class PointCloudMessage {
 public:
  /// @brief Preallocates the data for `capacity` points. Start-up only (allocates).
  /// @pre capacity > 0, layout.rows >= 1
  explicit PointCloudMessage(std::uint32_t capacity, CloudLayout layout = {});
  PointCloudMessage(PointCloudMessage&&) noexcept;
  PointCloudMessage& operator=(PointCloudMessage&&) noexcept;
  PointCloudMessage(const PointCloudMessage&) = delete;
  PointCloudMessage& operator=(const PointCloudMessage&) = delete;
  ~PointCloudMessage();

  /// @brief Fills x, y, z from `xyz` (x0 y0 z0 x1 ...; size a multiple of 3); other fields 0.
  /// @pre xyz.size() / 3 <= capacity() and a multiple of layout.rows
  /// @rt allocates: no.
  void fill(std::span<const float> xyz, std::int64_t stamp_ns, const char* frame_id) noexcept;

  /// @brief Fills from scan points like a driver: x, y, z (NaN for kPointNoReturn points),
  /// intensity, t = round(time_s * 1e9) clamped to [0, UINT32_MAX], ring = rings[i] (0 when
  /// `rings` is empty).
  /// @pre points.size() <= capacity() and a multiple of layout.rows; rings empty or as many
  /// as points
  /// @rt allocates: no.
  void fill(std::span<const msgs::ScanPoint> points, std::span<const std::uint16_t> rings,
            std::int64_t stamp_ns, const char* frame_id) noexcept;

  std::uint32_t capacity() const noexcept;
  std::uint32_t pointStep() const noexcept;
  const CloudLayout& layout() const noexcept;

  /// @brief The idlc struct (sensor_msgs_msg_dds__PointCloud2_) to pass to Writer::write().
  const void* sample() const noexcept;
  /// @brief The type of sample() (= pointCloud2Type()).
  static const dds_topic_descriptor_t* descriptor() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::dds
