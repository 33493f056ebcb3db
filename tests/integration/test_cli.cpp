// SPDX-License-Identifier: BSD-3-Clause
// The raymap program end to end: runs the real binary on generated inputs and checks its exit
// codes, messages, output files and that failures leave nothing behind.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/sim/yard_scan.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/dir_listing.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Running the program
// ---------------------------------------------------------------------------------------------

// ---------------------------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------------------------

/// Fails when a temporary file ("*.raymap-tmp-*") is in `dir`.
testing::AssertionResult noTemporaryFilesIn(const fs::path& dir) {
  for (const std::string& name : listFiles(dir)) {
    if (name.find(".raymap-tmp-") != std::string::npos) {
      return testing::AssertionFailure() << "temporary file left behind: " << name;
    }
  }
  return testing::AssertionSuccess();
}

/// The vertex count in a PLY header, or nullopt when there is none.
std::optional<std::uint64_t> plyVertexCount(const std::string& path) {
  const std::string text = readFile(path);
  const std::string tag = "element vertex ";
  const std::size_t at = text.find(tag);
  const std::size_t end_header = text.find("end_header");
  if (at == std::string::npos || end_header == std::string::npos || at > end_header) {
    return std::nullopt;
  }
  return std::stoull(text.substr(at + tag.size()));
}

// ---------------------------------------------------------------------------------------------
// JSON (the program's flat output: enough to read one value by key)
// ---------------------------------------------------------------------------------------------

/// A numeric value by key; NaN (which fails every comparison) when it is missing or not a number.
double jsonNumber(const std::string& json, const std::string& key) {
  const std::optional<std::string> text = jsonValue(json, key);
  if (!text) {
    ADD_FAILURE() << "key '" << key << "' missing from:\n" << json;
    return std::nan("");
  }
  try {
    return std::stod(*text);
  } catch (const std::exception&) {
    ADD_FAILURE() << "key '" << key << "' is not a number: " << *text;
    return std::nan("");
  }
}

std::uint64_t jsonCount(const std::string& json, const std::string& key) {
  const double value = jsonNumber(json, key);
  return value >= 0.0 ? static_cast<std::uint64_t>(value) : ~std::uint64_t{0};
}

