// SPDX-License-Identifier: BSD-3-Clause
// `raymap-fastdds-peer subscribe`: a planner's and a monitor's subscriptions to raymapd's
// GridMaps, costmap and diagnostics, as Fast DDS nodes make them.
#pragma once

#include <cstdint>
#include <string>

#include "tests/fastdds/peer/json_result.hpp"
#include "tests/fastdds/peer/peer_participant.hpp"

namespace raymap::fastdds_peer {

struct SubscribeOptions {
  double seconds = 10.0;
  /// End early once this many GridMaps, costmaps and diagnostic arrays each have arrived, the
  /// diagnostic arrays counted from the first GridMap on (0: run the whole time).
  std::int64_t until = 0;
  /// With `until`: end early only once this many GridMaps have arrived too.
  std::int64_t min_maps = 0;
  /// Count `seconds` from when the GridMap reader first matched raymapd's writer (discovery
  /// left out of a measurement), not from the start.
  bool from_match = false;
  std::string grid_topic = "rt/height_map";
  std::string costmap_topic = "rt/costmap";
  std::string diagnostics_topic = "rt/diagnostics";
};

/// @brief Subscribes (reliable, volatile, keep last 10: ROS's default profile) to the three
/// topics, stamps each message's arrival (steady clock, in Fast DDS's listener) and decodes it,
/// until `seconds` have passed, `until` is met, or SIGINT/SIGTERM.
/// @param[out] result when the GridMap writer matched, maps received and skipped (gaps in the
/// writer's sequence numbers), their period p50/p99/max
/// from the arrival times, the longest time without a map in the window measured, the first
/// map's delay after the subscriber started and after the match, costmaps and diagnostics
/// received, the last
/// pipeline level, summaries of the last GridMap, costmap and diagnostic values, and the
/// datagrams the kernel dropped on the participant's sockets meanwhile (buffer full)
/// @return false when an endpoint could not be created (result says why)
bool runSubscribe(PeerParticipant& participant, const SubscribeOptions& options, Json& result);

}  // namespace raymap::fastdds_peer
