// SPDX-License-Identifier: BSD-3-Clause
// Google Benchmark micro-benchmarks of the mapping core on generated data: the line walk alone,
// and whole-batch integration of a simulated lidar scan per semantics and thread count.
// Run: build/release/tools/raymap-microbench --benchmark_format=json
#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "kernels/common/line_walk.h"
#include "src/map/cpu_backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/sim/yard_scan.hpp"

namespace raymap {
namespace {

/// Random rays of a given length in voxels from a voxel centre.
std::vector<rm_vec3f> randomEnds(int count, float length_voxels) {
  std::mt19937 rng(5489);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<rm_vec3f> ends(static_cast<std::size_t>(count));
  for (rm_vec3f& e : ends) {
    const float x = u(rng);
    const float y = u(rng);
    const float z = 0.3f * u(rng);  // lidar-like: mostly horizontal
    const float n = std::sqrt(x * x + y * y + z * z);
    e = rm_vec3f{0.5f + x / n * length_voxels, 0.5f + y / n * length_voxels,
                 0.5f + z / n * length_voxels};
  }
  return ends;
}

void BM_LineWalk(benchmark::State& state) {
  const auto ends = randomEnds(4096, static_cast<float>(state.range(0)));
  std::int64_t steps = 0;
  for (auto _ : state) {
    for (const rm_vec3f& e : ends) {
      rm_line_walk w;
      const rm_vec3i end_voxel{static_cast<rm_i32>(std::floor(e.x)),
                               static_cast<rm_i32>(std::floor(e.y)),
                               static_cast<rm_i32>(std::floor(e.z))};
      rm_line_walk_init(&w, rm_vec3f{0.5f, 0.5f, 0.5f}, e, end_voxel);
      rm_i32 axis_sum = 0;
      for (rm_i32 axis = rm_line_walk_next(&w); axis >= 0; axis = rm_line_walk_next(&w)) {
        axis_sum += axis;
        ++steps;
      }
      benchmark::DoNotOptimize(axis_sum);
    }
  }
  state.counters["steps_per_second"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LineWalk)->Arg(16)->Arg(200)->Arg(10000);

/// One simulated 64-beam scan of the built-in yard, prepared once.
const std::vector<Ray>& yardScan() {
  static const std::vector<Ray> rays = [] {
    sim::YardScanConfig config;
    config.scans = 1;
    config.lidar.beams = 64;
    config.lidar.columns = 1024;
    return sim::simulateYardScans(config);
  }();
  return rays;
}

void BM_IntegrateScan(benchmark::State& state) {
  const Semantics semantics = state.range(0) == 0 ? Semantics::kPerRay : Semantics::kPerScan;
  const auto threads = static_cast<unsigned>(state.range(1));
  MapConfig config;
  config.semantics = semantics;
  config.memory_budget_bytes = std::uint64_t{2} << 30;
  auto map = VoxelMap::create(config);
  CpuBackendOptions options;
  options.threads = threads;
  auto backend = createCpuBackend(*map, options);
  RayFilter filter;
  filter.max_range_m = 20.0;
  RayPreparer preparer(*map, filter);
  const std::vector<Ray>& rays = yardScan();
  std::vector<PreparedRay> prepared(rays.size());
  const auto p = preparer.prepare(rays, prepared);
  prepared.resize(p.written);
  // Regions are created in the first pass; later passes measure steady-state integration.
  (void)(*backend)->integrate(prepared);
  for (auto _ : state) {
    if (!(*backend)->integrate(prepared)) {
      state.SkipWithError("integration failed");
      break;
    }
  }
  state.counters["rays_per_second"] = benchmark::Counter(
      static_cast<double>(prepared.size()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IntegrateScan)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"per_scan", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace raymap

BENCHMARK_MAIN();