/// 1234567 -> "1,234,567", as the program prints counts.
std::string withCommas(std::uint64_t value) {
  const std::string digits = std::to_string(value);
  std::string out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    out += digits[i];
    const std::size_t left = digits.size() - i - 1;
    if (left > 0 && left % 3 == 0) {
      out += ',';
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

/// A small yard recording: 8 beams x 256 columns per scan.
std::vector<Ray> yardRays(int scans) {
  sim::YardScanConfig config;
  config.lidar.beams = 8;
  config.lidar.columns = 256;
  config.lidar.max_range_m = 20.0;
  config.scans = scans;
  return sim::simulateYardScans(config);
}

constexpr int kYardScans = 2;
constexpr std::uint64_t kYardRays = 2 * 8 * 256;
/// Keeps the maps of the success tests small and fast.
const std::vector<std::string> kSmallMap = {"--max-range", "8", "--quiet"};

/// A valid ray cloud of `count` rays as a PlyTestFile (float x y z nx ny nz), for damaging.
PlyTestFile smallRayCloud(int count) {
  PlyTestFile file;
  PlyTestElement vertex("vertex", {{"float", "x", ""},
                                   {"float", "y", ""},
                                   {"float", "z", ""},
                                   {"float", "nx", ""},
                                   {"float", "ny", ""},
                                   {"float", "nz", ""}});
  for (int i = 0; i < count; ++i) {
    const double y = 0.01 * i;
    // Sample on a wall at x = 3; the sensor at (0, 0, 1).
    vertex.add({3.0, y, 0.5, -3.0, -y, 0.5});
  }
  file.elements.push_back(vertex);
  return file;
}

/// The three outputs of a populate run, inside `dir`.
std::vector<std::string> allOutputs(const TempDir& dir) {
  return {"--output",          dir.file("out.rmap"), "--ply",
          dir.file("out.ply"), "--stats-json",       dir.file("out.json")};
}

// ---------------------------------------------------------------------------------------------
// Malformed PLY input
// ---------------------------------------------------------------------------------------------

struct MalformedCase {
  const char* name;
  std::function<void(const std::string& path)> write;
  std::vector<std::string> expected;  ///< parts of the message besides the file name
};

void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.name; }

const char kRayCloudHeaderAscii[] =
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
    "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";

std::vector<MalformedCase> malformedCases() {
  return {
      {"BadMagic",
       [](const std::string& path) {
         writeBytes(path,
                    "plx\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n");
       },
       {"not a PLY file"}},
      {"UnknownFormat",
       [](const std::string& path) {
         writeBytes(path,
                    "ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\n"
                    "end_header\n");
       },
       {"line 2", "binary_middle_endian"}},
      {"NoEndHeader",
       [](const std::string& path) {
         writeBytes(path,
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "property float z\n");
       },
       {"end_header"}},
      {"MissingY",
       [](const std::string& path) {
         PlyTestFile file;
         PlyTestElement vertex("vertex", {{"float", "x", ""},
                                          {"float", "z", ""},
                                          {"float", "nx", ""},
                                          {"float", "ny", ""},
                                          {"float", "nz", ""}});
         vertex.add({3.0, 0.5, -3.0, 0.0, 0.5});
         file.elements.push_back(vertex);
         writePly(path, file);
       },
       {"'y'"}},
      {"TruncatedBinary",
       [](const std::string& path) {
         PlyTestFile file = smallRayCloud(10);
         file.truncate_data_to = 100;  // 4 whole records (24 bytes each) and a part
         writePly(path, file);
       },
       {"truncated"}},
      {"AsciiLineWithTooFewValues",
       [](const std::string& path) {
         writeBytes(path,
                    std::string(kRayCloudHeaderAscii) + "3 0 0.5 -3 0 0.5\n3 0.1 0.5 -3 -0.1\n");
       },
       {"too few values", "line 12"}},
      {"VertexCountLargerThanData",
       [](const std::string& path) {
         PlyTestFile file = smallRayCloud(10);
         file.elements.front().declared_count = 15;
         writePly(path, file);
       },
       {"truncated", "15"}},
      {"TrailingDataAfterVertices",
       [](const std::string& path) {
         PlyTestFile file = smallRayCloud(10);
         file.trailing = std::string(24, 'x');
         writePly(path, file);
       },
       {"unexpected data after the last vertex"}},
      {"GzipWithDataAfterIt",
       [](const std::string& path) {
         PlyTestFile file = smallRayCloud(2000);
         file.gzip = true;
         writePly(path, file);
         std::ofstream(path, std::ios::binary | std::ios::app) << "not gzip";
       },
       {"8 bytes of unexpected data after the gzip stream, at byte "}},
      {"GzipCutShort",
       [](const std::string& path) {
         PlyTestFile file = smallRayCloud(2000);
         file.gzip = true;
         writePly(path, file);
         fs::resize_file(path, fs::file_size(path) / 2);
       },
       {"truncated"}},
  };
}

class MalformedPly : public testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedPly, FailsNamingTheFileAndLeavesNoOutput) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("input.ply");
  ASSERT_NO_THROW(GetParam().write(input));
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(concat({"populate", input, "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, input));
  for (const std::string& part : GetParam().expected) {
    EXPECT_TRUE(contains(r.err, part));
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

INSTANTIATE_TEST_SUITE_P(Cli, MalformedPly, testing::ValuesIn(malformedCases()),
                         [](const testing::TestParamInfo<MalformedCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

// ---------------------------------------------------------------------------------------------
// Other bad input
// ---------------------------------------------------------------------------------------------

/// A point cloud (double x y z time, no normals) of one yard scan without its no-return rays, and
/// the sensor positions at its first and last time.
struct PointCloudInput {
  std::vector<Ray> rays;  ///< the rays the points came from
  double first_time = 0.0;
  double last_time = 0.0;
  Vec3d origin;
};

PointCloudInput writePointCloud(const std::string& path) {
  PointCloudInput input;
  for (const Ray& ray : yardRays(1)) {
    if ((ray.flags & kRayNoReturn) == 0u) {
      input.rays.push_back(ray);
    }
  }
  PlyTestFile file;
  PlyTestElement vertex(
      "vertex",
      {{"double", "x", ""}, {"double", "y", ""}, {"double", "z", ""}, {"double", "time", ""}});
  for (const Ray& ray : input.rays) {
    vertex.add({ray.sample.x, ray.sample.y, ray.sample.z, ray.time_s});
  }
  file.elements.push_back(vertex);
  writePly(path, file);
  input.first_time = input.rays.front().time_s;
  input.last_time = input.rays.back().time_s;
  input.origin = input.rays.front().origin;  // one scan: one sensor position
  return input;
}

/// A trajectory holding the sensor still at `origin` from `t0` to `t1`.
std::string stillTrajectory(Vec3d origin, double t0, double t1) {
  std::ostringstream text;
  text.precision(17);
  text << "# time x y z\n";
  for (const double t : {t0, t1}) {
    text << t << " " << origin.x << " " << origin.y << " " << origin.z << "\n";
  }
  return text.str();
}

TEST(Cli, PointCloudWithoutTrajectoryFails) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("points.ply");
  writePointCloud(input);
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(concat({"populate", input, "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, input));
  EXPECT_TRUE(contains(r.err, "--trajectory"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, TrajectoryNotCoveringTheCloudFailsNamingBothFiles) {
  // Arrange: the trajectory ends halfway through the scan.
  TempDir dir;
  const std::string input = dir.file("points.ply");
  const std::string trajectory = dir.file("path.txt");
  const PointCloudInput cloud = writePointCloud(input);
  writeText(trajectory, stillTrajectory(cloud.origin, cloud.first_time,
                                        0.5 * (cloud.first_time + cloud.last_time)));
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(
      concat({"populate", input, "--trajectory", trajectory, "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, input));
  EXPECT_TRUE(contains(r.err, trajectory));
  EXPECT_TRUE(contains(r.err, "outside"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, TrajectoryWithARayCloudFailsNamingBothFiles) {
  // Arrange: a ray cloud has its origins; the trajectory used to be ignored without a word.
  TempDir dir;
  const std::string input = dir.file("rays.ply");
  const std::string trajectory = dir.file("path.txt");
  writeRayCloud(input, yardRays(1));
  writeText(trajectory, stillTrajectory({0.0, 0.0, 1.0}, -1e9, 1e9));
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(
      concat({"populate", input, "--trajectory", trajectory, "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: " + input + " is a ray cloud"));
  EXPECT_TRUE(contains(
      r.err, "the trajectory " + trajectory + " would not be used: leave --trajectory out"))
      << r.err;
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, NonexistentInputFails) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("missing.ply");
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(concat({"populate", input, "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, input));
  EXPECT_TRUE(contains(r.err, platform::errnoText(ENOENT)));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

// ---------------------------------------------------------------------------------------------
// Unwritable outputs
// ---------------------------------------------------------------------------------------------

/// The output options of populate, one at a time.
class UnwritableOutput : public testing::TestWithParam<const char*> {
 protected:
  /// Populate arguments with every output in `dir` except GetParam(), which goes to `bad_path`.
  std::vector<std::string> arguments(const std::string& input, const TempDir& dir,
                                     const std::string& bad_path) const {
    std::vector<std::string> args = {"populate", input, "--max-range", "8", "--quiet"};
    const std::vector<std::string> outputs = allOutputs(dir);
    for (std::size_t i = 0; i < outputs.size(); i += 2) {
      args.push_back(outputs[i]);
      args.push_back(outputs[i] == GetParam() ? bad_path : outputs[i + 1]);
    }
    return args;
  }
};

TEST_P(UnwritableOutput, InMissingDirectoryFailsBeforeWork) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("input.ply");
  writeRayCloud(input, yardRays(kYardScans));
  const std::string bad_path = dir.file("no-such-dir/out");
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(arguments(input, dir, bad_path));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, GetParam()));
  EXPECT_TRUE(contains(r.err, bad_path));
  EXPECT_TRUE(contains(r.err, platform::errnoText(ENOENT)));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST_P(UnwritableOutput, InReadOnlyDirectoryFails) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("input.ply");
  writeRayCloud(input, yardRays(kYardScans));
  const fs::path read_only = dir.path() / "read-only";
  fs::create_directory(read_only);
  fs::permissions(read_only, fs::perms::owner_read | fs::perms::owner_exec);
  const std::string try_path = (read_only / "try").string();
  if (const int fd = ::open(try_path.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644); fd >= 0) {
    ::close(fd);
    ::unlink(try_path.c_str());
    fs::permissions(read_only, fs::perms::owner_all);
    GTEST_SKIP() << "this user can write into a read-only directory (root?)";
  }
  const std::string bad_path = (read_only / "out").string();
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(arguments(input, dir, bad_path));

  // Assert
  fs::permissions(read_only, fs::perms::owner_all);  // so TempDir can remove it
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, GetParam()));
  EXPECT_TRUE(contains(r.err, bad_path));
  EXPECT_TRUE(contains(r.err, platform::errnoText(EACCES)));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST_P(UnwritableOutput, ThatIsADirectoryFailsAndLeavesNoOtherOutput) {
  // Arrange: the output path names an existing directory (creatable next to, not at, the path).
  TempDir dir;
  const std::string input = dir.file("input.ply");
  writeRayCloud(input, yardRays(kYardScans));
  const std::string bad_path = dir.file("a-directory");
  fs::create_directory(bad_path);
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(arguments(input, dir, bad_path));

  // Assert: a failed run writes nothing, not some of its outputs.
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, bad_path));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

INSTANTIATE_TEST_SUITE_P(Cli, UnwritableOutput,
                         testing::Values("--output", "--ply", "--stats-json"),
                         [](const testing::TestParamInfo<const char*>& param_info) {
                           std::string name;
                           for (const char* c = param_info.param; *c != '\0'; ++c) {
                             if (*c != '-') {
                               name += *c;
                             }
                           }
                           return name;
                         });

// ---------------------------------------------------------------------------------------------
// Bad option values
// ---------------------------------------------------------------------------------------------

struct OptionCase {
  const char* name;
  std::vector<std::string> args;
  /// Parts of the message: the option (as the message spells it) and, where given, the value.
  std::vector<std::string> expected;
};

void PrintTo(const OptionCase& c, std::ostream* os) { *os << c.name; }

class BadOption : public testing::TestWithParam<OptionCase> {};

TEST_P(BadOption, IsAUsageErrorNamingTheOption) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("input.ply");
  ASSERT_NO_THROW(writePly(input, smallRayCloud(10)));
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r =
      runRaymap(concat(concat({"populate", input, "--quiet"}, GetParam().args), allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "error: "));
  for (const std::string& part : GetParam().expected) {
    EXPECT_TRUE(contains(r.err, part));
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

// NOTE(tests): the library's validation messages name options without their dashes
// ("hit probability", "region-voxels"), so those cases look for the bare name.
INSTANTIATE_TEST_SUITE_P(
    Cli, BadOption,
    testing::Values(
        OptionCase{"HitBelowHalf", {"--hit", "0.3"}, {"hit", "0.3"}},
        OptionCase{"MissAboveHalf", {"--miss", "0.6"}, {"miss", "0.6"}},
        OptionCase{"ZeroResolution", {"--resolution", "0"}, {"resolution"}},
        OptionCase{"RegionVoxelsTooLarge", {"--region-voxels", "1000"}, {"region-voxels", "1000"}},
        OptionCase{"MaxRangeBelowMinRange",
                   {"--min-range", "5", "--max-range", "2"},
                   {"max-range", "min-range"}},
        OptionCase{"MaxMemoryUnknownUnit", {"--max-memory", "12XB"}, {"--max-memory", "12XB"}},
        OptionCase{"SemanticsBoth", {"--semantics", "both"}, {"--semantics", "both"}},
        OptionCase{"UnknownOption", {"--no-such-option"}, {"--no-such-option"}},
        OptionCase{"TooManyThreads", {"--threads", "100"}, {"threads", "100"}},
        OptionCase{"UnknownBackend", {"--backend", "vulkan"}, {"--backend", "vulkan"}},
        OptionCase{"GpuCacheNotASize", {"--gpu-cache", "5xregions"}, {"--gpu-cache", "5xregions"}},
        OptionCase{"UnknownFallback", {"--fallback", "gpu"}, {"--fallback", "gpu"}}),
    [](const testing::TestParamInfo<OptionCase>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(Cli, UnknownExportModeIsAUsageError) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  const std::string map = dir.file("yard.rmap");
  writeRayCloud(input, yardRays(kYardScans));
  ASSERT_EQ(runRaymap(concat({"populate", input, "--output", map}, kSmallMap)).exit_code, 0);
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap({"export", map, "--mode", "bogus", "--ply", dir.file("out.ply")});

  // Assert
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap export: error: "));
  EXPECT_TRUE(contains(r.err, "mode"));
  EXPECT_TRUE(contains(r.err, "bogus"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, MapTooBigForMaxMemoryFailsAndLeavesNoOutput) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));
  const std::set<std::string> before = listFiles(dir.path());

  // Act: without the cold tiers (docs/large-maps.md) the pool is all the map may have.
  const RunResult r = runRaymap(concat(
      {"populate", input, "--max-memory", "1MiB", "--no-tiers", "--quiet"}, allOutputs(dir)));
  // With them, 1 MiB (two regions) is too small a pool to stream through.
  const RunResult tiered =
      runRaymap(concat({"populate", input, "--max-memory", "1MiB", "--quiet"}, allOutputs(dir)));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: error: "));
  EXPECT_TRUE(contains(r.err, "--max-memory"));
  EXPECT_EQ(tiered.exit_code, 2) << describe(tiered);
  EXPECT_TRUE(contains(tiered.err, "at least 16"));
  EXPECT_TRUE(contains(tiered.err,
                       "raise the memory budget (--max-memory), or turn the tiers off "
                       "(--no-tiers)"))
      << tiered.err;
  EXPECT_FALSE(contains(tiered.err, "map.")) << tiered.err;  // the library's keys, shown as flags
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, MaxMemoryBeyondTheMachineIsSizedToWhatItCanHold) {
  // 64 TiB of regions is about 179 million slots: their bookkeeping alone used to be committed
  // up front (about 28 GB; the OOM killer ended the run). The pool is now sized to what this
  // machine's memory can fill, said in a note, and a small map costs what it uses.
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));
  const std::string stats = dir.file("out.json");

  const RunResult r =
      runRaymap({"populate", input, "--max-memory", "64TiB", "--stats-json", stats});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap populate: note: --max-memory asks for")) << r.err;
  EXPECT_TRUE(contains(r.err, "this machine can hold")) << r.err;
  const std::string json = readFile(stats);
  EXPECT_LT(jsonCount(json, "peak_rss_bytes"), std::uint64_t{1} << 30) << json;
}

// ---------------------------------------------------------------------------------------------
// Success paths
// ---------------------------------------------------------------------------------------------

/// Checks the statistics JSON of a run over kYardRays rays; returns nothing, fails the test.
void expectSaneStats(const std::string& json, unsigned threads) {
  for (const char* key : {"rays_in", "rays_integrated", "rays_rejected", "integrate_seconds",
                          "rays_per_second", "voxels_free", "voxels_occupied", "backend", "threads",
                          "updates_dropped", "peak_rss_bytes"}) {
    EXPECT_TRUE(jsonValue(json, key).has_value()) << "missing key " << key << " in\n" << json;
  }
  EXPECT_EQ(jsonCount(json, "rays_in"), kYardRays);
  EXPECT_EQ(jsonCount(json, "rays_integrated") + jsonCount(json, "rays_rejected"), kYardRays);
  EXPECT_GT(jsonCount(json, "rays_integrated"), kYardRays * 9 / 10);
  EXPECT_GT(jsonNumber(json, "integrate_seconds"), 0.0);
  EXPECT_GT(jsonNumber(json, "rays_per_second"), 0.0);
  EXPECT_GT(jsonCount(json, "voxels_free"), 0u);
  EXPECT_GT(jsonCount(json, "voxels_occupied"), 0u);
  EXPECT_EQ(jsonValue(json, "backend"), std::optional<std::string>("cpu"));
  EXPECT_EQ(jsonCount(json, "threads"), threads);
  EXPECT_EQ(jsonCount(json, "updates_dropped"), 0u);
  EXPECT_GT(jsonCount(json, "peak_rss_bytes"), 1u << 20);
}

struct VoxelCounts {
  std::uint64_t free = 0;
  std::uint64_t occupied = 0;
  bool operator==(const VoxelCounts&) const = default;
};

/// Voxel counts as `raymap info --json` reports them for a saved map.
VoxelCounts infoCounts(const std::string& map_path) {
  const RunResult r = runRaymap({"info", "--json", map_path});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  return {jsonCount(r.out, "voxels_free"), jsonCount(r.out, "voxels_occupied")};
}

class Populate : public testing::TestWithParam<const char*> {};

TEST_P(Populate, WritesMapPlyAndStatsWithMatchingCountsForOneAndTwoThreads) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));
  std::vector<VoxelCounts> per_thread_count;

  for (const unsigned threads : {1u, 2u}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const std::string map = dir.file("yard-" + std::to_string(threads) + ".rmap");
    const std::string ply = dir.file("yard-" + std::to_string(threads) + ".ply");
    const std::string stats = dir.file("yard-" + std::to_string(threads) + ".json");

    // Act
    const RunResult r = runRaymap(
        concat({"populate", input, "--semantics", GetParam(), "--threads", std::to_string(threads),
                "--output", map, "--ply", ply, "--stats-json", stats},
               kSmallMap));

    // Assert
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_EQ(r.out, "");  // --quiet
    ASSERT_TRUE(fs::exists(map));
    ASSERT_TRUE(fs::exists(ply));
    ASSERT_TRUE(fs::exists(stats));
    const std::string json = readFile(stats);
    expectSaneStats(json, threads);
    EXPECT_EQ(jsonValue(json, "semantics"), std::optional<std::string>(GetParam()));
    const VoxelCounts saved = infoCounts(map);
    EXPECT_EQ(saved.free, jsonCount(json, "voxels_free"));
    EXPECT_EQ(saved.occupied, jsonCount(json, "voxels_occupied"));
    EXPECT_EQ(plyVertexCount(ply), std::optional<std::uint64_t>(saved.occupied));
    per_thread_count.push_back(saved);
  }
  ASSERT_EQ(per_thread_count.size(), 2u);
  EXPECT_EQ(per_thread_count[0], per_thread_count[1]) << "2 threads must build the 1-thread map";
  EXPECT_TRUE(noTemporaryFilesIn(dir.path()));
}

INSTANTIATE_TEST_SUITE_P(Cli, Populate, testing::Values("ray", "scan"),
                         [](const testing::TestParamInfo<const char*>& param_info) {
                           return std::string(param_info.param);
                         });

TEST(Cli, InfoAndExportDescribeThePopulatedMap) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  const std::string map = dir.file("yard.rmap");
  writeRayCloud(input, yardRays(kYardScans));
  const RunResult populated = runRaymap(concat({"populate", input, "--output", map}, kSmallMap));
  ASSERT_EQ(populated.exit_code, 0) << describe(populated);
  const VoxelCounts counts = infoCounts(map);
  ASSERT_GT(counts.free, 0u);
  ASSERT_GT(counts.occupied, 0u);

  // Act
  const RunResult text = runRaymap({"info", map});
  const RunResult json = runRaymap({"info", "--json", map});
  const std::string occupied_ply = dir.file("occupied.ply");
  const std::string free_ply = dir.file("free.ply");
  const std::string mean_ply = dir.file("mean.ply");
  const RunResult occupied =
      runRaymap({"export", map, "--mode", "occupied", "--ply", occupied_ply});
  const RunResult free = runRaymap({"export", map, "--mode", "free", "--ply", free_ply});
  const RunResult mean = runRaymap({"export", map, "--mode", "mean", "--ply", mean_ply});

  // Assert: info, as text and as JSON.
  ASSERT_EQ(text.exit_code, 0) << describe(text);
  EXPECT_TRUE(contains(text.out, map));
  EXPECT_TRUE(contains(text.out, withCommas(counts.free) + " free"));
  EXPECT_TRUE(contains(text.out, withCommas(counts.occupied) + " occupied"));
  EXPECT_TRUE(contains(text.out, "semantics      ray"));
  ASSERT_EQ(json.exit_code, 0) << describe(json);
  EXPECT_EQ(jsonValue(json.out, "path"), std::optional<std::string>(map));
  EXPECT_EQ(jsonNumber(json.out, "resolution"), 0.1);
  EXPECT_EQ(jsonValue(json.out, "semantics"), std::optional<std::string>("ray"));
  EXPECT_EQ(jsonCount(json.out, "rays_in"), kYardRays);  // provenance ("info") as a string
  // Export: the PLY headers and the printed counts match the map.
  ASSERT_EQ(occupied.exit_code, 0) << describe(occupied);
  ASSERT_EQ(free.exit_code, 0) << describe(free);
  ASSERT_EQ(mean.exit_code, 0) << describe(mean);
  EXPECT_EQ(plyVertexCount(occupied_ply), std::optional<std::uint64_t>(counts.occupied));
  EXPECT_EQ(plyVertexCount(free_ply), std::optional<std::uint64_t>(counts.free));
  EXPECT_TRUE(contains(occupied.out, "wrote " + withCommas(counts.occupied) + " points"));
  EXPECT_TRUE(contains(free.out, "wrote " + withCommas(counts.free) + " points"));
  // Every occupied voxel has samples (its hits); every voxel with samples is observed.
  const std::optional<std::uint64_t> with_samples = plyVertexCount(mean_ply);
  ASSERT_TRUE(with_samples.has_value());
  EXPECT_GE(*with_samples, counts.occupied);
  EXPECT_LE(*with_samples, counts.free + counts.occupied);
  EXPECT_TRUE(noTemporaryFilesIn(dir.path()));
}

TEST(Cli, PointCloudWithTrajectoryMatchesTheRayCloud) {
  // Arrange: the same scan as a point cloud + trajectory and as a ray cloud.
  TempDir dir;
  const std::string points = dir.file("points.ply");
  const std::string trajectory = dir.file("path.txt");
  const std::string rays = dir.file("rays.ply");
  const PointCloudInput cloud = writePointCloud(points);
  writeText(trajectory, stillTrajectory(cloud.origin, cloud.first_time, cloud.last_time));
  writeRayCloud(rays, cloud.rays);

  // Act
  const RunResult from_points =
      runRaymap(concat({"populate", points, "--trajectory", trajectory, "--stats-json",
                        dir.file("points.json"), "--output", dir.file("points.rmap")},
                       kSmallMap));
  const RunResult from_rays =
      runRaymap(concat({"populate", rays, "--stats-json", dir.file("rays.json")}, kSmallMap));

  // Assert: ray clouds store origins as float offsets, so allow a few voxels of difference.
  ASSERT_EQ(from_points.exit_code, 0) << describe(from_points);
  ASSERT_EQ(from_rays.exit_code, 0) << describe(from_rays);
  const std::string points_json = readFile(dir.file("points.json"));
  const std::string rays_json = readFile(dir.file("rays.json"));
  EXPECT_EQ(jsonCount(points_json, "rays_in"), cloud.rays.size());
  EXPECT_EQ(jsonCount(points_json, "rays_rejected"), 0u);
  for (const char* key : {"voxels_free", "voxels_occupied"}) {
    const double a = jsonNumber(points_json, key);
    const double b = jsonNumber(rays_json, key);
    EXPECT_GT(a, 0.0) << key;
    EXPECT_NEAR(a, b, 0.005 * b) << key;
  }
  EXPECT_EQ(infoCounts(dir.file("points.rmap")).occupied,
            jsonCount(points_json, "voxels_occupied"));
}

TEST(Cli, GzipInputGivesTheSameMapAsPlainInput) {
  // Arrange
  TempDir dir;
  const std::string plain = dir.file("yard.ply");
  const std::string gzipped = dir.file("yard.ply.gz");
  writeRayCloud(plain, yardRays(kYardScans));
  ASSERT_NO_THROW(writeBytes(gzipped, readFile(plain), /*gzip=*/true));
  ASSERT_LT(fs::file_size(gzipped), fs::file_size(plain));

  // Act
  const RunResult from_plain =
      runRaymap(concat({"populate", plain, "--output", dir.file("plain.rmap")}, kSmallMap));
  const RunResult from_gzip =
      runRaymap(concat({"populate", gzipped, "--output", dir.file("gzip.rmap")}, kSmallMap));

  // Assert
  ASSERT_EQ(from_plain.exit_code, 0) << describe(from_plain);
  ASSERT_EQ(from_gzip.exit_code, 0) << describe(from_gzip);
  const VoxelCounts plain_counts = infoCounts(dir.file("plain.rmap"));
  EXPECT_GT(plain_counts.occupied, 0u);
  EXPECT_EQ(infoCounts(dir.file("gzip.rmap")), plain_counts);
}

TEST(Cli, PopulatingOverAnExistingMapReplacesIt) {
  // Arrange: an older map from one scan, then a run over both scans to the same path.
  TempDir dir;
  const std::string one_scan = dir.file("one.ply");
  const std::string two_scans = dir.file("two.ply");
  const std::string map = dir.file("map.rmap");
  writeRayCloud(one_scan, yardRays(1));
  writeRayCloud(two_scans, yardRays(kYardScans));
  ASSERT_EQ(runRaymap(concat({"populate", one_scan, "--output", map}, kSmallMap)).exit_code, 0);
  const VoxelCounts old_counts = infoCounts(map);
  const RunResult reference =
      runRaymap(concat({"populate", two_scans, "--output", dir.file("ref.rmap")}, kSmallMap));
  ASSERT_EQ(reference.exit_code, 0) << describe(reference);
  const VoxelCounts new_counts = infoCounts(dir.file("ref.rmap"));
  ASSERT_NE(old_counts, new_counts);

  // Act
  const RunResult r = runRaymap(concat({"populate", two_scans, "--output", map}, kSmallMap));

  // Assert
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(infoCounts(map), new_counts);
  EXPECT_EQ(jsonValue(runRaymap({"info", "--json", map}).out, "source"),
            std::optional<std::string>(two_scans));
  EXPECT_TRUE(noTemporaryFilesIn(dir.path()));
}

TEST(Cli, FailedPopulateLeavesTheExistingMapUntouched) {
  // Arrange
  TempDir dir;
  const std::string good = dir.file("good.ply");
  const std::string bad = dir.file("bad.ply");
  const std::string map = dir.file("map.rmap");
  writeRayCloud(good, yardRays(1));
  PlyTestFile damaged = smallRayCloud(10);
  damaged.truncate_data_to = 100;
  ASSERT_NO_THROW(writePly(bad, damaged));
  ASSERT_EQ(runRaymap(concat({"populate", good, "--output", map}, kSmallMap)).exit_code, 0);
  const std::string old_bytes = readFile(map);
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymap(concat({"populate", bad, "--output", map}, kSmallMap));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(readFile(map) == old_bytes) << "the old map was changed";
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, CorruptMapFailsInInfoAndExportNamingTheFile) {
  // Arrange: a real map, then a truncated copy, a copy with a flipped byte in its region data,
  // and a file that is no map at all.
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  const std::string map = dir.file("good.rmap");
  writeRayCloud(input, yardRays(kYardScans));
  ASSERT_EQ(runRaymap(concat({"populate", input, "--output", map}, kSmallMap)).exit_code, 0);
  const std::string good = readFile(map);
  ASSERT_GT(good.size(), 1000u);
  std::string flipped = good;
  flipped[flipped.size() - 100] = static_cast<char>(flipped[flipped.size() - 100] ^ 0x5a);
  const std::vector<std::pair<std::string, std::string>> corrupt = {
      {dir.file("truncated.rmap"), good.substr(0, good.size() / 2)},
      {dir.file("flipped.rmap"), flipped},
      {dir.file("foreign.rmap"), "this is not a raymap map file\n"},
      {dir.file("empty.rmap"), ""},
  };
  for (const auto& [path, bytes] : corrupt) {
    writeText(path, bytes);
  }
  const std::set<std::string> before = listFiles(dir.path());

  for (const auto& [path, bytes] : corrupt) {
    SCOPED_TRACE(path);

    // Act
    const RunResult info = runRaymap({"info", path});
    const RunResult info_json = runRaymap({"info", "--json", path});
    const RunResult exported = runRaymap({"export", path, "--ply", dir.file("out.ply")});

    // Assert
    EXPECT_EQ(info.exit_code, 1) << describe(info);
    EXPECT_TRUE(contains(info.err, "raymap info: error: " + path));
    EXPECT_EQ(info_json.exit_code, 1) << describe(info_json);
    EXPECT_TRUE(contains(info_json.err, "raymap info: error: " + path));
    EXPECT_EQ(exported.exit_code, 1) << describe(exported);
    EXPECT_TRUE(contains(exported.err, "raymap export: error: " + path));
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, EmptyAndForeignFilesSayWhatIsWrong) {
  // Arrange: an empty record log was reported as "not a PLY file", and a log with a damaged
  // magic too (replay took every file that lacked the magic for a PLY).
  TempDir dir;
  const std::string empty_log = dir.file("empty.rmlog");
  const std::string foreign_log = dir.file("foreign.rmlog");
  const std::string empty_ply = dir.file("empty.ply");
  const std::string a_log = dir.file("drive.log");
  writeText(empty_log, "");
  writeText(foreign_log, "RMLOX\r\n\x1a and then some bytes");
  writeText(empty_ply, "");
  writeText(a_log, std::string("RMLOG\r\n\x1a", 8) + std::string(40, '\0'));
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"replay", empty_log, "--wait", "0", "-q"},
       "raymap replay: error: " + empty_log + " is empty (0 bytes): not a raymap record log"},
      {{"replay", foreign_log, "--wait", "0", "-q"},
       "raymap replay: error: " + foreign_log +
           ": not a raymap record log: it does not start "
           "with the magic"},
      {{"populate", empty_ply, "--stats-json", "-", "-q"},
       "raymap populate: error: " + empty_ply + " is empty (0 bytes): not a PLY file"},
      {{"populate", a_log, "--stats-json", "-", "-q"},
       "raymap populate: error: " + a_log +
           " is a raymap record log: populate maps PLY files and "
           "rosbag2 bags"},
  };
  const std::set<std::string> before = listFiles(dir.path());

  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[1]);
    // Act
    const RunResult r = runRaymap(c.args);

    // Assert
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_TRUE(contains(r.err, c.expected));
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(Cli, DemoWritesItsFiles) {
  // Arrange
  TempDir dir;
  const std::string out = dir.file("demo");

  // Act
  const RunResult r = runRaymap({"demo", "--output-dir", out, "--quiet"});

  // Assert
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out, "");
  for (const char* name : {"yard_raycloud.ply", "yard.rmap", "yard_occupied.ply"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / name)) << name;
  }
  EXPECT_GT(infoCounts((fs::path(out) / "yard.rmap").string()).occupied, 0u);
  EXPECT_TRUE(noTemporaryFilesIn(out));
}

TEST(Cli, BenchPrintsJsonWithARunPerConfiguration) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));

  // Act
  const RunResult r = runRaymap({"bench", input, "--max-range", "8", "--repeat", "1",
                                 "--threads-list", "1,2", "--semantics-list", "ray,scan"});

  // Assert
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::optional<Json> json = parseJson(r.out);
  ASSERT_TRUE(json.has_value());
  const Json* runs = findPath(*json, {"runs"});
  ASSERT_NE(runs, nullptr) << r.out;
  ASSERT_TRUE(runs->is_array()) << r.out;
  EXPECT_EQ(runs->size(), 4u);  // 2 semantics x 2 thread counts
  for (const Json& run : *runs) {
    EXPECT_EQ(run.value("rays_in", std::uint64_t{0}), kYardRays);
  }
  EXPECT_TRUE(noTemporaryFilesIn(dir.path()));
}

TEST(Cli, BenchTakesSemanticsAndThreadsAsOneRunAndRefusesThemBesideTheirLists) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(1));

  // Act
  const RunResult one = runRaymap({"bench", input, "--max-range", "8", "--repeat", "1", "--threads",
                                   "1", "--semantics", "scan"});
  const RunResult both = runRaymap({"bench", input, "--max-range", "8", "--repeat", "1",
                                    "--semantics", "ray", "--semantics-list", "ray,scan"});
  const RunResult both_threads = runRaymap({"bench", input, "--max-range", "8", "--repeat", "1",
                                            "--threads", "2", "--threads-list", "1"});

  // Assert
  ASSERT_EQ(one.exit_code, 0) << describe(one);
  const std::optional<Json> json = parseJson(one.out);
  ASSERT_TRUE(json.has_value());
  const Json* runs = findPath(*json, {"runs"});
  ASSERT_NE(runs, nullptr) << one.out;
  ASSERT_EQ(runs->size(), 1u) << one.out;
  EXPECT_EQ((*runs)[0].value("semantics", ""), "scan") << one.out;
  EXPECT_EQ((*runs)[0].value("threads", 0), 1) << one.out;
  EXPECT_EQ(both.exit_code, 2) << describe(both);
  EXPECT_TRUE(contains(both.err, "--semantics-list")) << both.err;
  EXPECT_EQ(both_threads.exit_code, 2) << describe(both_threads);
  EXPECT_TRUE(contains(both_threads.err, "--threads-list")) << both_threads.err;
}

