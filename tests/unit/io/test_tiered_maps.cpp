// SPDX-License-Identifier: BSD-3-Clause
// Maps larger than their memory budget (docs/large-maps.md): a long drive built, saved, loaded,
// exported and turned into height maps through a pool an eighth of its size gives the same bytes
// as with unlimited memory, in every map mode, on one thread and two; the spill file's failures
// (a missing folder, a full disk, a damaged record) are errors naming it, never a wrong map.
#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "src/io/ndt_export.hpp"
#include "src/io/tsdf_export.hpp"
#include "src/map/spill_file.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

using test::readFileBytes;
using test::TempDir;

struct ModeCase {
  const char* name;
  MapConfig (*config)();
};

MapConfig corridorConfig(Semantics semantics) {
  MapConfig c = test::smallConfig(semantics, 16);
  c.voxel_mean = true;
  return c;
}

const std::array<ModeCase, 7> kModes = {{
    {"occupancy_per_ray", [] { return corridorConfig(Semantics::kPerRay); }},
    {"occupancy_per_scan", [] { return corridorConfig(Semantics::kPerScan); }},
    {"ndt_om",
     [] {
       MapConfig c = corridorConfig(Semantics::kPerRay);
       c.mode = MapMode::kNdtOm;
       return c;
     }},
    {"ndt_tm",
     [] {
       MapConfig c = corridorConfig(Semantics::kPerRay);
       c.mode = MapMode::kNdtTm;
       return c;
     }},
    {"decay", [] { return corridorConfig(Semantics::kPerRay).forDecay(); }},
    {"occupancy_and_decay",
     [] {
       MapConfig c = corridorConfig(Semantics::kPerScan);
       c.decay_rate = true;
       return c;
     }},
    {"tsdf", [] { return corridorConfig(Semantics::kPerRay).forTsdf(); }},
}};

const std::vector<Ray>& drive() {
  static const std::vector<Ray> rays = test::corridorDrive(120.0, 0.5);
  return rays;
}

class TieredMap : public ::testing::TestWithParam<std::tuple<ModeCase, unsigned>> {};

TEST_P(TieredMap, AnEighthOfTheMemoryGivesTheSameFileAsUnlimitedMemory) {
  const auto& [mode, threads] = GetParam();
  TempDir dir;
  const MapConfig base = mode.config();
  VoxelMap whole = test::makeMap(base);
  auto whole_backend = test::cpuBackend(whole, threads);
  test::integrateEachScan(whole, *whole_backend, drive());
  const std::uint64_t regions = whole.regionCount();
  ASSERT_GT(regions, 400u) << "the drive is long enough for an eighth of it to be a real limit";

  // An eighth of the regions in the pool, a compressed tier that holds a few dozen regions: most
  // of the drive ends up in the spill file.
  VoxelMap small =
      test::makeMap(test::withTiers(base, regions / 8, 64u << 10, dir.path().string()));
  auto small_backend = test::cpuBackend(small, threads);
  test::integrateEachScan(small, *small_backend, drive());
  ASSERT_FALSE(small.tierFailure().has_value()) << small.tierFailure()->message;
  EXPECT_EQ(small.regionCount(), regions);
  EXPECT_LE(small.store().size(), regions / 8);

  ASSERT_TRUE(io::saveMap(whole, dir.file("whole.rmap")).has_value());
  auto saved = io::saveMap(small, dir.file("small.rmap"));
  ASSERT_TRUE(saved.has_value()) << saved.error().message;
  EXPECT_EQ(readFileBytes(dir.file("small.rmap")), readFileBytes(dir.file("whole.rmap")));

  // Every export of the mode reads the cold regions back (the TSDF exports look across region
  // faces, at neighbours the pool may not hold).
  const auto same_export = [&](const char* name, auto&& write) {
    const std::string a = dir.file(std::string("whole-") + name + ".ply");
    const std::string b = dir.file(std::string("small-") + name + ".ply");
    ASSERT_TRUE(write(whole, a)) << name;
    ASSERT_TRUE(write(small, b)) << name;
    EXPECT_EQ(readFileBytes(b), readFileBytes(a)) << name;
  };
  if (base.mode == MapMode::kTsdf) {
    same_export("surface", [](const VoxelMap& m, const std::string& p) {
      return io::exportTsdfSurface(m, p, 0.0).has_value();
    });
    same_export("mesh", [](const VoxelMap& m, const std::string& p) {
      return io::exportTsdfMesh(m, p, 0.0).has_value();
    });
  } else if (isNdt(base.mode)) {
    same_export("ndt", [](const VoxelMap& m, const std::string& p) {
      return io::exportNdtPoints(m, io::NdtExportOptions{}, p).has_value();
    });
  } else if (base.decay_rate) {
    same_export("decay", [](const VoxelMap& m, const std::string& p) {
      return io::exportPly(m, io::ExportMode::kDecay, p).has_value();
    });
  } else {
    same_export("occupied", [](const VoxelMap& m, const std::string& p) {
      return io::exportPly(m, io::ExportMode::kOccupied, p).has_value();
    });
  }

  ASSERT_TRUE(small.drainTiers().has_value());
  const RegionTierStats stats = *small.tierStats();
  EXPECT_GT(stats.evictions, regions - regions / 8);
  EXPECT_GT(stats.compressions, 0u);
  EXPECT_GT(stats.spill_writes, 0u) << "the compressed tier's budget was passed";
  EXPECT_GT(stats.restores, 0u) << "saving reads every cold region back";
  EXPECT_GT(stats.compressionRatio(), 2.0);
  EXPECT_LE(stats.compressed_bytes, 64u << 10);
}

