// SPDX-License-Identifier: BSD-3-Clause
// What other participants on the domain publish and subscribe, from Cyclone's built-in
// DCPSPublication and DCPSSubscription topics (a `ros2 topic list -t` without ROS).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "raymap/error.hpp"
#include <dds/dds.h>

#include "src/dds/entities.hpp"

namespace raymap::dds {

/// @brief One writer or reader that another participant announced.
struct DiscoveredEndpoint {
  std::string topic;  ///< the DDS topic name, e.g. "rt/height_map"
  std::string type;   ///< the DDS type name, e.g. "grid_map_msgs::msg::dds_::GridMap_"
  bool is_writer = false;
  Reliability reliability = Reliability::kBestEffort;
  /// kTransientLocal also stands for TRANSIENT and PERSISTENT (all three keep history for late
  /// readers; a volatile reader matches each of them).
  Durability durability = Durability::kVolatile;
  /// The endpoint accepts XCDR1 (as ROS 2 does): its data-representation list names XCDR1 or is
  /// absent (XCDR1 is the default). A writer without it does not match raymap's readers.
  bool xcdr1 = true;
  std::array<std::uint8_t, 16> participant_key{};  ///< the GUID of the endpoint's participant
};

/// @brief Readers of the DCPSPublication and DCPSSubscription built-in topics of one participant.
/// endpoints() uses dds_read, so what was discovered stays in the readers and every call sees
/// all endpoints alive now (an endpoint that went away is disposed by Cyclone and dropped).
/// Start-up and tool code: allocates, not for the real-time path.
/// Thread-safety: none; one thread at a time. Move-only; destroy before the Participant.
class Discovery {
 public:
  /// @brief Creates the two built-in readers on `participant` (which must outlive the Discovery).
  /// Discovery starts at once in the background; give it time (tens of milliseconds on
  /// loopback, more across machines) before endpoints() is complete.
  static Result<Discovery> create(const Participant& participant);

  Discovery(Discovery&& other) noexcept
      : publications_(std::exchange(other.publications_, 0)),
        subscriptions_(std::exchange(other.subscriptions_, 0)),
        own_participant_(other.own_participant_) {}
  Discovery& operator=(Discovery&& other) noexcept;
  Discovery(const Discovery&) = delete;
  Discovery& operator=(const Discovery&) = delete;
  ~Discovery();

  /// @brief Every writer and reader alive now, except those of this Discovery's own participant
  /// (built-in endpoints are never listed): writers first, in Cyclone's order. Empty when the
  /// readers cannot be read (the participant was deleted).
  std::vector<DiscoveredEndpoint> endpoints();

 private:
  Discovery(dds_entity_t publications, dds_entity_t subscriptions,
            const std::array<std::uint8_t, 16>& own_participant) noexcept
      : publications_(publications),
        subscriptions_(subscriptions),
        own_participant_(own_participant) {}
  void readInto(dds_entity_t reader, bool is_writer, std::vector<DiscoveredEndpoint>& out);

  dds_entity_t publications_ = 0;
  dds_entity_t subscriptions_ = 0;
  std::array<std::uint8_t, 16> own_participant_{};
};

/// @brief Waits up to `timeout_s` seconds for a writer of `topic` (a DDS name, "rt/...") to be
/// discovered, polling every 20 ms.
/// @return the first such writer (its type and QoS), or nullopt when none appeared in time
std::optional<DiscoveredEndpoint> waitForWriter(Discovery& discovery, const std::string& topic,
                                                double timeout_s);

}  // namespace raymap::dds