TEST(Cli, BenchWithUnwritableJsonFailsNamingThePathAndReason) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(1));
  const std::string bad_path = dir.file("no-such-dir/bench.json");
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r =
      runRaymap({"bench", input, "--max-range", "8", "--repeat", "1", "--threads-list", "1",
                 "--semantics-list", "ray", "--json", bad_path});

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap bench: error: "));
  EXPECT_TRUE(contains(r.err, bad_path));
  EXPECT_TRUE(contains(r.err, platform::errnoText(ENOENT)));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

}  // namespace
}  // namespace raymap::test

// ---------------------------------------------------------------------------------------------
// The OpenCL backend from the command line (runs on PoCL; skips without OpenCL)
// ---------------------------------------------------------------------------------------------

namespace raymap::test {
namespace {

/// Why `--backend opencl` cannot run here, or "" when it can.
std::string openClUnavailable() {
  const RunResult r = runRaymap({"devices"});
  return contains(r.out, "default for --backend opencl") ? std::string() : r.out + r.err;
}

/// Maps the yard on the CPU and on `device` (batches planned on the host, then on the device),
/// and expects the same map and the device report.
void expectDeviceMatchesTheCpu(const std::string& device) {
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));
  std::vector<VoxelCounts> counts;
  for (const auto& [backend, planning] :
       {std::pair{std::string("cpu"), std::string()}, std::pair{device, std::string("host")},
        std::pair{device, std::string("device")}}) {
    SCOPED_TRACE(backend + " " + planning);
    const std::string map = dir.file(backend + planning + ".rmap");
    const std::string stats = dir.file(backend + planning + ".json");
    // Per-scan semantics: the device map equals the CPU's exactly (docs/architecture.md), for
    // the same walk direction (devices walk in reverse by default).
    std::vector<std::string> args = {"populate",     input,   "--semantics", "scan",
                                     "--backend",    backend, "--output",    map,
                                     "--stats-json", stats};
    if (backend == "cpu") {
      args.push_back("--reverse");
    } else {
      args.insert(args.end(), {"--device-planning", planning});
    }
    const RunResult r = runRaymap(concat(args, kSmallMap));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    const std::string json = readFile(stats);
    EXPECT_EQ(jsonValue(json, "backend"), std::optional<std::string>(backend));
    EXPECT_EQ(jsonCount(json, "updates_dropped"), 0u);
    if (backend != "cpu") {
      for (const char* key : {"device", "rays_skipped", "bytes_to_device", "bytes_from_device",
                              "cache_slots", "cache_hits", "cache_misses", "cache_hit_rate"}) {
        EXPECT_TRUE(jsonValue(json, key).has_value()) << "missing key " << key << " in\n" << json;
      }
      EXPECT_GT(jsonCount(json, "bytes_to_device"), 0u);
      EXPECT_EQ(jsonCount(json, "rays_skipped"), 0u);
      EXPECT_EQ(jsonValue(json, "walk"), std::optional<std::string>("reverse"));
      EXPECT_EQ(jsonValue(json, "planning"), std::optional<std::string>(planning));
      EXPECT_EQ(jsonCount(json, "plans_on_host"), 0u);
    }
    counts.push_back(infoCounts(map));
  }
  EXPECT_EQ(counts[0], counts[1]);
}