// Every mode on one thread, and the two occupancy semantics also on two (the parallel path's
// own region creation): each case builds the drive twice, which under the sanitizers is seconds.
INSTANTIATE_TEST_SUITE_P(EveryMode, TieredMap,
                         ::testing::Values(std::tuple{kModes[0], 1u}, std::tuple{kModes[0], 2u},
                                           std::tuple{kModes[1], 1u}, std::tuple{kModes[1], 2u},
                                           std::tuple{kModes[2], 1u}, std::tuple{kModes[3], 1u},
                                           std::tuple{kModes[4], 1u}, std::tuple{kModes[5], 2u},
                                           std::tuple{kModes[6], 1u}),
                         [](const ::testing::TestParamInfo<std::tuple<ModeCase, unsigned>>& param) {
                           return std::string(std::get<0>(param.param).name) + "_" +
                                  std::to_string(std::get<1>(param.param)) + "_threads";
                         });

/// Builds the drive's occupancy map with unlimited memory and saves it to `path`.
VoxelMap wholeDrive(const std::string& path) {
  VoxelMap map = test::makeMap(corridorConfig(Semantics::kPerRay));
  auto backend = test::cpuBackend(map, 1);
  test::integrateEachScan(map, *backend, drive());
  EXPECT_TRUE(io::saveMap(map, path).has_value());
  return map;
}

io::MapLoadOptions tieredLoad(const VoxelMap& like, std::uint64_t regions,
                              const std::string& spill_dir) {
  io::MapLoadOptions options;
  options.memory_budget_bytes =
      regions * like.config().schema().bytesPerRegion(like.geometry().voxelsPerRegion());
  options.tiers.enabled = true;
  options.tiers.compressed_bytes = 128u << 10;
  options.tiers.spill_dir = spill_dir;
  return options;
}

