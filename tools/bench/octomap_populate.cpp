// SPDX-License-Identifier: BSD-3-Clause
// raymap-octomap: integrates an input with OctoMap and prints raymap's stats JSON keys, so both
// mappers run side by side on the same rays (docs/benchmarks.md).
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "platform/process.hpp"
#include "src/io/map_file.hpp"
#include "src/io/ray_source.hpp"
#include "tools/bench/octomap_reference.hpp"
#include "tools/raymap/json_output.hpp"

namespace {

using namespace raymap;

/// Feeds the input to `reference` whole scans at a time (insertPointCloud needs them); per-ray
/// input is fed in the same chunks.
Expected<void, Error> integrateInput(const std::string& input, const std::string& trajectory,
                                     double scan_period, bench::OctomapReference& reference) {
  io::RaySourceOptions source_options;
  source_options.trajectory_path = trajectory;
  source_options.scan_period_s = scan_period;
  auto source = io::openRaySource(input, source_options);
  if (!source) {
    return Unexpected(source.error());
  }
  std::vector<Ray> chunk(1u << 16);
  std::vector<Ray> scan;
  for (;;) {
    auto n = (*source)->read(chunk);
    if (!n) {
      return Unexpected(n.error());
    }
    for (std::size_t i = 0; i < *n; ++i) {
      if (!scan.empty() && chunk[i].scan != scan.front().scan) {
        reference.integrate(scan);
        scan.clear();
      }
      scan.push_back(chunk[i]);
    }
    if (*n == 0) {
      break;
    }
  }
  reference.integrate(scan);
  return {};
}

int run(int argc, char** argv) {
  CLI::App app{"Integrate a ray file with OctoMap (reference for raymap benchmarks)",
               "raymap-octomap"};
  std::string input;
  std::string trajectory;
  std::string compare;
  std::string semantics = "ray";
  double scan_period = io::RaySourceOptions::kDefaultScanPeriod;
  bench::OctomapOptions options;
  std::optional<double> hit;
  std::optional<double> miss;
  app.add_option("input", input, "Input file (.ply or .ply.gz)")->required();
  app.add_option("--trajectory", trajectory, "Point clouds: sensor trajectory");
  app.add_option("--scan-period", scan_period, "Seconds per scan without a 'scan' property");
  app.add_option("--resolution", options.resolution, "Voxel edge, metres")->capture_default_str();
  app.add_option("--min-range", options.min_range_m, "Drop shorter rays, metres");
  app.add_option("--max-range", options.max_range_m, "Clip longer rays, metres (0 = none)");
  app.add_option("--hit", hit, "Hit probability (default 0.7, OctoMap's)");
  app.add_option("--miss", miss, "Miss probability (default 0.4, OctoMap's)");
  app.add_option("--semantics", semantics,
                 "ray: insertRay per ray; scan: insertPointCloud per scan")
      ->check(CLI::IsMember({"ray", "scan"}));
  app.add_option("--compare", compare, "A raymap map of the same input: report voxel agreement");
  CLI11_PARSE(app, argc, argv);
  if (hit) {
    options.occupancy.hit = logOdds(*hit);
  }
  if (miss) {
    options.occupancy.miss = logOdds(*miss);
  }
  options.semantics = semantics == "scan" ? Semantics::kPerScan : Semantics::kPerRay;

  bench::OctomapReference reference(options);
  if (auto ok = integrateInput(input, trajectory, scan_period, reference); !ok) {
    std::fprintf(stderr, "raymap-octomap: error: %s\n", ok.error().message.c_str());
    return 1;
  }
  const bench::OctomapCounts c = reference.counts();
  cli::Json j = {
      {"input", input},
      {"mapper", "octomap"},
      {"semantics", semantics},
      {"resolution", options.resolution},
      {"min_range", options.min_range_m},
      {"max_range", options.max_range_m},
      {"hit_probability", probability(options.occupancy.hit)},
      {"miss_probability", probability(options.occupancy.miss)},
      {"rays_in", c.rays_in},
      {"rays_integrated", c.rays_integrated},
      {"rays_rejected", c.rays_rejected},
      {"rays_skipped_no_return", c.rays_skipped_no_return},
      {"integrate_seconds", c.integrate_seconds},
      {"rays_per_second", c.integrate_seconds > 0
                              ? static_cast<double>(c.rays_integrated) / c.integrate_seconds
                              : 0.0},
      {"voxels_free", c.voxels_free},
      {"voxels_occupied", c.voxels_occupied},
      {"backend", "octomap"},
      {"threads", 1},
      {"updates_dropped", 0},
      {"peak_rss_bytes", platform::peakResidentBytes()},
  };
  if (!compare.empty()) {
    auto map = io::loadMap(compare);
    if (!map) {
      std::fprintf(stderr, "raymap-octomap: error: %s\n", map.error().message.c_str());
      return 1;
    }
    const bench::Agreement a = reference.compare(*map);
    j["compared_voxels"] = a.compared;
    j["same_state"] = a.same;
    j["only_raymap"] = a.only_raymap;
    j["only_octomap"] = a.only_octomap;
    j["agreement"] = a.fraction();
  }
  std::printf("%s\n", cli::dumpJson(j).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return run(argc, argv); }