TEST(CliOpenCl, PopulateMatchesTheCpuAndReportsTheDevice) {
  if (const std::string why = openClUnavailable(); !why.empty()) {
    GTEST_SKIP() << why;
  }
  expectDeviceMatchesTheCpu("opencl");
}

TEST(CliOpenCl, BenchHeightmapCyclesReadTheDeviceLayersAndCopyNoneOfTheMap) {
  if (const std::string why = openClUnavailable(); !why.empty()) {
    GTEST_SKIP() << why;
  }
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(kYardScans));
  for (const bool from_host : {false, true}) {
    SCOPED_TRACE(from_host ? "from host" : "device layers");
    std::vector<std::string> args = {"bench",
                                     input,
                                     "--max-range",
                                     "8",
                                     "--repeat",
                                     "1",
                                     "--semantics-list",
                                     "scan",
                                     "--backend",
                                     "opencl",
                                     "--gpu-memory",
                                     "shared",
                                     "--heightmap-every",
                                     "500",
                                     "--heightmap-size",
                                     "6"};
    if (from_host) {
      args.emplace_back("--heightmap-from-host");
    }
    const RunResult r = runRaymap(args);
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    const std::optional<Json> document = parseJson(r.out);
    ASSERT_TRUE(document.has_value());
    const Json* cycles = findFirst(*document, "heightmap_cycles");
    ASSERT_NE(cycles, nullptr) << r.out;
    const std::string json = cycles->dump();
    EXPECT_EQ(jsonValue(json, "reads"),
              std::optional<std::string>(from_host ? "host store" : "device layers"));
    EXPECT_GE(jsonCount(json, "heightmaps"), 3u) << json;
    EXPECT_GT(jsonCount(json, "heightmap_transfer_bytes_p99"), 0u) << json;
    if (from_host) {
      EXPECT_GT(jsonCount(json, "heightmap_copy_bytes_p99"), 0u) << json;
    } else {
      EXPECT_EQ(jsonCount(json, "heightmap_copy_bytes_p99"), 0u) << json;
      EXPECT_EQ(jsonCount(json, "sync_copy_bytes_p99"), 0u) << json;
    }
  }
}

