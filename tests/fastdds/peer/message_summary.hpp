// SPDX-License-Identifier: BSD-3-Clause
// What the peer reports of the messages it received: a GridMap's layout and floor, a costmap's
// cells by cost, the latest diagnostic values.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "diagnostic_msgsPubSubTypes.h"
#include "grid_map_msgsPubSubTypes.h"
#include "nav_msgsPubSubTypes.h"

#include "tests/fastdds/peer/json_result.hpp"

namespace raymap::fastdds_peer {

/// @brief A grid_map_msgs/GridMap as decoded by Fast DDS.
struct GridMapSummary {
  std::string frame_id;
  std::int64_t stamp_ns = 0;
  double resolution = 0.0, length_x = 0.0, length_y = 0.0, centre_x = 0.0, centre_y = 0.0;
  std::vector<std::string> layers, basic_layers, dim_labels;  ///< dim_labels: the first layer's
  std::vector<std::int64_t> dim_sizes, dim_strides;           ///< the first layer's
  std::vector<std::int64_t> layer_sizes;                      ///< values per layer
  std::int64_t surface_cells = 0;         ///< cells of layer `kind` = 1 (a surface)
  double surface_elevation_median = 0.0;  ///< layer `elevation` over those cells (NaN: none)
};

/// @brief A nav_msgs/OccupancyGrid as decoded by Fast DDS, its cells counted by value.
struct CostmapSummary {
  std::string frame_id;
  std::int64_t stamp_ns = 0;
  std::int64_t width = 0, height = 0;
  double resolution = 0.0, origin_x = 0.0, origin_y = 0.0;
  std::int64_t cells = 0;
  std::int64_t unknown = 0;  ///< -1
  std::int64_t free = 0;     ///< 0
  std::int64_t costed = 0;   ///< 1 to 99
  std::int64_t lethal = 0;   ///< 100
  std::int64_t invalid = 0;  ///< anything else
};

GridMapSummary summarize(const grid_map_msgs::msg::dds_::GridMap_& map);
CostmapSummary summarize(const nav_msgs::msg::dds_::OccupancyGrid_& costmap);

/// @brief The latest value of every diagnostic key as "status name/key", plus "status
/// name/level" and "status name/message", over all arrays absorbed.
class DiagnosticValues {
 public:
  void absorb(const diagnostic_msgs::msg::dds_::DiagnosticArray_& array);
  /// @brief The value of `key` in the status whose name ends with `status_suffix` (": pipeline"
  /// finds "raymapd: pipeline"), or "" when there is none.
  std::string find(const std::string& status_suffix, const std::string& key) const;

 private:
  std::map<std::string, std::string> values_;  // "status name/key"
};

Json toJson(const GridMapSummary& map);
Json toJson(const CostmapSummary& costmap);
/// @brief raymapd's pipeline and height-map counters the tests read (integers; -1 when absent or
/// not a number).
Json toJson(const DiagnosticValues& values);

}  // namespace raymap::fastdds_peer
