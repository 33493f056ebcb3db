// SPDX-License-Identifier: BSD-3-Clause
// `raymap heightmap` end to end on the simulated stairs: the PNG and CSV it writes, its modes and
// JSON summary, device backends against the CPU, and its errors.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/map_file.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

constexpr int kCells = 80;  // --size 8 at the map's 0.1 m
/// The stair treads are at 0.17 m steps; measured surfaces are within a voxel of them.
constexpr double kTreadTolerance = 0.1;
/// Cell centres are written with 4 decimals.
constexpr double kCsvCoordTolerance = 1e-3;

/// The stairs scene (config/scenes/stairs.yaml), 5 scans simulated and mapped once per process;
/// empty (and a test failure) when either step fails.
const std::string& stairsMap() {
  static TempDir dir;
  static const std::string map = [] {
    const std::string rays = dir.file("stairs.ply");
    const std::string path = dir.file("stairs.rmap");
    const RunResult simulated =
        runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml", "--scans", "5",
                   "--rays", rays, "-q"});
    if (simulated.exit_code != 0) {
      ADD_FAILURE() << "simulate: " << describe(simulated);
      return std::string();
    }
    const RunResult populated = runRaymap({"populate", rays, "--output", path, "-q"});
    if (populated.exit_code != 0) {
      ADD_FAILURE() << "populate: " << describe(populated);
      return std::string();
    }
    return path;
  }();
  return map;
}

/// The request most tests make: 8 m around the origin at ground height.
std::vector<std::string> aroundTheOrigin(const std::string& map) {
  return {"heightmap", map, "--center", "0,0,0", "--size", "8"};
}

/// One data line of the CSV.
struct CsvCell {
  double x = 0.0;
  double y = 0.0;
  double elevation = 0.0;
  double clearance = 0.0;
  std::string kind;
};

/// The CSV's data lines (the header is checked by the caller); a malformed line fails the test.
std::vector<CsvCell> parseCsv(const std::string& text) {
  std::vector<CsvCell> cells;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    std::istringstream words(line);
    while (std::getline(words, field, ',')) {
      fields.push_back(field);
    }
    if (fields.size() != 5) {
      ADD_FAILURE() << "not 5 fields: " << line;
      continue;
    }
    CsvCell c;
    c.x = std::strtod(fields[0].c_str(), nullptr);
    c.y = std::strtod(fields[1].c_str(), nullptr);
    c.elevation = std::strtod(fields[2].c_str(), nullptr);  // strtod reads "nan" and "inf"
    c.clearance = std::strtod(fields[3].c_str(), nullptr);
    c.kind = fields[4];
    cells.push_back(std::move(c));
  }
  return cells;
}

std::optional<CsvCell> cellAt(const std::vector<CsvCell>& cells, double x, double y) {
  for (const CsvCell& c : cells) {
    if (std::fabs(c.x - x) < kCsvCoordTolerance && std::fabs(c.y - y) < kCsvCoordTolerance) {
      return c;
    }
  }
  return std::nullopt;
}

std::map<std::string, int> kindCounts(const std::vector<CsvCell>& cells) {
  std::map<std::string, int> counts;
  for (const CsvCell& c : cells) {
    counts[c.kind] += 1;
  }
  return counts;
}

/// The first three treads (the lidar at the foot of the flight sees them from above) are surfaces
/// at 0.17, 0.34 and 0.51 m, mid-tread on the stairs' centre line; the ground at the origin is at
/// 0.
void expectStairsAndGround(const std::vector<CsvCell>& cells) {
  const std::pair<double, double> expected[] = {
      {2.15, 0.17}, {2.45, 0.34}, {2.75, 0.51}, {0.05, 0.0}};
  for (const auto& [x, elevation] : expected) {
    SCOPED_TRACE(::testing::Message() << "x = " << x);
    const std::optional<CsvCell> c = cellAt(cells, x, 0.05);
    ASSERT_TRUE(c.has_value());
    EXPECT_EQ(c->kind, "surface");
    EXPECT_NEAR(c->elevation, elevation, kTreadTolerance);
  }
}

