// SPDX-License-Identifier: BSD-3-Clause
// Maps a recording — a ray-cloud PLY, a point cloud with a trajectory, or a rosbag2 bag (lidar
// clouds with odometry or TF, depth images with CameraInfo) — with raymap::RecordingReader and
// raymap::Mapper, in any map mode, through a memory budget with the cold tiers on, and saves
// the map: what `raymap populate IN --mode MODE --max-memory SIZE -o OUT` does, as a library
// call. Prints the scans and voxel counts.
//   map_recording IN OUT.rmap [--mode occupancy|ndt-om|ndt-tm|tsdf|decay] [--topic T]
//                 [--trajectory FILE] [--max-memory-mib N]
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <raymap/mapper.hpp>
#include <raymap/recording.hpp>

namespace {

int failed(const raymap::Error& error) {
  std::fprintf(stderr, "map_recording: %s\n", error.message.c_str());
  return 1;
}

int usage(const std::string& why) {
  std::fprintf(stderr,
               "map_recording: %s\nusage: map_recording IN OUT.rmap [--mode MODE] [--topic T] "
               "[--trajectory FILE] [--max-memory-mib N]\n",
               why.c_str());
  return 2;
}

/// --mode as MapOptions: "decay" is decay rates without occupancy.
bool setMode(const std::string& mode, raymap::MapOptions& map) {
  if (mode == "occupancy") {
    map.mode = raymap::MapMode::kOccupancy;
  } else if (mode == "ndt-om") {
    map.mode = raymap::MapMode::kNdtOm;
  } else if (mode == "ndt-tm") {
    map.mode = raymap::MapMode::kNdtTm;
  } else if (mode == "tsdf") {
    map.mode = raymap::MapMode::kTsdf;
  } else if (mode == "decay") {
    map.decay_rate = true;
    map.occupancy = false;
  } else {
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    return usage("an input and an output are needed");
  }
  const std::string input = argv[1];
  const std::string output = argv[2];
  raymap::MapperConfig config;  // the defaults of `raymap populate`
  raymap::RecordingOptions read;
  // Maps larger than the budget move their coldest regions to compressed memory, then to an
  // unnamed spill file next to the output (as `raymap populate` does).
  config.map.tiers.enabled = true;
  config.map.tiers.spill_dir = std::filesystem::absolute(output).parent_path().string();
  for (int i = 3; i < argc; i += 2) {
    const std::string option = argv[i];
    if (i + 1 == argc) {
      return usage(option + " needs a value");
    }
    const std::string value = argv[i + 1];
    if (option == "--mode") {
      if (!setMode(value, config.map)) {
        return usage("--mode must be occupancy, ndt-om, ndt-tm, tsdf or decay (got '" + value +
                     "')");
      }
    } else if (option == "--topic") {
      read.bag.topics.push_back(value);
    } else if (option == "--trajectory") {
      read.trajectory_path = value;
    } else if (option == "--max-memory-mib") {
      char* end = nullptr;
      const unsigned long long mib = std::strtoull(value.c_str(), &end, 10);
      if (end == value.c_str() || *end != '\0' || mib == 0) {
        return usage("--max-memory-mib must be a positive whole number (got '" + value + "')");
      }
      config.map.max_memory_bytes = mib << 20;
    } else {
      return usage("unknown option " + option);
    }
  }

  auto mapper = raymap::Mapper::create(config);
  if (!mapper) {
    return failed(mapper.error());
  }
  auto reader = raymap::RecordingReader::open(input, read);
  if (!reader) {
    return failed(reader.error());
  }
  std::vector<raymap::WorldRay> scan;
  for (;;) {
    auto more = reader->nextScan(scan);
    if (!more) {
      return failed(more.error());
    }
    if (!*more) {
      break;
    }
    if (auto ok = mapper->integrate(scan); !ok) {
      return failed(ok.error());
    }
  }
  if (auto ok = mapper->save(output); !ok) {
    return failed(ok.error());
  }
  for (const std::string& warning : reader->warnings()) {
    std::fprintf(stderr, "map_recording: note: %s\n", warning.c_str());
  }
  const raymap::MapCounts counts = mapper->counts();
  std::printf("source %s\nscans %llu\nrays_integrated %llu\nregions %llu\n",
              reader->isBag() ? "bag" : "file",
              static_cast<unsigned long long>(mapper->counters().scans),
              static_cast<unsigned long long>(mapper->counters().rays_integrated),
              static_cast<unsigned long long>(counts.regions));
  std::printf("voxels_occupied %llu\nvoxels_free %llu\n",
              static_cast<unsigned long long>(counts.voxels_occupied),
              static_cast<unsigned long long>(counts.voxels_free));
  return 0;
}
