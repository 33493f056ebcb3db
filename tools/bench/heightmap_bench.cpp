// SPDX-License-Identifier: BSD-3-Clause
// Google Benchmark of height-map generation: a 20 m x 20 m x 20 m box at 0.1 m (200 x 200
// columns) over a map of the simulated yard, planar and flood fill, on every generator this
// build and machine have (CPU on one thread, OpenCL, CUDA).
// Run: build/release/tools/raymap-heightmap-bench --benchmark_format=json
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/cpu_backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/sim/yard_scan.hpp"
#if defined(RAYMAP_HAVE_OPENCL)
#include "src/device/opencl/opencl_heightmap.hpp"
#endif
#if defined(RAYMAP_HAVE_CUDA)
#include "src/device/cuda/cuda_heightmap.hpp"
#endif

namespace raymap {
namespace {

/// The yard scanned by a 32-beam lidar driven through it (20 scans), integrated once.
const VoxelMap& yardMap() {
  static const std::unique_ptr<VoxelMap> map = [] {
    MapConfig config;
    config.memory_budget_bytes = std::uint64_t{4} << 30;
    auto created = VoxelMap::create(config);
    auto owned = std::make_unique<VoxelMap>(std::move(*created));
    sim::YardScanConfig scan;
    scan.scans = 20;
    scan.lidar.columns = 1024;
    const std::vector<Ray> rays = sim::simulateYardScans(scan);
    RayFilter filter;
    filter.max_range_m = 30.0;
    RayPreparer preparer(*owned, filter);
    std::vector<PreparedRay> prepared(rays.size());
    prepared.resize(preparer.prepare(rays, prepared).written);
    auto backend = createCpuBackend(*owned, CpuBackendOptions{});
    (void)(*backend)->integrate(prepared);
    (void)(*backend)->synchronise();
    return owned;
  }();
  return *map;
}

std::unique_ptr<heightmap::HeightmapGenerator> makeGenerator(int id, std::string* why) {
  if (id == 0) {
    return heightmap::makeCpuHeightmapGenerator();
  }
#if defined(RAYMAP_HAVE_OPENCL)
  if (id == 1) {
    auto g = createOpenClHeightmapGenerator({});
    if (g) {
      return std::move(*g);
    }
    *why = g.error().message;
    return nullptr;
  }
#endif
#if defined(RAYMAP_HAVE_CUDA)
  if (id == 2) {
    auto g = createCudaHeightmapGenerator({});
    if (g) {
      return std::move(*g);
    }
    *why = g.error().message;
    return nullptr;
  }
#endif
  *why = "not built";
  return nullptr;
}

/// Args: generator (0 cpu, 1 opencl, 2 cuda), mode (0 planar, 1 fill).
void BM_Heightmap(benchmark::State& state) {
  std::string why;
  auto generator = makeGenerator(static_cast<int>(state.range(0)), &why);
  if (!generator) {
    state.SkipWithError(why.c_str());
    return;
  }
  const VoxelMap& map = yardMap();
  heightmap::HeightmapOptions options;
  options.centre = {0.0, 0.0, 0.0};
  options.size = 20.0;
  options.mode =
      state.range(1) == 0 ? heightmap::HeightmapMode::kPlanar : heightmap::HeightmapMode::kFill;
  options.virtual_surfaces = true;
  heightmap::HeightmapPlan plan;
  if (!heightmap::planHeightmap(map, options, plan)) {
    state.SkipWithError("planning failed");
    return;
  }
  heightmap::HeightMap out;
  (void)generator->generate(map, plan, out);  // buffers and program warm
  for (auto _ : state) {
    if (!generator->generate(map, plan, out)) {
      state.SkipWithError("generation failed");
      break;
    }
  }
  std::size_t surfaces = 0;
  for (std::uint32_t kind : out.kind) {
    surfaces += kind == RM_HM_SURFACE ? 1 : 0;
  }
  state.SetLabel(std::string(generator->name()) + " " +
                 std::string(heightmap::toString(options.mode)) + " 200x200 " +
                 generator->deviceName());
  state.counters["cells"] = static_cast<double>(out.cellCount());
  state.counters["surface_cells"] = static_cast<double>(surfaces);
}
BENCHMARK(BM_Heightmap)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace raymap

BENCHMARK_MAIN();