/// The CSV of `device` equals the CPU's byte for byte, planar and fill with virtual surfaces
/// (the column search is the same code on both, exact in float).
void expectDeviceCsvMatchesTheCpu(const std::string& device) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::vector<std::vector<std::string>> variants = {{},
                                                          {"--mode", "fill", "--virtual-surfaces"}};
  for (std::size_t v = 0; v < variants.size(); ++v) {
    SCOPED_TRACE(v);
    std::string csv[2];
    const std::string backends[2] = {"cpu", device};
    for (int b = 0; b < 2; ++b) {
      const std::string path = dir.file(backends[b] + std::to_string(v) + ".csv");
      const RunResult r =
          runRaymap(concat(aroundTheOrigin(map),
                           concat(variants[v], {"--backend", backends[b], "--csv", path, "-q"})));
      ASSERT_EQ(r.exit_code, 0) << backends[b] << ": " << describe(r);
      csv[b] = readFile(path);
    }
    ASSERT_FALSE(csv[0].empty());
    EXPECT_TRUE(csv[0] == csv[1]) << device << " differs from the CPU";
  }
}

// ---------------------------------------------------------------------------------------------
// What it writes

TEST(CliHeightmap, WritesAPngAndACsvWithTheStairTreads) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string png = dir.file("stairs.png");
  const std::string csv = dir.file("stairs.csv");

  const RunResult r = runRaymap(concat(aroundTheOrigin(map), {"--png", png, "--csv", csv}));

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "80 x 80 cells")) << r.out;
  const std::string image = readFile(png);
  ASSERT_GE(image.size(), 24u);
  EXPECT_EQ(image.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(image.substr(12, 4), "IHDR");
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      v = (v << 8) | static_cast<unsigned char>(image[at + k]);
    }
    return v;
  };
  // 80 cells drawn at least 400 pixels wide (several pixels a cell), plus the legend.
  EXPECT_GE(be32(16), 400u);
  EXPECT_LE(be32(16), 4000u);
  EXPECT_GE(be32(20), 400u);
  EXPECT_LE(be32(20), 4000u);
  EXPECT_GT(image.size(), 1000u);

  const std::string text = readFile(csv);
  ASSERT_EQ(text.substr(0, text.find('\n') + 1), "x,y,elevation,clearance,kind\n");
  const std::vector<CsvCell> cells = parseCsv(text);
  ASSERT_EQ(cells.size(), static_cast<std::size_t>(kCells * kCells));
  for (const auto& [kind, n] : kindCounts(cells)) {
    EXPECT_TRUE(kind == "surface" || kind == "virtual" || kind == "vacant" || kind == "unknown")
        << kind;
  }
  for (const CsvCell& c : cells) {
    ASSERT_LT(std::fabs(c.x), 4.0);
    ASSERT_LT(std::fabs(c.y), 4.0);
    if (c.kind == "surface") {
      ASSERT_TRUE(std::isfinite(c.elevation)) << c.x << ", " << c.y;
    } else if (c.kind != "virtual") {
      ASSERT_TRUE(std::isnan(c.elevation)) << c.x << ", " << c.y;
    }
  }
  expectStairsAndGround(cells);
  EXPECT_EQ(kindCounts(cells)["virtual"], 0);  // not asked for
}

TEST(CliHeightmap, FillModeFollowsTheStairs) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string csv = dir.file("fill.csv");

  const RunResult r = runRaymap(concat(aroundTheOrigin(map), {"--mode", "fill", "--csv", csv}));

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "fill mode")) << r.out;
  const std::vector<CsvCell> cells = parseCsv(readFile(csv));
  ASSERT_EQ(cells.size(), static_cast<std::size_t>(kCells * kCells));
  expectStairsAndGround(cells);
}

