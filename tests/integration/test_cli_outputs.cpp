// SPDX-License-Identifier: BSD-3-Clause
// Outputs never leave debris: every command writes all of its output files or none (a full disk,
// a signal, a killed run), cleans up temporaries a killed run left, and refuses to overwrite its
// own inputs.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/sim/yard_scan.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/dir_listing.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

/// Runs raymap with its file-size limit (RLIMIT_FSIZE) at `kib` KiB and SIGXFSZ ignored: a
/// write that would make a file larger fails with EFBIG, as on a full disk (the tests run as
/// root, for whom a read-only directory is no obstacle).
RunResult runRaymapWithFileLimit(std::uintmax_t kib, const std::vector<std::string>& args) {
  std::vector<std::string> words = {
      "bash", "-c", "ulimit -f " + std::to_string(kib) + " && trap '' XFSZ && exec \"$0\" \"$@\"",
      RAYMAP_CLI_PATH};
  return runProgram(concat(words, args));
}

/// KiB that hold `bytes`.
std::uintmax_t kibFor(std::uintmax_t bytes) { return (bytes + 1023) / 1024; }

/// A small yard recording (2 scans of 8 x 256 rays) as a ray cloud in `dir`.
std::string yardCloud(const TempDir& dir) {
  sim::YardScanConfig config;
  config.lidar.beams = 8;
  config.lidar.columns = 256;
  config.lidar.max_range_m = 20.0;
  config.scans = 2;
  const std::string path = dir.file("yard.ply");
  writeRayCloud(path, sim::simulateYardScans(config));
  return path;
}

/// The yard cloud mapped into `dir`; empty (and a test failure) when populate fails.
std::string yardMap(const TempDir& dir) {
  const std::string map = dir.file("yard.rmap");
  const RunResult r =
      runRaymap({"populate", yardCloud(dir), "--max-range", "8", "--output", map, "-q"});
  if (r.exit_code != 0) {
    ADD_FAILURE() << describe(r);
    return {};
  }
  return map;
}

// ---------------------------------------------------------------------------------------------
// A full disk: the first output fits, a later one does not
// ---------------------------------------------------------------------------------------------

