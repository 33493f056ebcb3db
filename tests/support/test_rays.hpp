// SPDX-License-Identifier: BSD-3-Clause
// Helpers to build maps and integrate rays in tests.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "src/map/backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::test {

/// @brief A ray from `origin` to `sample` (world frame, metres) with optional flags and scan.
Ray makeRay(Vec3d origin, Vec3d sample, std::uint32_t flags = 0, std::uint64_t scan = 0);

/// @brief A small test map: `semantics`, regions of `region_voxels`^3 at 0.1 m, a 256 MiB pool.
MapConfig smallConfig(Semantics semantics, std::int32_t region_voxels = 8);

/// @brief A decay-rate map (the traversal layer) of `mode` on smallConfig, with a 2 GiB pool.
MapConfig decayConfig(Semantics semantics = Semantics::kPerRay, MapMode mode = MapMode::kOccupancy,
                      std::int32_t region_voxels = 16);

/// @brief A voxel's decay rate, reflections per metre (rm_decay_rate: NaN where no ray entered).
float decayRate(const VoxelMap& map, Vec3i voxel);

/// @brief Creates a map or fails the test.
VoxelMap makeMap(const MapConfig& config);

/// @brief Prepares `rays` and integrates them: per-ray maps in one batch, per-scan maps one batch
/// per run of equal `scan` values. Fails the test on any error. Returns the preparer's counters.
RayCounters integrate(VoxelMap& map, Backend& backend, std::span<const Ray> rays,
                      const RayFilter& filter = {});

/// @brief `scans` scans of `rays_per_scan` random rays (0.2-12 m, flattened in z) from random
/// origins within +-2 m; every 17th ray is a no-return ray. Deterministic for a seed.
std::vector<Ray> randomScans(std::uint64_t seed, int scans, int rays_per_scan);
/// @brief `count` rays whose ends lie on a lattice of `step` metres (voxel faces, edges and
/// corners at 0.1 m with a step of a quarter voxel), within +-40 steps, the sample's x and y
/// stretched by `stretch` (longer rays crossing region faces too): where walks decide ties.
std::vector<Ray> latticeRays(std::uint64_t seed, int count, double step, int stretch = 1);

/// @brief A drive down a long corridor (walls at y = +-3 m, floor at 0, ceiling at 2.5 m, a 1 m
/// crate every 10 m): a scan every `step` metres from (x, 0, 1) for x in [0, length], 32
/// azimuths x 8 elevations, each ray ending on the first surface or as a no-return at 4 m.
/// A scan touches only the regions within 4 m of the sensor while the map grows with the length:
/// the data of the tests of maps larger than their memory. Deterministic.
std::vector<Ray> corridorDrive(double length, double step);

/// @brief `config` with a pool of `regions` regions and the cold tiers on: a compressed tier of
/// `compressed_bytes`, the spill file in `spill_dir` (empty: none).
MapConfig withTiers(MapConfig config, std::uint64_t regions, std::uint64_t compressed_bytes,
                    const std::string& spill_dir);

/// @brief Integrates `rays` 256 at a time (one corridorDrive() scan), letting the compressor catch
/// up after each batch, until a batch fails; returns the first failure, or success.
Expected<void, IntegrateError> integrateUntilFailure(VoxelMap& map, Backend& backend,
                                                     const std::vector<Ray>& rays);

/// @brief integrate() one scan (run of equal `scan`) per batch, then synchronise(): a batch's
/// regions must fit a tiered map's pool at once.
void integrateEachScan(VoxelMap& map, Backend& backend, const std::vector<Ray>& rays);

/// @brief Writes `rays` as a ray-cloud PLY (io::RayCloudWriter) or fails the test.
void writeRayCloud(const std::string& path, const std::vector<Ray>& rays);

/// @brief Creates a CPU backend with `threads` workers or fails the test.
std::unique_ptr<Backend> cpuBackend(VoxelMap& map, unsigned threads);

/// @brief The cube room of the exact-expectation tests (see test_rays.cpp): the sensor sits at
/// the centre of voxel (0,0,0); one ray goes to the centre of every wall voxel at +-`half`
/// voxels, except the wall edges. Every such ray crosses only interior voxels and its own wall
/// voxel.
std::vector<Ray> cubeRoomRays(double resolution, int half);

/// @brief Compares two maps voxel by voxel over the union of their regions: the fraction of
/// voxels (observed in either) with equal state, and whether all occupancy values match exactly.
struct MapComparison {
  std::uint64_t compared = 0;
  std::uint64_t same_state = 0;
  std::uint64_t exact_value = 0;
  double sameStateFraction() const {
    return compared ? double(same_state) / double(compared) : 1.0;
  }
};
/// @brief Voxel by voxel over the regions either map holds (resident ones, on a tiered map): how
/// many are observed in either, in the same state, and bit-identical in occupancy. The maps must
/// have one region size (a test failure otherwise).
MapComparison compareMaps(const VoxelMap& a, const VoxelMap& b);

}  // namespace raymap::test
