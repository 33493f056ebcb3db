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

JsonObject toJson(const GridMapSummary& map) {
  JsonObject o;
  o.text("frame_id", map.frame_id)
      .integer("stamp_ns", map.stamp_ns)
      .number("resolution", map.resolution)
      .number("length_x", map.length_x)
      .number("length_y", map.length_y)
      .number("centre_x", map.centre_x)
      .number("centre_y", map.centre_y)
      .texts("layers", map.layers)
      .texts("basic_layers", map.basic_layers)
      .texts("dim_labels", map.dim_labels)
      .integers("dim_sizes", map.dim_sizes)
      .integers("dim_strides", map.dim_strides)
      .integers("layer_sizes", map.layer_sizes)
      .integer("surface_cells", map.surface_cells)
      .number("surface_elevation_median", map.surface_elevation_median);
  return o;
}

JsonObject toJson(const CostmapSummary& costmap) {
  JsonObject o;
  o.text("frame_id", costmap.frame_id)
      .integer("stamp_ns", costmap.stamp_ns)
      .integer("width", costmap.width)
      .integer("height", costmap.height)
      .number("resolution", costmap.resolution)
      .number("origin_x", costmap.origin_x)
      .number("origin_y", costmap.origin_y)
      .integer("cells", costmap.cells)
      .integer("unknown", costmap.unknown)
      .integer("free", costmap.free)
      .integer("costed", costmap.costed)
      .integer("lethal", costmap.lethal)
      .integer("invalid", costmap.invalid);
  return o;
}

JsonObject toJson(const DiagnosticValues& values) {
  JsonObject o;
  const auto number = [&](const char* status, const char* key) {
    const std::string text = values.find(status, key);
    char* end = nullptr;
    const double value = text.empty() ? -1.0 : std::strtod(text.c_str(), &end);
    o.number(key, (end != nullptr && *end != '\0') ? -1.0 : value);
  };
  for (const char* key : {"scans_integrated", "clouds_received", "clouds_malformed",
                          "pose_publishers", "poses_received", "tf_static_edges"}) {
    number(": pipeline", key);
  }
  for (const char* key : {"maps_published", "costmaps_published"}) {
    number(": height map", key);
  }
  return o;
}

}  // namespace raymap::fastdds_peer