TEST(CliOutputs, HeightmapOnAFullDiskLeavesNeitherFile) {
  // Arrange: the sizes of both files from a run without a limit, in a directory of their own.
  TempDir dir;
  TempDir reference;
  const std::string map = yardMap(dir);
  ASSERT_FALSE(map.empty());
  const std::vector<std::string> request = {"heightmap", map, "--center", "0,0,0",
                                            "--size",    "8", "-q"};
  const RunResult full = runRaymap(
      concat(request, {"--png", reference.file("hm.png"), "--csv", reference.file("hm.csv")}));
  ASSERT_EQ(full.exit_code, 0) << describe(full);
  const std::uintmax_t png_bytes = fs::file_size(reference.file("hm.png"));
  const std::uintmax_t csv_bytes = fs::file_size(reference.file("hm.csv"));
  const std::uintmax_t limit_kib = kibFor(png_bytes);
  ASSERT_GT(csv_bytes, limit_kib * 1024) << "the CSV must be the file that does not fit";
  const std::string png = dir.file("hm.png");
  const std::string csv = dir.file("hm.csv");
  const std::set<std::string> before = listFiles(dir.path());

  // Act: the PNG (written first) fits, the CSV does not.
  const RunResult r =
      runRaymapWithFileLimit(limit_kib, concat(request, {"--png", png, "--csv", csv}));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap heightmap: error: "));
  EXPECT_TRUE(contains(r.err, csv));
  EXPECT_TRUE(contains(r.err, "File too large"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

TEST(CliOutputs, SimulateOnAFullDiskLeavesNoOutput) {
  // Arrange: the truth CSV (written last, at 5 mm cells) is the one that does not fit.
  TempDir dir;
  TempDir reference;
  const auto request = [](const TempDir& where) {
    return std::vector<std::string>{"simulate",
                                    std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml",
                                    "--scans",
                                    "1",
                                    "--sensors",
                                    "lidar",
                                    "--points",
                                    where.file("points.ply"),
                                    "--trajectory",
                                    where.file("path.txt"),
                                    "--truth",
                                    where.file("truth.csv"),
                                    "--truth-resolution",
                                    "0.005",
                                    "-q"};
  };
  const RunResult full = runRaymap(request(reference));
  ASSERT_EQ(full.exit_code, 0) << describe(full);
  const std::uintmax_t limit_kib = kibFor(std::max(fs::file_size(reference.file("points.ply")),
                                                   fs::file_size(reference.file("path.txt"))));
  ASSERT_GT(fs::file_size(reference.file("truth.csv")), limit_kib * 1024)
      << "the truth CSV must be the file that does not fit";
  const std::set<std::string> before = listFiles(dir.path());

  // Act
  const RunResult r = runRaymapWithFileLimit(limit_kib, request(dir));

  // Assert
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "raymap simulate: error: --truth"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

// ---------------------------------------------------------------------------------------------
// Signals: SIGINT and SIGTERM stop the command and remove its temporaries
// ---------------------------------------------------------------------------------------------

/// A raymap process started in the background, its output going to files.
struct Started {
  pid_t pid = -1;
  std::string out;
  std::string err;
};

/// Starts raymap with `args`, stdout and stderr into files in `dir`, and SIGINT, SIGTERM and
/// SIGHUP at their default action whatever this process inherited (a shell's background job
/// ignores SIGINT, and an ignored signal stays ignored across exec).
Started startRaymap(const TempDir& dir, const std::vector<std::string>& args) {
  Started started{-1, dir.file("stdout.txt"), dir.file("stderr.txt")};
  std::vector<std::string> words = {RAYMAP_CLI_PATH};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& word : words) {
    argv.push_back(word.data());
  }
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, started.out.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, started.err.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;
  sigemptyset(&defaults);
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    sigaddset(&defaults, signal_number);
  }
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  const int spawned =
      ::posix_spawn(&started.pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) {
    ADD_FAILURE() << "cannot start raymap: " << platform::errnoText(spawned);
    started.pid = -1;
  }
  return started;
}

/// Waits for the process; returns its exit code, or 128 + the signal that ended it.
int waitFor(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

/// True when a file of `dir` whose name starts with `prefix` exists.
bool anyNameStartsWith(const fs::path& dir, const std::string& prefix) {
  for (const std::string& name : listFiles(dir)) {
    if (name.rfind(prefix, 0) == 0) {
      return true;
    }
  }
  return false;
}

/// Names in `dir` that look like a temporary file of any raymap version.
std::vector<std::string> temporariesIn(const fs::path& dir) {
  std::vector<std::string> found;
  for (const std::string& name : listFiles(dir)) {
    if (name.find(".raymap-tmp-") != std::string::npos ||
        name.find(".part-") != std::string::npos || name.find(".tmp-") != std::string::npos ||
        name.find(".probe-") != std::string::npos) {
      found.push_back(name);
    }
  }
  return found;
}

class StoppedBySignal : public testing::TestWithParam<int> {};

TEST_P(StoppedBySignal, PopulateRemovesItsTemporariesAndWritesNothing) {
  // Arrange: a recording big enough that mapping and saving it take a while.
  TempDir inputs;
  TempDir dir;
  sim::YardScanConfig config;
  config.scans = 40;
  const std::string input = inputs.file("big.ply");
  writeRayCloud(input, sim::simulateYardScans(config));
  const std::set<std::string> before = listFiles(dir.path());

  // Act: the signal goes as soon as an output file of any name appears (this raymap stages its
  // outputs before it starts; older ones made them only while saving). The test does not rely
  // on catching the run: a run that finished first must have written everything instead.
  const Started run = startRaymap(
      dir, {"populate", input, "--output", dir.file("out.rmap"), "--ply", dir.file("out.ply"),
            "--stats-json", dir.file("out.json"), "--threads", "1", "-q"});
  ASSERT_GT(run.pid, 0);
  int status = 0;
  bool exited = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!anyNameStartsWith(dir.path(), "out.") && std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(run.pid, &status, WNOHANG) == run.pid) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  int exit_code = 0;
  if (exited) {
    exit_code = WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
  } else {
    ::kill(run.pid, GetParam());
    exit_code = waitFor(run.pid);
  }

  // Assert
  const std::string err = readFile(run.err);
  EXPECT_TRUE(temporariesIn(dir.path()).empty())
      << "left behind: " << temporariesIn(dir.path()).front() << "\n"
      << err;
  if (exit_code == 0) {
    for (const char* name : {"out.rmap", "out.ply", "out.json"}) {
      EXPECT_TRUE(fs::exists(dir.file(name))) << name;
    }
    return;
  }
  EXPECT_EQ(exit_code, 128 + GetParam()) << err;
  EXPECT_TRUE(contains(err, "raymap populate: interrupted by "));
  std::set<std::string> expected = before;
  expected.insert({"stdout.txt", "stderr.txt"});
  if (contains(err, "while putting its outputs in place")) {
    // The signal came during the final renames, which it waits for: all outputs are there.
    expected.insert({"out.rmap", "out.ply", "out.json"});
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), expected));
  EXPECT_EQ(listFiles(dir.path()), expected);
}

