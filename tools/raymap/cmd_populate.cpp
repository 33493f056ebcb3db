// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate`: build a map from a recorded file.
#include <cstdio>
#include <memory>

#include "src/io/atomic_file.hpp"
#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/populate.hpp"

namespace raymap::cli {
namespace {

struct PopulateFlags {
  std::string input;
  MappingFlags mapping;
  std::string output;
  std::string ply;
  std::string stats_json;
  bool quiet = false;
};

Expected<void, Error> writeText(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::fputs(text.c_str(), stdout);
    std::fputc('\n', stdout);
    return {};
  }
  auto writer = io::AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = writer->write(text + "\n"); !ok) {
    return ok;
  }
  return writer->commit();
}

void printSummary(const PopulateReport& r, const PopulateOptions& o) {
  const double rate = r.integrate_seconds > 0
                          ? static_cast<double>(r.rays.rays_accepted) / r.integrate_seconds
                          : 0.0;
  std::printf("input          %s\n", o.input.c_str());
  std::printf("rays           %s in, %s integrated, %s rejected",
              withCommas(r.rays.rays_in).c_str(), withCommas(r.rays.rays_accepted).c_str(),
              withCommas(r.rays.rejected()).c_str());
  if (r.rays.rejected() > 0) {
    std::printf(" (invalid %s, too short %s, out of bounds %s)",
                withCommas(r.rays.rays_invalid).c_str(), withCommas(r.rays.rays_too_short).c_str(),
                withCommas(r.rays.rays_out_of_bounds).c_str());
  }
  std::printf("\n               %s clipped to max range, %s without return, %s scans\n",
              withCommas(r.rays.rays_clipped).c_str(), withCommas(r.rays.rays_no_return).c_str(),
              withCommas(r.scans).c_str());
  std::printf("map            %s free, %s occupied voxels in %s regions (%.3g m, %s semantics)\n",
              withCommas(r.summary.voxels_free).c_str(),
              withCommas(r.summary.voxels_occupied).c_str(), withCommas(r.summary.regions).c_str(),
              o.map.geometry.resolution, toString(o.map.semantics));
  std::printf("integration    %.3f s, %.3g M rays/s (%s, %u threads); reading %.3f s\n",
              r.integrate_seconds, rate / 1e6, r.backend_name.c_str(), r.threads, r.read_seconds);
}

int runPopulate(const PopulateFlags& f) {
  const char* command = "populate";
  auto options = toPopulateOptions(f.input, f.mapping);
  if (!options) {
    printError(command, options.error().message);
    return kExitUsage;
  }
  options->progress = !f.quiet;
  std::string output = f.output;
  if (output.empty() && f.ply.empty() && f.stats_json.empty()) {
    printError(command,
               "nothing to write: give --output MAP, --ply CLOUD.ply or --stats-json FILE");
    return kExitUsage;
  }
  // Fail on unwritable outputs before spending minutes on the input.
  for (const auto& [path, name] : {std::pair{output, "--output"}, std::pair{f.ply, "--ply"},
                                   std::pair{f.stats_json, "--stats-json"}}) {
    if (!path.empty() && path != "-") {
      if (auto ok = checkWritable(path, name); !ok) {
        printError(command, ok.error().message);
        return kExitFailure;
      }
    }
  }
  auto map = VoxelMap::create(options->map);
  if (!map) {
    printError(command, map.error().message);
    return kExitFailure;
  }
  auto report = populateFromFile(*map, *options);
  if (!report) {
    printError(command, report.error().message);
    return kExitFailure;
  }
  if (!output.empty()) {
    if (auto ok = io::saveMap(*map, output); !ok) {
      printError(command, ok.error().message);
      return kExitFailure;
    }
  }
  if (!f.ply.empty()) {
    auto count = io::exportPly(*map, io::ExportMode::kOccupied, f.ply);
    if (!count) {
      printError(command, count.error().message);
      return kExitFailure;
    }
  }
  if (!f.stats_json.empty()) {
    if (auto ok = writeText(f.stats_json, statsJson(*report, *options)); !ok) {
      printError(command, ok.error().message);
      return kExitFailure;
    }
  }
  if (!f.quiet) {
    printSummary(*report, *options);
    if (!output.empty()) {
      std::printf("map file       %s\n", output.c_str());
    }
    if (!f.ply.empty()) {
      std::printf("point cloud    %s (occupied voxels at their voxel mean)\n", f.ply.c_str());
    }
  }
  return kExitOk;
}

}  // namespace

void printError(const std::string& command, const std::string& message) {
  std::fprintf(stderr, "raymap %s: error: %s\n", command.c_str(), message.c_str());
}

std::string withCommas(std::uint64_t value) {
  std::string digits = std::to_string(value);
  std::string out;
  const std::size_t n = digits.size();
  for (std::size_t i = 0; i < n; ++i) {
    out += digits[i];
    if ((n - i - 1) % 3 == 0 && i + 1 < n) {
      out += ',';
    }
  }
  return out;
}

void addPopulateCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<PopulateFlags>();
  CLI::App* c = app.add_subcommand(
      "populate", "Build an occupancy map from a ray-cloud PLY or a point cloud + trajectory");
  c->add_option("input", flags->input, "Input file (.ply or .ply.gz)")->required();
  addMappingOptions(*c, flags->mapping);
  c->add_option("-o,--output", flags->output, "Map file to write (.rmap)");
  c->add_option("--ply", flags->ply, "Also write the occupied voxels as a point-cloud PLY");
  c->add_option("--stats-json", flags->stats_json, "Write run statistics as JSON ('-' = stdout)");
  c->add_flag("-q,--quiet", flags->quiet, "No progress bar and no summary");
  c->callback([flags, exit_code] { *exit_code = runPopulate(*flags); });
}

}  // namespace raymap::cli
