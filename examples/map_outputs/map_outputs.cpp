// SPDX-License-Identifier: BSD-3-Clause
// What a saved map gives a robot's other software, through raymap::Mapper: a Nav2 costmap around
// a point, written as a map_server map (a PGM image and its YAML: load it with
// `ros2 run nav2_map_server map_server --ros-args -p yaml_filename:=costmap.yaml`), and the map's
// voxels as a PLY point cloud for a viewer (the file `raymap export --mode KIND` writes).
//   map_outputs MAP.rmap OUT_DIR [--centre X Y Z] [--size METRES] [--export KIND]
// KIND: occupied (default), free, mean, decay, ndt, ndt-points, tsdf or tsdf-mesh.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <raymap/mapper.hpp>

namespace {

struct Arguments {
  std::string map;
  std::string out_dir;
  raymap::HeightmapRequest request;
  raymap::ExportKind kind = raymap::ExportKind::kOccupied;
};

bool parse(int argc, char** argv, Arguments& a) {
  if (argc < 3) {
    return false;
  }
  a.map = argv[1];
  a.out_dir = argv[2];
  for (int i = 3; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--centre" && i + 3 < argc) {
      a.request.centre = {std::atof(argv[i + 1]), std::atof(argv[i + 2]), std::atof(argv[i + 3])};
      i += 3;
    } else if (flag == "--size" && i + 1 < argc) {
      a.request.size = std::atof(argv[++i]);
    } else if (flag == "--export" && i + 1 < argc) {
      const auto kind = raymap::exportKindFromName(argv[++i]);
      if (!kind) {
        return false;
      }
      a.kind = *kind;
    } else {
      return false;
    }
  }
  return true;
}

/// map_server's trinary image: lethal black (0), unknown grey (205), free white (254); the first
/// image row is the grid's last (+y) row.
bool writeMapServerMap(const raymap::Costmap& costmap, const std::string& out_dir) {
  std::ofstream pgm(out_dir + "/costmap.pgm", std::ios::binary);
  pgm << "P5\n" << costmap.width << ' ' << costmap.height << "\n255\n";
  for (int y = costmap.height - 1; y >= 0; --y) {
    for (int x = 0; x < costmap.width; ++x) {
      const std::int8_t cost = costmap.cells[static_cast<std::size_t>(x + y * costmap.width)];
      pgm.put(static_cast<char>(cost < 0 ? 205 : cost >= 100 ? 0 : 254));
    }
  }
  std::ofstream yaml(out_dir + "/costmap.yaml");
  yaml << "image: costmap.pgm\nmode: trinary\nresolution: " << costmap.resolution << "\norigin: ["
       << costmap.origin.x() << ", " << costmap.origin.y() << ", 0.0]\n"
       << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n";
  return pgm.good() && yaml.good();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  if (!parse(argc, argv, args)) {
    std::fprintf(stderr,
                 "usage: map_outputs MAP.rmap OUT_DIR [--centre X Y Z] [--size METRES] "
                 "[--export occupied|free|mean|decay|ndt|ndt-points|tsdf|tsdf-mesh]\n");
    return 2;
  }
  auto mapper = raymap::Mapper::load(args.map);
  if (!mapper) {
    std::fprintf(stderr, "map_outputs: %s\n", mapper.error().message.c_str());
    return 1;
  }

  // The costmap: raymapd's default costs (a step over 0.15 m, a slope over 30 degrees or less
  // than 0.5 m of clearance is lethal).
  auto costmap = mapper->costmap(args.request, raymap::CostmapOptions{});
  if (!costmap) {
    std::fprintf(stderr, "map_outputs: costmap: %s\n", costmap.error().message.c_str());
    return 1;
  }
  if (!writeMapServerMap(*costmap, args.out_dir)) {
    std::fprintf(stderr, "map_outputs: cannot write the costmap to %s\n", args.out_dir.c_str());
    return 1;
  }
  int lethal = 0;
  int unknown = 0;
  for (const std::int8_t cost : costmap->cells) {
    lethal += cost >= 100 ? 1 : 0;
    unknown += cost < 0 ? 1 : 0;
  }
  std::printf("costmap: %d x %d cells of %g m, %d lethal, %d unknown\n", costmap->width,
              costmap->height, costmap->resolution, lethal, unknown);

  // The export, as `raymap export MAP --mode KIND --ply OUT_DIR/voxels.ply` writes it.
  raymap::ExportRequest request;
  request.kind = args.kind;
  auto counts = mapper->exportPly(args.out_dir + "/voxels.ply", request);
  if (!counts) {
    std::fprintf(stderr, "map_outputs: export: %s\n", counts.error().message.c_str());
    return 1;
  }
  std::printf("export %s: %llu items\n", std::string(raymap::toString(args.kind)).c_str(),
              static_cast<unsigned long long>(counts->items));
  return 0;
}