INSTANTIATE_TEST_SUITE_P(CliOutputs, StoppedBySignal, testing::Values(SIGINT, SIGTERM),
                         [](const testing::TestParamInfo<int>& param_info) {
                           return std::string(param_info.param == SIGINT ? "SIGINT" : "SIGTERM");
                         });

// ---------------------------------------------------------------------------------------------
// SIGKILL: the temporaries of a dead process go when the same output is written again
// ---------------------------------------------------------------------------------------------

/// The pid of a process that has exited and been reaped (`true`, run to its end).
pid_t deadPid() {
  pid_t pid = -1;
  char name[] = "true";
  char* argv[] = {name, nullptr};
  if (::posix_spawnp(&pid, name, nullptr, nullptr, argv, environ) != 0) {
    ADD_FAILURE() << "cannot run true";
    return -1;
  }
  waitFor(pid);
  return pid;
}

TEST(CliOutputs, StaleTemporariesOfDeadProcessesAreRemovedAndReported) {
  // Arrange: what SIGKILLed runs left for out.rmap (a pid beyond any pid_max, and one that has
  // exited), and files that are not such leftovers and must stay.
  TempDir dir;
  const std::string input = yardCloud(dir);
  const std::string map = dir.file("out.rmap");
  const std::vector<std::string> stale = {map + ".raymap-tmp-" + std::to_string(INT_MAX - 7),
                                          map + ".raymap-tmp-" + std::to_string(deadPid())};
  const std::vector<std::string> kept = {
      map + ".raymap-tmp-" + std::to_string(::getpid()),  // a live process: this test
      dir.file("other.rmap.raymap-tmp-" + std::to_string(INT_MAX - 7)),  // another output
      map + ".raymap-tmp-12x",                                           // not a pid
      map + ".raymap-tmp-0123",                     // not as raymap writes a pid
      map + ".tmp-" + std::to_string(INT_MAX - 7),  // not raymap's pattern
  };
  for (const std::string& path : stale) {
    writeText(path, "half a map");
  }
  for (const std::string& path : kept) {
    writeText(path, "not ours to remove");
  }
  fs::create_directory(map + ".raymap-tmp-" + std::to_string(INT_MAX - 8));  // not a file

  // Act
  const RunResult r = runRaymap({"populate", input, "--max-range", "8", "--output", map, "-q"});

  // Assert
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (const std::string& path : stale) {
    EXPECT_FALSE(fs::exists(path)) << path;
    EXPECT_TRUE(contains(r.err, "raymap populate: removed '" + path + "'"));
  }
  for (const std::string& path : kept) {
    EXPECT_EQ(readFile(path), "not ours to remove") << path;
    EXPECT_FALSE(contains(r.err, path));
  }
  EXPECT_TRUE(fs::is_directory(map + ".raymap-tmp-" + std::to_string(INT_MAX - 8)));
  EXPECT_TRUE(fs::exists(map));
}

// ---------------------------------------------------------------------------------------------
// Outputs that are inputs
// ---------------------------------------------------------------------------------------------

/// How an output names the input file.
enum class Spelling { kSame, kOtherPath, kSymlink, kHardLink };

class OutputIsTheInput : public testing::TestWithParam<Spelling> {
 protected:
  /// Another name for `input` (in its directory), made as GetParam() says.
  std::string aliasOf(const std::string& input) const {
    const fs::path path(input);
    switch (GetParam()) {
      case Spelling::kSame:
        return input;
      case Spelling::kOtherPath:
        return (path.parent_path() / "." / ".." / path.parent_path().filename() / path.filename())
            .string();
      case Spelling::kSymlink:
        fs::create_symlink(path.filename(), path.parent_path() / "alias");
        return (path.parent_path() / "alias").string();
      case Spelling::kHardLink:
        fs::create_hard_link(path, path.parent_path() / "alias");
        return (path.parent_path() / "alias").string();
    }
    return input;
  }
};