TEST(TieredMapFile, ALargeFileLoadsSummarisesSavesAndExportsThroughAnEighthOfItsSize) {
  TempDir dir;
  const VoxelMap whole = wholeDrive(dir.file("whole.rmap"));
  const std::uint64_t regions = whole.regionCount();
  auto loaded =
      io::loadMap(dir.file("whole.rmap"), tieredLoad(whole, regions / 8, dir.path().string()));
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_TRUE(loaded->tiered());
  EXPECT_LE(loaded->store().capacity(), regions / 8);
  EXPECT_EQ(loaded->regionCount(), regions);

  const MapSummary a = whole.summarise();
  const MapSummary b = loaded->summarise();
  EXPECT_EQ(b.regions, a.regions);
  EXPECT_EQ(b.voxels_free, a.voxels_free);
  EXPECT_EQ(b.voxels_occupied, a.voxels_occupied);
  EXPECT_EQ(b.voxels_unobserved, a.voxels_unobserved);
  EXPECT_EQ(b.observed_min, a.observed_min);
  EXPECT_EQ(b.observed_max, a.observed_max);
  // Point queries reach cold regions too.
  for (const Vec3d p : {Vec3d{1.0, -2.95, 0.5}, Vec3d{60.0, 2.95, 1.2}, Vec3d{118.0, 0.0, 0.05}}) {
    const Vec3i v = whole.voxelOf(p);
    EXPECT_EQ(loaded->state(v), whole.state(v)) << p.x;
    EXPECT_EQ(loaded->mean(v).count, whole.mean(v).count) << p.x;
  }

  ASSERT_TRUE(io::saveMap(*loaded, dir.file("again.rmap")).has_value());
  EXPECT_EQ(readFileBytes(dir.file("again.rmap")), readFileBytes(dir.file("whole.rmap")));
  for (const io::ExportMode mode : {io::ExportMode::kOccupied, io::ExportMode::kFree}) {
    auto n_whole = io::exportPly(whole, mode, dir.file("whole.ply"));
    auto n_loaded = io::exportPly(*loaded, mode, dir.file("loaded.ply"));
    ASSERT_TRUE(n_whole.has_value() && n_loaded.has_value());
    EXPECT_EQ(*n_loaded, *n_whole);
    EXPECT_EQ(readFileBytes(dir.file("loaded.ply")), readFileBytes(dir.file("whole.ply")));
  }
  ASSERT_FALSE(loaded->tierFailure().has_value());
  const RegionTierStats stats = *loaded->tierStats();
  EXPECT_GT(stats.clean_evictions, 0u) << "reading a region back keeps its cold copy";
}

TEST(TieredMapFile, HeightMapsOfAColdPartOfTheMapMatchTheWholeMap) {
  TempDir dir;
  const VoxelMap whole = wholeDrive(dir.file("whole.rmap"));
  auto loaded = io::loadMap(dir.file("whole.rmap"),
                            tieredLoad(whole, whole.regionCount() / 8, dir.path().string()));
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  auto generator = heightmap::makeCpuHeightmapGenerator();
  // The start of the drive went cold first while the file streamed in.
  for (const double x : {5.0, 60.0, 115.0}) {
    heightmap::HeightmapOptions options;
    options.centre = Vec3d{x, 0.0, 0.05};
    options.size = 6.0;
    heightmap::HeightmapPlan plan_whole;
    heightmap::HeightmapPlan plan_loaded;
    ASSERT_TRUE(heightmap::planHeightmap(whole, options, plan_whole).has_value());
    auto planned = heightmap::planHeightmap(*loaded, options, plan_loaded);
    ASSERT_TRUE(planned.has_value()) << planned.error().message;
    heightmap::HeightMap a;
    heightmap::HeightMap b;
    ASSERT_TRUE(generator->generate(whole, plan_whole, a).has_value());
    ASSERT_TRUE(generator->generate(*loaded, plan_loaded, b).has_value());
    ASSERT_EQ(a.cellCount(), b.cellCount());
    EXPECT_EQ(
        0, std::memcmp(a.elevation.data(), b.elevation.data(), a.elevation.size() * sizeof(float)))
        << x;
    EXPECT_EQ(a.kind, b.kind) << x;
    EXPECT_EQ(a.observed_count, b.observed_count) << x;
  }
  // A box larger than the whole pool is refused with the budget named, not a partial map.
  heightmap::HeightmapOptions huge;
  huge.centre = Vec3d{60.0, 0.0, 0.05};
  huge.size = 100.0;
  heightmap::HeightmapPlan plan;
  auto refused = heightmap::planHeightmap(*loaded, huge, plan);
  ASSERT_FALSE(refused.has_value());
  // The library names the option by its configuration key; raymap shows it as --max-memory.
  EXPECT_NE(refused.error().message.find("(map.max_memory)"), std::string::npos)
      << refused.error().message;
  EXPECT_EQ(refused.error().message.find("--"), std::string::npos) << refused.error().message;
}

