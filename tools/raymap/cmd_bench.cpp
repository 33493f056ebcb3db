// SPDX-License-Identifier: BSD-3-Clause
// `raymap bench`: integration throughput on a preloaded input, printed as JSON.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "platform/process.hpp"
#include "src/io/staged_outputs.hpp"
#include "src/mapper/recording.hpp"
#include "tools/raymap/bench_heightmaps.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/option_names.hpp"
#include "tools/raymap/populate.hpp"

namespace raymap::cli {
namespace {

constexpr const char* kDefaultSemanticsList = "ray,scan";

struct BenchFlags {
  std::string input;
  MappingFlags mapping;
  std::string threads_list = "1,0";
  std::string semantics_list = kDefaultSemanticsList;
  int repeat = 3;
  bool steady_state = false;
  std::string json;
  BenchHeightmapOptions heightmaps;
};

std::vector<std::string> splitComma(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    if (!part.empty()) {
      parts.push_back(part);
    }
  }
  return parts;
}

/// The whole input in memory: the benchmark measures preparation and integration, not file
/// decoding. Prints the error and returns false when the input cannot be read.
bool preloadRays(const std::string& input, const PopulateOptions& base, std::vector<Ray>& rays) {
  const char* command = "bench";
  auto recording = mapper::openRecording(input, base.recording);
  if (!recording) {
    printError(command, recording.error().message);
    return false;
  }
  io::RaySource* source = recording->source.get();
  std::vector<Ray> chunk(std::size_t{1} << 16);
  for (;;) {
    auto n = source->read(chunk);
    if (!n) {
      printError(command, n.error().message);
      return false;
    }
    if (*n == 0) {
      break;
    }
    rays.insert(rays.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(*n));
  }
  if (const std::string warning = inputWarning(base.map.mode, source->info()); !warning.empty()) {
    std::fprintf(stderr, "bench: warning: %s\n", withCliFlags(warning).c_str());
  }
  return true;
}

/// One run to time: a semantics and a thread count.
struct BenchRun {
  std::string semantics;
  unsigned threads = 0;
};

/// Every semantics × thread count to run, checked before any runs. NDT, TSDF and
/// decay-rate-only maps integrate per ray only: the default list shrinks to "ray"; an explicit
/// "scan" is an error rather than a silently skipped run. Thread counts apply to the CPU
/// backend; a device backend runs once per semantics. Prints the error and returns nothing on a
/// bad list.
std::optional<std::vector<BenchRun>> plannedRuns(const BenchFlags& f, const PopulateOptions& base) {
  const char* command = "bench";
  std::string semantics_list = f.semantics_list;
  const bool per_ray_only = isNdt(base.map.mode) || !base.map.occupancy_layer;
  if (per_ray_only && semantics_list == kDefaultSemanticsList) {
    semantics_list = "ray";
  }
  std::vector<BenchRun> runs;
  for (const std::string& semantics : splitComma(semantics_list)) {
    if (per_ray_only && semantics == "scan") {
      printError(command, "--semantics-list: --mode " + mapModeName(base.map) +
                              " maps need per-ray semantics; use --semantics-list ray");
      return std::nullopt;
    }
    if (semantics != "ray" && semantics != "scan") {
      printError(command, "--semantics-list: unknown semantics '" + semantics + "'");
      return std::nullopt;
    }
    const std::vector<std::string> thread_runs =
        base.backend.name == "cpu" ? splitComma(f.threads_list) : std::vector<std::string>{"1"};
    for (const std::string& threads_text : thread_runs) {
      try {
        runs.push_back({semantics, static_cast<unsigned>(std::stoul(threads_text))});
      } catch (const std::exception&) {
        printError(command, "--threads-list: '" + threads_text + "' is not a number");
        return std::nullopt;
      }
    }
  }
  return runs;
}

/// One timed pass over the preloaded rays through the same path as populate, after an untimed
/// one with --steady-state. In steady state both passes share one backend and one batcher, as a
/// service keeps them, so a device's region cache and the batch buffers stay warm too. With
/// height maps the backend is kept here too: the cycles run on it between batches.
Result<PopulateReport> timedPass(const BenchFlags& f, const PopulateOptions& options,
                                 const std::vector<Ray>& rays, BenchHeightmaps& cycles) {
  auto map = VoxelMap::create(options.map);
  if (!map) {
    return Unexpected(map.error());
  }
  StreamState shared;
  const bool keep_backend = f.steady_state || (f.heightmaps.every_rays > 0);
  auto pass = [&](bool timed) {
    std::size_t next = 0;
    return integrateStream(
        *map, options,
        [&](std::span<Ray> out) -> Result<std::size_t> {
          if (timed && next > 0 && shared.created.backend) {
            auto cycle = cycles.maybeGenerate(next, rays[next - 1].origin, *map,
                                              *shared.created.backend, options.backend);
            if (!cycle) {
              return Unexpected(cycle.error());
            }
          }
          std::size_t n = std::min(out.size(), rays.size() - next);
          if (f.heightmaps.every_rays > 0) {
            // Chunks end at the cycle instants, so that each comes after that many rays.
            const std::uint64_t every = f.heightmaps.every_rays;
            n = static_cast<std::size_t>(std::min<std::uint64_t>(n, every - next % every));
          }
          std::copy_n(rays.begin() + static_cast<std::ptrdiff_t>(next), n, out.begin());
          next += n;
          return n;
        },
        [&] { return static_cast<double>(next) / static_cast<double>(rays.size()); },
        keep_backend ? &shared : nullptr);
  };
  if (f.steady_state) {
    // Untimed first pass: the regions exist and their memory is paged in afterwards, as for a
    // robot working inside its (prefaulted) rolling window.
    if (auto warm = pass(false); !warm) {
      return Unexpected(warm.error());
    }
  }
  auto report = pass(true);
  if (report) {
    report->read_seconds -= cycles.seconds();  // the cycles ran inside the reads
  }
  return report;
}

/// --repeat timed passes of one run; the median pass's statistics as JSON (and its warnings
/// and a summary line on stderr).
Result<Json> benchRun(const BenchFlags& f, const PopulateOptions& base,
                      const std::vector<Ray>& rays, const BenchRun& run) {
  PopulateOptions options = base;
  options.map.semantics = run.semantics == "scan" ? Semantics::kPerScan : Semantics::kPerRay;
  options.map.device_scan_marks = options.backend.name != "cpu";  // the CPU keeps bits
  options.backend.threads = run.threads;
  std::vector<PopulateReport> reports;
  std::vector<Json> heightmap_json;  // per report, with --heightmap-every
  for (int r = 0; r < std::max(f.repeat, 1); ++r) {
    BenchHeightmaps cycles(f.heightmaps);
    auto report = timedPass(f, options, rays, cycles);
    if (!report) {
      return Unexpected(report.error());
    }
    reports.push_back(*report);
    heightmap_json.push_back(cycles.json(report->rays.rays_accepted, report->integrate_seconds));
  }
  std::vector<std::size_t> order(reports.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    order[k] = k;
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return reports[a].integrate_seconds < reports[b].integrate_seconds;
  });
  const std::size_t median_index = order[order.size() / 2];
  const PopulateReport& median = reports[median_index];
  Json json = statsJson(median, options);
  if (f.heightmaps.every_rays > 0) {
    json["heightmap_cycles"] = heightmap_json[median_index];  // the median run's cycles
  }
  for (const std::string* warning : {&median.fallback_warning, &median.startup_warning}) {
    if (!warning->empty()) {
      std::fprintf(stderr, "bench: warning: %s\n", withCliFlags(*warning).c_str());
    }
  }
  std::fprintf(stderr, "bench: %s semantics, %s, %u threads: %.3f s median of %zu, %.3g M rays/s\n",
               run.semantics.c_str(), median.backend_name.c_str(), median.threads,
               median.integrate_seconds, reports.size(),
               static_cast<double>(median.rays.rays_accepted) / median.integrate_seconds / 1e6);
  return json;
}