TEST_P(OutputIsTheInput, PopulateRefusesBeforeAnyWork) {
  for (const char* option : {"--output", "--ply", "--stats-json"}) {
    SCOPED_TRACE(option);
    // Arrange
    TempDir dir;
    const std::string input = yardCloud(dir);
    const std::string alias = aliasOf(input);
    const std::string bytes = readFile(input);
    const std::set<std::string> before = listFiles(dir.path());

    // Act
    const RunResult r = runRaymap({"populate", input, "--max-range", "8", option, alias, "-q"});

    // Assert
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_TRUE(contains(r.err, "raymap populate: error: " + std::string(option) + " '" + alias +
                                    "' is the same file as the input '" + input + "'"));
    EXPECT_TRUE(readFile(input) == bytes) << "the input was changed";
    EXPECT_TRUE(nothingNewIn(dir.path(), before));
  }
}

INSTANTIATE_TEST_SUITE_P(CliOutputs, OutputIsTheInput,
                         testing::Values(Spelling::kSame, Spelling::kOtherPath, Spelling::kSymlink,
                                         Spelling::kHardLink),
                         [](const testing::TestParamInfo<Spelling>& param_info) {
                           switch (param_info.param) {
                             case Spelling::kSame:
                               return std::string("SamePath");
                             case Spelling::kOtherPath:
                               return std::string("OtherPath");
                             case Spelling::kSymlink:
                               return std::string("Symlink");
                             case Spelling::kHardLink:
                               return std::string("HardLink");
                           }
                           return std::string();
                         });

TEST(CliOutputs, EveryCommandRefusesToOverwriteItsInputs) {
  // Arrange
  TempDir dir;
  const std::string cloud = yardCloud(dir);
  const std::string map = yardMap(dir);
  ASSERT_FALSE(map.empty());
  const std::string scene = dir.file("stairs.yaml");
  fs::copy_file(std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml", scene);
  const std::string trajectory = dir.file("path.txt");
  writeText(trajectory, "0 0 0 1\n100 0 0 1\n");
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"heightmap", map, "--center", "0,0,0", "--png", map},
       "--png '" + map + "' is the same file as the map"},
      {{"heightmap", map, "--center", "0,0,0", "--csv", map},
       "--csv '" + map + "' is the same file as the map"},
      {{"export", map, "--ply", map}, "--ply '" + map + "' is the same file as the map"},
      {{"simulate", scene, "--truth", scene},
       "--truth '" + scene + "' is the same file as the scene file"},
      {{"populate", cloud, "--trajectory", trajectory, "--output", trajectory},
       "--output '" + trajectory + "' is the same file as --trajectory"},
      {{"bench", cloud, "--json", cloud}, "--json '" + cloud + "' is the same file as the input"},
  };
  const std::set<std::string> before = listFiles(dir.path());
  std::vector<std::string> contents;
  for (const std::string& name : before) {
    contents.push_back(readFile(dir.file(name)));
  }

  for (const Case& c : cases) {
    SCOPED_TRACE(c.args.front());
    // Act
    const RunResult r = runRaymap(c.args);

    // Assert
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_TRUE(contains(r.err, "raymap " + c.args.front() + ": error: " + c.expected));
  }
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
  std::size_t i = 0;
  for (const std::string& name : before) {
    EXPECT_TRUE(readFile(dir.file(name)) == contents[i++]) << name << " was changed";
  }
}

TEST(CliOutputs, TwoOutputsOnOneFileAreRefused) {
  // Arrange
  TempDir dir;
  const std::string cloud = yardCloud(dir);
  const std::set<std::string> before = listFiles(dir.path());

  // Act: the same file by two spellings.
  const RunResult r = runRaymap({"populate", cloud, "--output", dir.file("out"), "--ply",
                                 (dir.path() / "." / "out").string(), "-q"});

  // Assert
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "is also the file of --output '" + dir.file("out") + "'"));
  EXPECT_TRUE(nothingNewIn(dir.path(), before));
}

}  // namespace
}  // namespace raymap::test