// ---- failures ----

TEST(TieredMapFailure, AMissingSpillFolderFailsAtCreationNamingIt) {
  MapConfig c =
      test::withTiers(corridorConfig(Semantics::kPerRay), 32, 1u << 20, "/nonexistent/spill");
  auto map = VoxelMap::create(c);
  ASSERT_FALSE(map.has_value());
  EXPECT_NE(map.error().message.find("/nonexistent/spill"), std::string::npos)
      << map.error().message;
}

TEST(TieredMapFailure, APoolTooSmallForTheTiersIsRefused) {
  TempDir dir;
  auto map = VoxelMap::create(
      test::withTiers(corridorConfig(Semantics::kPerRay), 4, 1u << 20, dir.path().string()));
  ASSERT_FALSE(map.has_value());
  EXPECT_NE(map.error().message.find("at least 16"), std::string::npos) << map.error().message;
  // What to change, by configuration key (raymapd's and the library's words), not by flag.
  EXPECT_NE(map.error().message.find("raise the memory budget (map.max_memory), or turn the tiers "
                                     "off (map.tiers: false)"),
            std::string::npos)
      << map.error().message;
  EXPECT_EQ(map.error().message.find("--"), std::string::npos) << map.error().message;
}

TEST(TieredMapFailure, WithoutASpillFolderAFullCompressedTierIsAnError) {
  MapConfig c = test::withTiers(corridorConfig(Semantics::kPerRay), 64, 16u << 10, "");
  VoxelMap map = test::makeMap(c);
  auto backend = test::cpuBackend(map, 1);
  const auto status = test::integrateUntilFailure(map, *backend, drive());
  ASSERT_FALSE(status.has_value());
  EXPECT_EQ(status.error(), IntegrateError::kTierFailed);
  ASSERT_TRUE(map.tierFailure().has_value());
  EXPECT_NE(map.tierFailure()->message.find("(map.spill_dir)"), std::string::npos)
      << map.tierFailure()->message;
  EXPECT_EQ(map.tierFailure()->message.find("--"), std::string::npos) << map.tierFailure()->message;
}

/// Sets RLIMIT_FSIZE (a full disk for every file this process writes) for its lifetime; SIGXFSZ
/// is ignored so that the write fails with EFBIG instead of killing the test.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    previous_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*previous_)(int) = nullptr;
};

TEST(TieredMapFailure, AFullDiskFailsIntegrationNamingTheSpillFile) {
  TempDir dir;
  VoxelMap map = test::makeMap(
      test::withTiers(corridorConfig(Semantics::kPerRay), 64, 16u << 10, dir.path().string()));
  auto backend = test::cpuBackend(map, 1);
  Expected<void, IntegrateError> status;
  {
    const FileSizeLimit full(8u << 10);
    status = test::integrateUntilFailure(map, *backend, drive());
  }
  ASSERT_FALSE(status.has_value());
  EXPECT_EQ(status.error(), IntegrateError::kTierFailed);
  ASSERT_TRUE(map.tierFailure().has_value());
  const std::string message = map.tierFailure()->message;
  EXPECT_NE(message.find("the spill file in " + dir.path().string()), std::string::npos) << message;
  // Nothing half-built is saved: the map refuses to be written while a region is lost.
  auto saved = io::saveMap(map, dir.file("out.rmap"));
  EXPECT_FALSE(saved.has_value());
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.rmap")));
}