TEST(CliHeightmap, VirtualSurfacesAreReportedWhenAskedFor) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string csv = dir.file("virtual.csv");

  const RunResult r = runRaymap(concat(aroundTheOrigin(map), {"--virtual-surfaces", "--csv", csv}));

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<CsvCell> cells = parseCsv(readFile(csv));
  ASSERT_EQ(cells.size(), static_cast<std::size_t>(kCells * kCells));
  EXPECT_GT(kindCounts(cells)["virtual"], 0);
  for (const CsvCell& c : cells) {
    if (c.kind == "virtual") {
      ASSERT_TRUE(std::isfinite(c.elevation)) << c.x << ", " << c.y;
    }
  }
  expectStairsAndGround(cells);
}

TEST(CliHeightmap, JsonSummaryAgreesWithTheCsv) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string csv = dir.file("cells.csv");

  const RunResult r =
      runRaymap(concat(aroundTheOrigin(map), {"--json", "--repeat", "3", "--csv", csv}));

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::string& json = r.out;
  ASSERT_FALSE(json.empty());
  EXPECT_EQ(json.front(), '{') << json;
  EXPECT_EQ(json.substr(json.find_last_not_of('\n'), 1), "}") << json;
  EXPECT_EQ(std::count(json.begin(), json.end(), '{'), std::count(json.begin(), json.end(), '}'));
  EXPECT_EQ(std::count(json.begin(), json.end(), '"') % 2, 0);
  EXPECT_EQ(jsonValue(json, "backend"), std::optional<std::string>("cpu"));
  EXPECT_EQ(jsonValue(json, "mode"), std::optional<std::string>("planar"));
  EXPECT_EQ(jsonValue(json, "cells_x"), std::optional<std::string>("80"));
  EXPECT_EQ(jsonValue(json, "cells_y"), std::optional<std::string>("80"));
  EXPECT_EQ(jsonValue(json, "repeat"), std::optional<std::string>("3"));
  const std::optional<std::string> seconds = jsonValue(json, "seconds_median");
  ASSERT_TRUE(seconds.has_value()) << json;
  const double median = std::strtod(seconds->c_str(), nullptr);
  EXPECT_GE(median, 0.0);
  EXPECT_LT(median, 10.0);
  const std::map<std::string, int> counts = kindCounts(parseCsv(readFile(csv)));
  for (const char* kind : {"surface", "virtual", "vacant", "unknown"}) {
    SCOPED_TRACE(kind);
    const auto found = counts.find(kind);
    const int n = found == counts.end() ? 0 : found->second;
    EXPECT_EQ(jsonValue(json, std::string(kind) + "_cells"), std::optional(std::to_string(n)));
  }
}

// ---------------------------------------------------------------------------------------------
// Device backends

TEST(CliHeightmap, OpenClGivesTheCpuCsvByteForByte) {
  if (const std::string why = deviceUnavailable("opencl"); !why.empty()) {
    GTEST_SKIP() << why;
  }
  expectDeviceCsvMatchesTheCpu("opencl");
}

TEST(CliHeightmap, CudaGivesTheCpuCsvByteForByte) {
  if (const std::string why = deviceUnavailable("cuda"); !why.empty()) {
    GTEST_SKIP() << why;
  }
  expectDeviceCsvMatchesTheCpu("cuda");
}

