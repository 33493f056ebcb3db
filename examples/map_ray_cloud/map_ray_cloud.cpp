// SPDX-License-Identifier: BSD-3-Clause
// Maps a ray-cloud PLY with raymap::Mapper and prints the occupied and free voxel counts and the
// occupancy at a few points along the first ray.
//   map_ray_cloud CLOUD.ply [--semantics ray|scan] [--resolution METRES] [--save MAP.rmap]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <raymap/mapper.hpp>
#include <raymap/ray_cloud.hpp>

namespace {

const char* name(raymap::VoxelState state) {
  switch (state) {
    case raymap::VoxelState::kOccupied:
      return "occupied";
    case raymap::VoxelState::kFree:
      return "free";
    case raymap::VoxelState::kUnobserved:
      break;
  }
  return "unobserved";
}

int failed(const raymap::Error& error) {
  std::fprintf(stderr, "map_ray_cloud: %s\n", error.message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: map_ray_cloud CLOUD.ply [--semantics ray|scan] [--resolution METRES] "
                 "[--save MAP.rmap]\n");
    return 2;
  }
  raymap::MapperConfig config;  // the defaults of `raymap populate`
  std::string save_path;
  for (int i = 2; i < argc; i += 2) {
    const std::string option = argv[i];
    if (i + 1 == argc) {  // an option without its value is a mistake, not a default
      std::fprintf(stderr, "map_ray_cloud: %s needs a value\n", option.c_str());
      return 2;
    }
    const std::string value = argv[i + 1];
    if (option == "--semantics") {
      if (value != "ray" && value != "scan") {
        std::fprintf(stderr, "map_ray_cloud: --semantics must be ray or scan (got '%s')\n",
                     value.c_str());
        return 2;
      }
      config.map.semantics =
          value == "scan" ? raymap::Semantics::kPerScan : raymap::Semantics::kPerRay;
    } else if (option == "--resolution") {
      char* end = nullptr;
      config.map.resolution = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0') {
        std::fprintf(stderr, "map_ray_cloud: --resolution must be a number of metres (got '%s')\n",
                     value.c_str());
        return 2;
      }
    } else if (option == "--save") {
      save_path = value;
    } else {
      std::fprintf(stderr, "map_ray_cloud: unknown option %s\n", option.c_str());
      return 2;
    }
  }

  auto mapper = raymap::Mapper::create(config);
  if (!mapper) {
    return failed(mapper.error());
  }
  auto reader = raymap::RayCloudReader::open(argv[1]);
  if (!reader) {
    return failed(reader.error());
  }
  std::vector<raymap::WorldRay> scan;
  std::vector<raymap::WorldRay> first_scan;
  for (;;) {
    auto more = reader->nextScan(scan);
    if (!more) {
      return failed(more.error());
    }
    if (!*more) {
      break;
    }
    if (first_scan.empty()) {
      first_scan = scan;
    }
    if (auto ok = mapper->integrate(scan); !ok) {
      return failed(ok.error());
    }
  }
  if (auto ok = mapper->flush(); !ok) {
    return failed(ok.error());
  }

  const raymap::MapCounts counts = mapper->counts();
  const raymap::MapperCounters counters = mapper->counters();
  std::printf("rays_in %llu\nrays_integrated %llu\nscans %llu\n",
              static_cast<unsigned long long>(counters.rays_in),
              static_cast<unsigned long long>(counters.rays_integrated),
              static_cast<unsigned long long>(counters.scans));
  std::printf("voxels_occupied %llu\nvoxels_free %llu\n",
              static_cast<unsigned long long>(counts.voxels_occupied),
              static_cast<unsigned long long>(counts.voxels_free));
  if (!first_scan.empty()) {
    // Along the first ray: the sensor, a quarter and half way, the return, a metre beyond it.
    const raymap::WorldRay& ray = first_scan.front();
    const Eigen::Vector3d along = ray.end - ray.origin;
    const std::vector<Eigen::Vector3d> points = {ray.origin, ray.origin + 0.25 * along,
                                                 ray.origin + 0.5 * along, ray.end,
                                                 ray.end + along.normalized()};
    for (const Eigen::Vector3d& p : points) {
      std::printf("occupancy at (%.3f, %.3f, %.3f): %s\n", p.x(), p.y(), p.z(),
                  name(mapper->occupancy(p)));
    }
  }
  if (!save_path.empty()) {
    if (auto ok = mapper->save(save_path); !ok) {
      return failed(ok.error());
    }
  }
  return 0;
}