/// Opens this process's unnamed spill file in `folder` (found through /proc/self/fd) for writing.
int openSpillFileIn(const std::filesystem::path& folder) {
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    const std::string target = std::filesystem::read_symlink(entry.path(), error).string();
    if (!error && target.rfind(folder.string() + "/", 0) == 0 &&
        target.find("(deleted)") != std::string::npos) {
      return ::open(entry.path().c_str(), O_WRONLY | O_CLOEXEC);
    }
  }
  return -1;
}

TEST(TieredMapFailure, ADamagedSpillFileIsAnErrorNamingItAndNothingIsSaved) {
  TempDir dir;
  const VoxelMap whole = wholeDrive(dir.file("whole.rmap"));
  auto loaded = io::loadMap(dir.file("whole.rmap"),
                            tieredLoad(whole, whole.regionCount() / 8, dir.path().string()));
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  ASSERT_TRUE(loaded->drainTiers().has_value());
  ASSERT_GT(loaded->tierStats()->spill_writes, 0u);
  const int fd = openSpillFileIn(dir.path());
  ASSERT_GE(fd, 0) << "the spill file is open, unnamed, in the spill folder";
  // Every byte of the first records: whichever region is read back first is damaged.
  const std::vector<char> garbage(4096, '\x5A');
  ASSERT_EQ(::pwrite(fd, garbage.data(), garbage.size(), 0), static_cast<ssize_t>(garbage.size()));
  ::close(fd);
  auto saved = io::saveMap(*loaded, dir.file("copy.rmap"));
  ASSERT_FALSE(saved.has_value());
  EXPECT_NE(saved.error().message.find("the spill file in " + dir.path().string()),
            std::string::npos)
      << saved.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir.file("copy.rmap")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("whole.rmap"))) << "the input is untouched";
}

// ---- the spill file itself ----

TEST(SpillFile, RecordsReadBackAndDamageIsNamed) {
  TempDir dir;
  auto file = SpillFile::create(dir.path().string());
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "the file has no name";
  std::vector<std::byte> a(1000, std::byte{7});
  std::vector<std::byte> b(300, std::byte{9});
  auto ra = file->append(42, 5000, a);
  auto rb = file->append(43, 5000, b);
  ASSERT_TRUE(ra.has_value() && rb.has_value());
  EXPECT_EQ(file->sizeBytes(), 2 * SpillFile::kHeaderBytes + a.size() + b.size());
  std::vector<std::byte> out;
  ASSERT_TRUE(file->read(*rb, 43, 5000, out).has_value());
  EXPECT_EQ(out, b);
  ASSERT_TRUE(file->read(*ra, 42, 5000, out).has_value());
  EXPECT_EQ(out, a);

  auto wrong_key = file->read(*ra, 44, 5000, out);
  ASSERT_FALSE(wrong_key.has_value());
  EXPECT_NE(wrong_key.error().message.find("another region"), std::string::npos);
  // A flipped payload byte, then a flipped header byte.
  const char flip = 1;
  ASSERT_EQ(::pwrite(file->descriptorForTests(), &flip, 1,
                     static_cast<off_t>(rb->offset + SpillFile::kHeaderBytes + 10)),
            1);
  auto payload = file->read(*rb, 43, 5000, out);
  ASSERT_FALSE(payload.has_value());
  EXPECT_NE(payload.error().message.find("payload checksum"), std::string::npos);
  EXPECT_NE(payload.error().message.find(dir.path().string()), std::string::npos);
  ASSERT_EQ(::pwrite(file->descriptorForTests(), &flip, 1, static_cast<off_t>(ra->offset + 5)), 1);
  auto header = file->read(*ra, 42, 5000, out);
  ASSERT_FALSE(header.has_value());
  EXPECT_NE(header.error().message.find("damaged record header"), std::string::npos);
}

}  // namespace
}  // namespace raymap