TEST(CliHeightmap, CudaWithoutADeviceFailsUnlessTheCpuFallbackIsAllowed) {
  if (deviceUnavailable("cuda").empty()) {
    GTEST_SKIP() << "a CUDA device is present";
  }
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string csv = dir.file("cuda.csv");
  const std::string cpu_csv = dir.file("cpu.csv");

  const RunResult refused =
      runRaymap(concat(aroundTheOrigin(map), {"--backend", "cuda", "--csv", csv}));
  const RunResult fallen_back = runRaymap(
      concat(aroundTheOrigin(map), {"--backend", "cuda", "--fallback", "cpu", "--csv", csv}));
  const RunResult cpu = runRaymap(concat(aroundTheOrigin(map), {"--csv", cpu_csv, "-q"}));

  EXPECT_EQ(refused.exit_code, 1) << describe(refused);
  EXPECT_TRUE(contains(refused.err, "--backend cuda")) << refused.err;
  EXPECT_TRUE(contains(refused.err, "--fallback cpu")) << refused.err;  // how to go on anyway
  EXPECT_FALSE(contains(refused.err, "backend.")) << refused.err;  // the library's keys, as flags
  EXPECT_TRUE(refused.out.empty()) << refused.out;
  ASSERT_EQ(fallen_back.exit_code, 0) << describe(fallen_back);
  EXPECT_TRUE(contains(fallen_back.err, "warning")) << fallen_back.err;
  EXPECT_TRUE(contains(fallen_back.err, "falling back to the CPU")) << fallen_back.err;
  ASSERT_EQ(cpu.exit_code, 0) << describe(cpu);
  EXPECT_TRUE(readFile(csv) == readFile(cpu_csv)) << "the fallback differs from --backend cpu";
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST(CliHeightmap, CentreOutsideTheMapNamesTheMapFile) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());

  const RunResult r = runRaymap({"heightmap", map, "--center", "500,0,0", "--size", "8"});

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, map)) << r.err;
  EXPECT_TRUE(contains(r.err, "--center 500,0,0: outside the map")) << r.err;
  EXPECT_FALSE(contains(r.err, "heightmap.centre")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(CliHeightmap, UnknownModeIsAUsageError) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());

  const RunResult r = runRaymap(concat(aroundTheOrigin(map), {"--mode", "sideways"}));

  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "--mode")) << r.err;
  EXPECT_TRUE(contains(r.err, "sideways")) << r.err;
}

TEST(CliHeightmap, ZeroSizeNamesTheOption) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());

  const RunResult r = runRaymap({"heightmap", map, "--center", "0,0,0", "--size", "0"});

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "--size 0: must be a finite size")) << r.err;
  EXPECT_TRUE(contains(r.err, "resolution")) << r.err;
  EXPECT_FALSE(contains(r.err, "heightmap.size")) << r.err;
}

TEST(CliHeightmap, MissingMapFileIsNamed) {
  TempDir dir;
  const std::string missing = dir.file("no-such-map.rmap");

  const RunResult r = runRaymap({"heightmap", missing, "--center", "0,0,0"});

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, missing)) << r.err;
}

TEST(CliHeightmap, UnwritablePngFailsBeforeAnyWork) {
  const std::string& map = stairsMap();
  ASSERT_FALSE(map.empty());
  TempDir dir;
  const std::string png = dir.file("missing-dir/out.png");
  const std::string csv = dir.file("out.csv");

  const RunResult r = runRaymap(concat(aroundTheOrigin(map), {"--png", png, "--csv", csv}));
  // Checked before the map is read: a missing map is not what it reports.
  const RunResult no_map = runRaymap({"heightmap", dir.file("no-such-map.rmap"), "--png", png});

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "--png")) << r.err;
  EXPECT_TRUE(contains(r.err, png)) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(no_map.exit_code, 1) << describe(no_map);
  EXPECT_TRUE(contains(no_map.err, "--png")) << no_map.err;
  EXPECT_TRUE(fs::is_empty(dir.path())) << "something was written to " << dir.path();
}

TEST(CliHeightmap, MapWithoutAnOccupancyLayerIsRefused) {
  TempDir dir;
  const std::string path = dir.file("no_occupancy.rmap");
  // A map of decay rates only (populate --mode decay): voxel means and path lengths, no occupancy.
  MapConfig config = MapConfig{}.forDecay();
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  auto map = VoxelMap::create(config);
  ASSERT_TRUE(map) << map.error().message;
  for (const Vec3i region : {Vec3i{0, 0, 0}, Vec3i{-1, 0, 0}}) {
    ASSERT_TRUE(map->acquireRegion(region));
  }
  auto saved = io::saveMap(*map, path);
  ASSERT_TRUE(saved) << saved.error().message;

  const RunResult centred =
      runRaymap({"heightmap", path, "--center", "0.5,0.5,0.5", "--size", "2"});
  const RunResult defaults = runRaymap({"heightmap", path});

  for (const RunResult& r : {centred, defaults}) {
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_TRUE(contains(r.err, path)) << r.err;
    EXPECT_TRUE(contains(r.err, "no occupancy layer")) << r.err;
  }
}

}  // namespace
}  // namespace raymap::test