int runBench(const BenchFlags& f) {
  const char* command = "bench";
  auto base = toPopulateOptions(f.input, f.mapping);
  if (!base) {
    printError(command, base.error().message);
    return kExitUsage;
  }
  base->progress = false;
  io::StagedOutputs staged(command);
  staged.input(f.input, "the input");
  staged.input(f.mapping.trajectory, "--trajectory");
  std::string json_temp;
  if (!f.json.empty() && f.json != "-") {
    auto temp = staged.add(f.json, "--json");
    if (!temp) {
      printError(command, temp.error().message);
      return exitCodeFor(temp.error());
    }
    json_temp = std::move(*temp);
  }
  const auto planned = plannedRuns(f, *base);
  if (!planned) {
    return kExitUsage;
  }
  std::vector<Ray> rays;
  if (!preloadRays(f.input, *base, rays)) {
    return kExitFailure;
  }
  Json runs = Json::array();
  for (const BenchRun& run : *planned) {
    auto json = benchRun(f, *base, rays, run);
    if (!json) {
      printError(command, json.error().message);
      return kExitFailure;
    }
    runs.push_back(std::move(*json));
  }
  const Json result = {
      {"benchmark", "raymap bench"},
      {"repeat", f.repeat},
      {"machine", {{"cpu_model", platform::cpuModelName()}, {"cores", platform::availableCores()}}},
      {"runs", runs},
  };
  if (f.json.empty() || f.json == "-") {
    std::printf("%s\n", dumpJson(result).c_str());
    return kExitOk;
  }
  if (auto ok = writeTextFile(json_temp, dumpJson(result)); !ok) {
    printError(command, "--json: " + ok.error().message);
    return kExitFailure;
  }
  if (auto ok = staged.commit(); !ok) {
    printError(command, ok.error().message);
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void addBenchCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<BenchFlags>();
  CLI::App* c = app.add_subcommand(
      "bench", "Measure integration throughput on a preloaded input (prints JSON)");
  c->add_option("input", flags->input, "Input file (.ply or .ply.gz)")->required();
  addMappingOptions(*c, flags->mapping);
  c->add_option("--threads-list", flags->threads_list, "Thread counts to run, e.g. 1,2,0 (0 = all)")
      ->capture_default_str();
  c->add_option("--semantics-list", flags->semantics_list,
                "Semantics to run: ray, scan or both (NDT and TSDF --mode: ray only)")
      ->capture_default_str();
  c->add_option("--repeat", flags->repeat, "Runs per configuration (the median is reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  c->add_option("--json", flags->json, "Write the JSON here instead of stdout");
  c->add_flag("--steady-state", flags->steady_state,
              "Integrate the input once untimed first, so no region is created or paged in "
              "during the timed pass");
  c->add_option("--heightmap-every", flags->heightmaps.every_rays,
                "Generate a planar height map around the sensor each time this many more rays "
                "were read, between batches as raymapd's cycle does (0: none)")
      ->capture_default_str();
  c->add_option("--heightmap-size", flags->heightmaps.size_m, "Side of those height maps, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  c->add_flag("--heightmap-from-host", flags->heightmaps.from_host,
              "Device backends: synchronise and generate from the host store with a generator of "
              "its own (the path before one device context), for comparison");
  c->callback([c, flags, exit_code] {
    // --semantics and --threads, the mapping commands' options, name one run each: on their own
    // they are the bench's list; beside the list option they are refused rather than ignored.
    if (c->count("--semantics") > 0) {
      if (c->count("--semantics-list") > 0) {
        printError("bench", "--semantics: give --semantics or --semantics-list, not both");
        *exit_code = kExitUsage;
        return;
      }
      flags->semantics_list = flags->mapping.semantics;
    }
    if (c->count("--threads") > 0) {
      if (c->count("--threads-list") > 0) {
        printError("bench", "--threads: give --threads or --threads-list, not both");
        *exit_code = kExitUsage;
        return;
      }
      flags->threads_list = std::to_string(flags->mapping.threads);
    }
    *exit_code = runBench(*flags);
  });
}

}  // namespace raymap::cli