/// Why `--backend cuda` cannot run here, or "" when it can.
std::string cudaUnavailable() {
  const RunResult r = runRaymap({"devices"});
  return contains(r.out, "default for --backend cuda") ? std::string() : r.out + r.err;
}

TEST(CliCuda, PopulateMatchesTheCpuOrExplainsWhyNotAndOffersTheFallback) {
  if (cudaUnavailable().empty()) {
    expectDeviceMatchesTheCpu("cuda");
    return;
  }
  // No NVIDIA driver or GPU (CI), or a build without CUDA: a clear error, nothing written, and
  // --fallback cpu still maps.
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(1));
  const std::string map = dir.file("out.rmap");
  const std::string stats = dir.file("out.json");
  const std::vector<std::string> args = {
      "populate",     input, "--backend", "cuda",        "--output", map,
      "--stats-json", stats, "--quiet",   "--max-range", "8"};
  const RunResult failed = runRaymap(args);
  EXPECT_EQ(failed.exit_code, 1) << describe(failed);
  EXPECT_TRUE(contains(failed.err, "--backend cuda: ")) << failed.err;
  EXPECT_TRUE(contains(failed.err, "(--fallback cpu maps on the CPU instead)")) << failed.err;
  EXPECT_FALSE(contains(failed.err, "backend.")) << failed.err;  // keys shown as flags
  EXPECT_FALSE(fs::exists(map));
  const RunResult fell_back = runRaymap(concat(args, {"--fallback", "cpu"}));
  ASSERT_EQ(fell_back.exit_code, 0) << describe(fell_back);
  EXPECT_TRUE(contains(fell_back.err, "falling back to the CPU"));
  EXPECT_TRUE(contains(fell_back.err, "warning: --backend cuda: ")) << fell_back.err;
  const std::optional<std::string> fallback = jsonValue(readFile(stats), "fallback");
  ASSERT_TRUE(fallback.has_value());
  EXPECT_TRUE(contains(*fallback, "--backend cuda: ")) << *fallback;
  EXPECT_EQ(jsonValue(readFile(stats), "backend"), std::optional<std::string>("cpu"));
}

