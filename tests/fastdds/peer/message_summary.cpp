// SPDX-License-Identifier: BSD-3-Clause
// Summaries of received messages, and their JSON.
#include "tests/fastdds/peer/message_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace raymap::fastdds_peer {
namespace {

std::int64_t unixNs(const builtin_interfaces::msg::dds_::Time_& time) {
  return static_cast<std::int64_t>(time.sec()) * 1000000000 + time.nanosec();
}

const std::vector<float>* layer(const grid_map_msgs::msg::dds_::GridMap_& map,
                                const std::string& name) {
  for (std::size_t i = 0; i < map.layers().size() && i < map.data().size(); ++i) {
    if (map.layers()[i] == name) {
      return &map.data()[i].data();
    }
  }
  return nullptr;
}

double median(std::vector<double> values) {
  if (values.empty()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

std::string endingWith(const std::map<std::string, std::string>& values,
                       const std::string& status_suffix, const std::string& key) {
  const std::string tail = status_suffix + "/" + key;
  for (const auto& [name, value] : values) {
    if (name.size() >= tail.size() &&
        name.compare(name.size() - tail.size(), tail.size(), tail) == 0) {
      return value;
    }
  }
  return "";
}

}  // namespace

GridMapSummary summarize(const grid_map_msgs::msg::dds_::GridMap_& map) {
  GridMapSummary s;
  s.frame_id = map.header().frame_id();
  s.stamp_ns = unixNs(map.header().stamp());
  s.resolution = map.info().resolution();
  s.length_x = map.info().length_x();
  s.length_y = map.info().length_y();
  s.centre_x = map.info().pose().position().x();
  s.centre_y = map.info().pose().position().y();
  s.layers = map.layers();
  s.basic_layers = map.basic_layers();
  for (const auto& values : map.data()) {
    s.layer_sizes.push_back(static_cast<std::int64_t>(values.data().size()));
  }
  if (!map.data().empty()) {
    for (const auto& dim : map.data().front().layout().dim()) {
      s.dim_labels.push_back(dim.label());
      s.dim_sizes.push_back(dim.size());
      s.dim_strides.push_back(dim.stride());
    }
  }
  const std::vector<float>* elevation = layer(map, "elevation");
  const std::vector<float>* kind = layer(map, "kind");
  std::vector<double> surface;
  if (elevation != nullptr && kind != nullptr) {
    for (std::size_t c = 0; c < std::min(elevation->size(), kind->size()); ++c) {
      if ((*kind)[c] == 1.0f && std::isfinite((*elevation)[c])) {
        surface.push_back(static_cast<double>((*elevation)[c]));
      }
    }
  }
  s.surface_cells = static_cast<std::int64_t>(surface.size());
  s.surface_elevation_median = median(std::move(surface));
  return s;
}

CostmapSummary summarize(const nav_msgs::msg::dds_::OccupancyGrid_& costmap) {
  CostmapSummary s;
  s.frame_id = costmap.header().frame_id();
  s.stamp_ns = unixNs(costmap.header().stamp());
  s.width = costmap.info().width();
  s.height = costmap.info().height();
  s.resolution = static_cast<double>(costmap.info().resolution());
  s.origin_x = costmap.info().origin().position().x();
  s.origin_y = costmap.info().origin().position().y();
  s.cells = static_cast<std::int64_t>(costmap.data().size());
  for (const std::int8_t cost : costmap.data()) {
    if (cost == -1) {
      ++s.unknown;
    } else if (cost == 0) {
      ++s.free;
    } else if (cost > 0 && cost < 100) {
      ++s.costed;
    } else if (cost == 100) {
      ++s.lethal;
    } else {
      ++s.invalid;
    }
  }
  return s;
}

void DiagnosticValues::absorb(const diagnostic_msgs::msg::dds_::DiagnosticArray_& array) {
  for (const auto& status : array.status()) {
    values_[status.name() + "/level"] = std::to_string(status.level());
    values_[status.name() + "/message"] = status.message();
    for (const auto& kv : status.values()) {
      values_[status.name() + "/" + kv.key()] = kv.value();
    }
  }
}

std::string DiagnosticValues::find(const std::string& status_suffix, const std::string& key) const {
  return endingWith(values_, status_suffix, key);
}

Json toJson(const GridMapSummary& map) {
  return {
      {"frame_id", map.frame_id},
      {"stamp_ns", map.stamp_ns},
      {"resolution", map.resolution},
      {"length_x", map.length_x},
      {"length_y", map.length_y},
      {"centre_x", map.centre_x},
      {"centre_y", map.centre_y},
      {"layers", map.layers},
      {"basic_layers", map.basic_layers},
      {"dim_labels", map.dim_labels},
      {"dim_sizes", map.dim_sizes},
      {"dim_strides", map.dim_strides},
      {"layer_sizes", map.layer_sizes},
      {"surface_cells", map.surface_cells},
      {"surface_elevation_median", map.surface_elevation_median},
  };
}

Json toJson(const CostmapSummary& costmap) {
  return {
      {"frame_id", costmap.frame_id},     {"stamp_ns", costmap.stamp_ns},
      {"width", costmap.width},           {"height", costmap.height},
      {"resolution", costmap.resolution}, {"origin_x", costmap.origin_x},
      {"origin_y", costmap.origin_y},     {"cells", costmap.cells},
      {"unknown", costmap.unknown},       {"free", costmap.free},
      {"costed", costmap.costed},         {"lethal", costmap.lethal},
      {"invalid", costmap.invalid},
  };
}

Json toJson(const DiagnosticValues& values) {
  Json o = Json::object();
  // The diagnostics carry numbers as text; these are all counts.
  const auto count = [&](const char* status, const char* key) {
    const std::string text = values.find(status, key);
    char* end = nullptr;
    const double value = text.empty() ? -1.0 : std::strtod(text.c_str(), &end);
    o[key] = std::llround((end != nullptr && *end != '\0') ? -1.0 : value);
  };
  for (const char* key : {"scans_integrated", "clouds_received", "clouds_malformed",
                          "pose_publishers", "poses_received", "tf_static_edges"}) {
    count(": pipeline", key);
  }
  for (const char* key : {"maps_published", "costmaps_published"}) {
    count(": height map", key);
  }
  return o;
}

}  // namespace raymap::fastdds_peer
