// SPDX-License-Identifier: BSD-3-Clause
// A nav_msgs/OccupancyGrid sample preallocated for one grid size: the Nav2 costmap raymapd
// publishes beside each height map.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "src/core/vec3.hpp"

struct dds_topic_descriptor;
typedef struct dds_topic_descriptor dds_topic_descriptor_t;

namespace raymap::dds {

/// @brief The OccupancyGrid of one fixed grid (width × height cells): header, info (resolution,
/// width, height, origin with identity orientation, map_load_time = the stamp) and the int8
/// cells (row-major, -1 unknown, 0..100). The cells are written in place through cells().
///
/// Thread-safety: none; cells(), fill() and the Writer::write() of sample() from one thread.
/// Move-only (the sample points into buffers owned by the object).
class OccupancyGridMessage {
 public:
  /// @brief Preallocates the message. Start-up only (allocates). @pre width > 0, height > 0
  OccupancyGridMessage(int width, int height);
  OccupancyGridMessage(OccupancyGridMessage&&) noexcept;
  OccupancyGridMessage& operator=(OccupancyGridMessage&&) noexcept;
  ~OccupancyGridMessage();

  /// @brief The cells to write (width × height, row-major). @rt allocates: no.
  std::span<std::int8_t> cells() noexcept;
  /// @brief Sets the header and the geometry: `origin` is the world position of cell (0, 0)'s
  /// outer corner, metres; the frame is truncated to 63 characters. @rt allocates: no.
  void fill(double resolution, Vec3d origin, std::int64_t stamp_ns, const char* frame_id) noexcept;

  /// @brief The idlc struct (nav_msgs_msg_dds__OccupancyGrid_) to pass to Writer::write().
  const void* sample() const noexcept;
  /// @brief The type of sample() (= occupancyGridType()).
  static const dds_topic_descriptor_t* descriptor() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::dds