TEST(CliCuda, DevicesListsBothApisAndSaysWhyOneHasNone) {
  const RunResult text = runRaymap({"devices"});
  EXPECT_TRUE(contains(text.out, "OpenCL\n")) << text.out;
  EXPECT_TRUE(contains(text.out, "\nCUDA\n")) << text.out;
  const RunResult json = runRaymap({"devices", "--json"});
  const std::optional<Json> devices = parseJson(json.out);
  ASSERT_TRUE(devices.has_value());
  for (const char* api : {"opencl", "cuda"}) {
    const Json* section = findPath(*devices, {api});
    EXPECT_TRUE(section != nullptr && section->is_object()) << api << "\n" << json.out;
  }
  if (!cudaUnavailable().empty()) {
    EXPECT_TRUE(contains(text.out, "none: ")) << text.out;
    const Json* error = findPath(*devices, {"cuda", "error"});
    EXPECT_TRUE(error != nullptr && error->is_string()) << json.out;
  }
}

TEST(CliOpenCl, UnknownDeviceFailsUnlessTheCpuFallbackIsAllowed) {
  if (const std::string why = openClUnavailable(); !why.empty()) {
    GTEST_SKIP() << why;
  }
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(1));
  const std::string map = dir.file("out.rmap");
  const std::string stats = dir.file("out.json");
  const std::vector<std::string> args = {
      "populate",     input, "--backend",   "opencl", "--opencl-device", "nosuch", "--output", map,
      "--stats-json", stats, "--max-range", "8",      "--quiet"};
  const RunResult failed = runRaymap(args);
  EXPECT_EQ(failed.exit_code, 1) << describe(failed);
  EXPECT_TRUE(contains(failed.err, "nosuch"));
  EXPECT_TRUE(contains(failed.err, "--fallback cpu"));
  EXPECT_FALSE(fs::exists(map));
  EXPECT_TRUE(noTemporaryFilesIn(dir.path()));

  const RunResult fell_back = runRaymap(concat(args, {"--fallback", "cpu"}));
  ASSERT_EQ(fell_back.exit_code, 0) << describe(fell_back);
  EXPECT_TRUE(contains(fell_back.err, "warning"));
  EXPECT_TRUE(contains(fell_back.err, "falling back to the CPU"));
  const std::string json = readFile(stats);
  EXPECT_EQ(jsonValue(json, "backend"), std::optional<std::string>("cpu"));
  EXPECT_TRUE(jsonValue(json, "fallback").has_value());
  EXPECT_TRUE(fs::exists(map));
}

