// SPDX-License-Identifier: BSD-3-Clause
// `raymap info`: parameters, layers and voxel counts of a map file.
#include <cstdio>
#include <memory>
#include <string>

#include "src/bag/bag_reader.hpp"
#include "src/io/map_file.hpp"
#include "src/map/decay_summary.hpp"
#include "src/map/tsdf_surface.hpp"
#include "tools/raymap/bag_info.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/memory_tiers.hpp"

namespace raymap::cli {
namespace {

struct InfoFlags {
  std::string map;
  bool json = false;
  bool read_all = false;            ///< bags: count by reading every message, even with a summary
  std::string max_memory = "4GiB";  ///< a larger map streams through the tiers
  TierFlags tiers;
};

Json vectorJson(Vec3d v) { return {v.x, v.y, v.z}; }

/// The NDT parameters as stored, plus the adaptation rate in effect (given or derived).
Json ndtJson(const MapConfig& c) {
  const NdtParams& n = c.ndt;
  return {
      {"sensor_noise_m", n.sensor_noise},
      {"regulariser_voxels", n.regulariser},
      {"sample_threshold", n.sample_threshold},
      {"reinit_probability", n.reinit_probability},
      {"reinit_count", n.reinit_count},
      {"adaptation_rate", n.adaptationRate(c.occupancy)},
      {"adaptation_rate_source", n.adaptation_rate ? "given" : "from miss probability"},
      {"initial_intensity_variance", n.initial_intensity_variance},
  };
}

void printNdt(const MapConfig& c) {
  const NdtParams& n = c.ndt;
  std::printf(
      "ndt            sensor noise %g m, regulariser %g voxel, sample threshold %u, "
      "adaptation rate %g (%s)\n",
      n.sensor_noise, n.regulariser, n.sample_threshold, n.adaptationRate(c.occupancy),
      n.adaptation_rate ? "given" : "from miss probability");
  std::printf("               reinitialise below p = %g after %u samples", n.reinit_probability,
              n.reinit_count);
  if (c.mode == MapMode::kNdtTm) {
    std::printf("; initial intensity variance %g", n.initial_intensity_variance);
  }
  std::printf("\n");
}

/// Everything `info` reports of a map file, counted before anything is printed.
struct MapReport {
  std::uint32_t version = 0;
  MapSummary summary;
  TsdfSummary tsdf;
  DecaySummary decay;
  std::optional<TierReport> tiers;  ///< only when the tiers moved regions
};

/// Counts the map (a tiered map that cannot read a region back fails instead of printing counts
/// that leave it out); prints why not.
std::optional<MapReport> reportMap(const std::string& path, std::uint32_t version, VoxelMap& map) {
  const MapConfig& c = map.config();
  MapReport r;
  r.version = version;
  r.summary = map.summarise();
  r.tsdf = c.mode == MapMode::kTsdf ? summariseTsdf(map) : TsdfSummary{};
  r.decay = c.decay_rate ? summariseDecay(map) : DecaySummary{};
  if (auto ok = map.drainTiers(); !ok) {
    printError("info", path + ": " + ok.error().message);
    return std::nullopt;
  }
  if (auto ok = checkTiers(map); !ok) {
    printError("info", path + ": " + ok.error().message);
    return std::nullopt;
  }
  r.tiers = tierReport(map);
  if (r.tiers && r.tiers->stats.evictions == 0) {
    r.tiers.reset();
  }
  return r;
}

Json occupancyJson(const OccupancyParams& o) {
  return {
      {"hit_probability", probability(o.hit)},
      {"miss_probability", probability(o.miss)},
      {"clamp_min_probability", probability(o.clamp_min)},
      {"clamp_max_probability", probability(o.clamp_max)},
      {"threshold_probability", probability(o.threshold)},
      {"hit_log_odds", o.hit},
      {"miss_log_odds", o.miss},
      {"clamp_min_log_odds", o.clamp_min},
      {"clamp_max_log_odds", o.clamp_max},
      {"threshold_log_odds", o.threshold},
  };
}

/// The saved layers' names, and their details.
std::pair<Json, Json> layersJson(const LayerSchema& schema) {
  Json names = Json::array();
  Json details = Json::array();
  for (int i = 0; i < schema.size(); ++i) {
    if (schema.at(i).saved) {
      names.push_back(schema.at(i).name);
      details.push_back(Json{
          {"name", schema.at(i).name},
          {"bytes_per_voxel", schema.at(i).bytes_per_voxel},
          {"version", unsigned{schema.at(i).version}},
      });
    }
  }
  return {names, details};
}

/// The mode's own parameters and counts (NDT, TSDF, decay) into `j`.
void addModeJson(const MapConfig& c, const MapReport& r, Json& j) {
  if (isNdt(c.mode)) {
    j["ndt"] = ndtJson(c);
  }
  if (c.mode == MapMode::kTsdf) {
    j["tsdf"] = {
        {"truncation_m", c.tsdf.truncationMetres(c.geometry.resolution)},
        {"max_weight", c.tsdf.max_weight},
        {"dropoff_m", c.tsdf.dropoffMetres(c.geometry.resolution)},
        {"voxels_updated", r.tsdf.updated},
        {"voxels_behind_surface", r.tsdf.behind},
        {"voxels_at_max_weight", r.tsdf.saturated},
    };
  }
  if (c.decay_rate) {
    j["decay"] = {
        {"voxels_crossed", r.decay.crossed},
        {"voxels_with_samples", r.decay.with_samples},
        {"metres", r.decay.metres},
        {"samples", r.decay.samples},
    };
  }
}

void printInfoJson(const std::string& path, const VoxelMap& map, const MapReport& r) {
  const MapConfig& c = map.config();
  const LayerSchema& schema = map.store().schema();
  const auto [layer_names, layer_details] = layersJson(schema);
  Json info = Json::object();  // {} rather than null for a map without provenance
  for (const auto& [key, value] : map.info()) {
    info[key] = value;
  }
  Json j = {
      {"path", path},
      {"format_version", r.version},
      {"resolution", c.geometry.resolution},
      {"region_voxels", c.geometry.region_voxels},
      {"region_extent", c.geometry.regionExtent()},
      {"semantics", toString(c.semantics)},
      {"mode", mapModeName(c)},
      {"occupancy", occupancyJson(c.occupancy)},
      {"layers", layer_names},
      {"layer_details", layer_details},
  };
  addModeJson(c, r, j);
  const MapSummary& s = r.summary;
  j["regions"] = s.regions;
  j["memory_bytes"] = s.regions * schema.bytesPerRegion(c.geometry.voxelsPerRegion());
  j["voxels_free"] = s.voxels_free;
  j["voxels_occupied"] = s.voxels_occupied;
  j["voxels_unobserved"] = s.voxels_unobserved;
  if (s.voxels_free + s.voxels_occupied > 0) {
    j["extent_min"] = vectorJson(s.observed_min);
    j["extent_max"] = vectorJson(s.observed_max);
  }
  if (r.tiers) {
    j["memory_tiers"] = tierJson(*r.tiers);
  }
  j["info"] = info;
  std::printf("%s\n", dumpJson(j).c_str());
}

/// The mode's own parameters and counts (occupancy, NDT, TSDF, decay) as lines.
void printModeText(const MapConfig& c, const MapReport& r) {
  const OccupancyParams& o = c.occupancy;
  if (c.occupancy_layer) {
    std::printf(
        "occupancy      hit %.4g, miss %.4g, clamps %.4g / %.4g, threshold %.4g"
        " (log-odds %+.4f %+.4f %+.4f %+.4f %+.4f)\n",
        probability(o.hit), probability(o.miss), probability(o.clamp_min), probability(o.clamp_max),
        probability(o.threshold), static_cast<double>(o.hit), static_cast<double>(o.miss),
        static_cast<double>(o.clamp_min), static_cast<double>(o.clamp_max),
        static_cast<double>(o.threshold));
  }
  if (isNdt(c.mode)) {
    printNdt(c);
  }
  if (c.mode == MapMode::kTsdf) {
    std::printf("tsdf           truncation %g m, max weight %g, drop-off %g m\n",
                c.tsdf.truncationMetres(c.geometry.resolution), c.tsdf.max_weight,
                c.tsdf.dropoffMetres(c.geometry.resolution));
    std::printf("tsdf voxels    %s updated, %s behind the surface, %s at the max weight\n",
                withCommas(r.tsdf.updated).c_str(), withCommas(r.tsdf.behind).c_str(),
                withCommas(r.tsdf.saturated).c_str());
  }
  if (c.decay_rate) {
    std::printf("decay voxels   %s crossed, %s with samples; %.6g m of ray path, %s samples\n",
                withCommas(r.decay.crossed).c_str(), withCommas(r.decay.with_samples).c_str(),
                r.decay.metres, withCommas(r.decay.samples).c_str());
  }
}

void printInfoText(const std::string& path, const VoxelMap& map, const MapReport& r) {
  const MapConfig& c = map.config();
  const LayerSchema& schema = map.store().schema();
  std::string layers;
  for (int i = 0; i < schema.size(); ++i) {
    if (schema.at(i).saved) {
      layers += layers.empty() ? "" : ", ";
      layers += schema.at(i).name;
      layers += " (" + std::to_string(schema.at(i).bytes_per_voxel) + " B)";
    }
  }
  const MapSummary& s = r.summary;
  const std::uint64_t bytes_per_region = schema.bytesPerRegion(c.geometry.voxelsPerRegion());
  std::printf("map            %s (format %u)\n", path.c_str(), r.version);
  std::printf("resolution     %g m, regions of %d^3 voxels (%g m)\n", c.geometry.resolution,
              c.geometry.region_voxels, c.geometry.regionExtent());
  std::printf("semantics      %s\n", toString(c.semantics));
  std::printf("mode           %s\n", mapModeName(c).c_str());
  printModeText(c, r);
  std::printf("layers         %s per voxel\n", layers.c_str());
  std::printf("regions        %s (%.1f MiB in memory)\n", withCommas(s.regions).c_str(),
              static_cast<double>(s.regions * bytes_per_region) / (1024.0 * 1024.0));
  if (c.occupancy_layer) {
    std::printf("voxels         %s free, %s occupied, %s unobserved in stored regions\n",
                withCommas(s.voxels_free).c_str(), withCommas(s.voxels_occupied).c_str(),
                withCommas(s.voxels_unobserved).c_str());
  }
  if (s.voxels_free + s.voxels_occupied > 0) {
    std::printf("extent         [%.2f, %.2f, %.2f] to [%.2f, %.2f, %.2f] m\n", s.observed_min.x,
                s.observed_min.y, s.observed_min.z, s.observed_max.x, s.observed_max.y,
                s.observed_max.z);
  }
  if (r.tiers) {
    std::printf("memory tiers   %s\n", tierSummaryLine(*r.tiers).c_str());
  }
  for (const auto& [key, value] : map.info()) {
    std::printf("%-14s %s\n", key.c_str(), value.c_str());
  }
}

int runInfo(const InfoFlags& f) {
  if (bag::isBag(f.map)) {
    return runBagInfo(f.map, f.json, f.read_all);
  }
  auto header = io::readMapHeader(f.map);
  if (!header) {
    printError("info", header.error().message);
    return kExitFailure;
  }
  auto load = toLoadOptions(f.max_memory, f.tiers, "");
  if (!load) {
    printError("info", load.error().message);
    return kExitUsage;
  }
  auto map = io::loadMap(f.map, *load);
  if (!map) {
    printError("info", map.error().message);
    return kExitFailure;
  }
  const auto report = reportMap(f.map, header->format_version, *map);
  if (!report) {
    return kExitFailure;
  }
  if (f.json) {
    printInfoJson(f.map, *map, *report);
  } else {
    printInfoText(f.map, *map, *report);
  }
  return kExitOk;
}

}  // namespace

void addInfoCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<InfoFlags>();
  CLI::App* c = app.add_subcommand(
      "info", "Show a map's parameters, layers and voxel counts, or a bag's topics and counts");
  c->add_option("map", flags->map, "Map file (.rmap), or a rosbag2 bag (directory, .mcap, .db3)")
      ->required();
  c->add_flag("--json", flags->json, "Print JSON");
  c->add_flag("--read-all", flags->read_all,
              "Bags: count by reading every message (also gives bytes per topic), not from the "
              "MCAP summary");
  addMaxMemoryOption(*c, flags->max_memory);
  addTierOptions(*c, flags->tiers);
  c->callback([flags, exit_code] { *exit_code = runInfo(*flags); });
}

}  // namespace raymap::cli
