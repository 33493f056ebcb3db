// SPDX-License-Identifier: BSD-3-Clause
// raymap-mapper-bench: raymap::Mapper's integration rate through the public C++ API, the
// baseline of the Python module's benchmark (tools/bench/python_mapper_bench.py does the same
// from Python). The recording's scans are read into memory first; each repetition then builds a
// fresh Mapper and integrates every scan (Mapper::integrate(span<const WorldRay>)) and flushes.
// Prints one JSON object: rays, the median seconds and rays per second.
//   raymap-mapper-bench RECORDING [--repeat N] [--semantics ray|scan] [--threads N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include "raymap/recording.hpp"

namespace {

struct Args {
  std::string recording;
  int repeat = 5;
  std::string semantics = "ray";
  unsigned threads = 0;
};

bool parse(int argc, char** argv, Args& args) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--repeat" && has_value) {
      args.repeat = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--semantics" && has_value) {
      args.semantics = argv[++i];
    } else if (a == "--threads" && has_value) {
      args.threads = static_cast<unsigned>(std::atoi(argv[++i]));
    } else if (args.recording.empty() && a.rfind("--", 0) != 0) {
      args.recording = a;
    } else {
      return false;
    }
  }
  return !args.recording.empty() && (args.semantics == "ray" || args.semantics == "scan");
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!parse(argc, argv, args)) {
    std::fprintf(stderr,
                 "usage: raymap-mapper-bench RECORDING [--repeat N] [--semantics ray|scan] "
                 "[--threads N]\n");
    return 2;
  }
  auto reader = raymap::RecordingReader::open(args.recording);
  if (!reader) {
    std::fprintf(stderr, "raymap-mapper-bench: %s\n", reader.error().message.c_str());
    return 1;
  }
  std::vector<std::vector<raymap::WorldRay>> scans;
  std::size_t rays = 0;
  for (std::vector<raymap::WorldRay> scan;;) {
    auto more = reader->nextScan(scan);
    if (!more) {
      std::fprintf(stderr, "raymap-mapper-bench: %s\n", more.error().message.c_str());
      return 1;
    }
    if (!*more) {
      break;
    }
    rays += scan.size();
    scans.push_back(scan);
  }
  raymap::MapperConfig config;
  config.map.semantics =
      args.semantics == "scan" ? raymap::Semantics::kPerScan : raymap::Semantics::kPerRay;
  config.backend.threads = args.threads;
  std::vector<double> seconds;
  for (int r = 0; r < args.repeat; ++r) {
    auto mapper = raymap::Mapper::create(config);
    if (!mapper) {
      std::fprintf(stderr, "raymap-mapper-bench: %s\n", mapper.error().message.c_str());
      return 1;
    }
    const auto start = std::chrono::steady_clock::now();
    for (const std::vector<raymap::WorldRay>& scan : scans) {
      if (auto ok = mapper->integrate(scan); !ok) {
        std::fprintf(stderr, "raymap-mapper-bench: %s\n", ok.error().message.c_str());
        return 1;
      }
    }
    if (auto ok = mapper->flush(); !ok) {
      std::fprintf(stderr, "raymap-mapper-bench: %s\n", ok.error().message.c_str());
      return 1;
    }
    seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(seconds.begin(), seconds.end());
  const double median = seconds[seconds.size() / 2];
  std::printf(
      "{\"api\": \"c++\", \"recording\": \"%s\", \"scans\": %zu, \"rays\": %zu, "
      "\"semantics\": \"%s\", \"repeat\": %d, \"median_s\": %.6f, \"rays_per_s\": %.0f}\n",
      args.recording.c_str(), scans.size(), rays, args.semantics.c_str(), args.repeat, median,
      static_cast<double>(rays) / median);
  return 0;
}