TEST(CliOpenCl, DevicesListsTheDefaultDeviceAsJson) {
  if (const std::string why = openClUnavailable(); !why.empty()) {
    GTEST_SKIP() << why;
  }
  const RunResult r = runRaymap({"devices", "--json"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::optional<Json> json = parseJson(r.out);
  ASSERT_TRUE(json.has_value());
  const Json* platforms = findPath(*json, {"opencl", "platforms"});
  ASSERT_TRUE(platforms != nullptr && platforms->is_array() && !platforms->empty()) << r.out;
  EXPECT_NE(findFirst(*platforms, "int64_atomics"), nullptr) << r.out;
  EXPECT_NE(findPath(*json, {"opencl", "default", "name"}), nullptr) << r.out;
}

}  // namespace
}  // namespace raymap::test

namespace raymap::test {
namespace {

TEST(CliOpenCl, UnwritableKernelCacheIsAWarningNotAFailure) {
  if (const std::string why = openClUnavailable(); !why.empty()) {
    GTEST_SKIP() << why;
  }
  TempDir dir;
  const std::string input = dir.file("yard.ply");
  writeRayCloud(input, yardRays(1));
  const std::string stats = dir.file("out.json");
  // The child inherits the environment; /proc refuses new directories even to root.
  ASSERT_EQ(::setenv("RAYMAP_CACHE_DIR", "/proc/raymap-test", 1), 0);
  const RunResult r = runRaymap(
      concat({"populate", input, "--backend", "opencl", "--stats-json", stats}, kSmallMap));
  ::unsetenv("RAYMAP_CACHE_DIR");
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "warning"));
  EXPECT_TRUE(contains(r.err, "/proc/raymap-test"));
  EXPECT_TRUE(jsonValue(readFile(stats), "backend_warning").has_value());
}

}  // namespace
}  // namespace raymap::test
