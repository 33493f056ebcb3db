// SPDX-License-Identifier: BSD-3-Clause
// The height-map generators: one interface, a CPU implementation here, device implementations in
// src/device/opencl and src/device/cuda. All run the column search of kernels/common/heightmap.h,
// so they produce the same height map.
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "raymap/error.hpp"

#include "src/heightmap/height_map.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::heightmap {

/// @brief Generates height maps from a map.
/// Where the map is read depends on the generator (readsHostStore()): the CPU generator and a
/// device generator with its own context read the host store, so a map integrated by a device
/// backend must be synchronised (Backend::synchronise()) first; a device generator created over
/// the integration backend reads the layers where the backend left them and needs no
/// synchronisation (it does what it needs itself).
/// Thread-safety: one generator per thread; generate() reads the map, which must not be updated
/// meanwhile. Real-time: generate() allocates only when `out` or the device buffers must grow
/// (the first call for a grid size), and performs no I/O.
class HeightmapGenerator {
 public:
  virtual ~HeightmapGenerator() = default;
  /// "cpu", "opencl" or "cuda".
  virtual const char* name() const noexcept = 0;
  /// The device it runs on, for logs ("cpu" on the host).
  virtual std::string deviceName() const { return name(); }
  /// @brief Runs `plan` (from planHeightmap() on the same map) into `out`: its geometry is the
  /// plan's grid and every layer is written.
  virtual Expected<void, Error> generate(const VoxelMap& map, const HeightmapPlan& plan,
                                         HeightMap& out) = 0;
  /// @brief Bytes copied between host and device by every generate() so far (uploads of the map's
  /// layers and the plan, read-backs of the output): 0 on the host.
  virtual std::uint64_t bytesCopied() const noexcept { return 0; }
  /// @brief Of bytesCopied(): the map's layers copied to the device (regions under the box
  /// uploaded); 0 on the host, and where the device already held them.
  virtual std::uint64_t mapBytesCopied() const noexcept { return 0; }
  /// @brief True when generate() reads the map's host store (which must then be current).
  virtual bool readsHostStore() const noexcept { return true; }
  /// @brief Reserves what generate() needs for plans over up to `regions` regions of `map`
  /// (start-up: a real-time caller's cycles then allocate nothing on the host as the box meets
  /// more regions). Default: nothing to reserve.
  virtual void reserveHostScratch(const VoxelMap& map, std::size_t regions) {
    (void)map;
    (void)regions;
  }
};

/// @brief The CPU generator: one thread (a 200 x 200 planar map takes a few milliseconds).
std::unique_ptr<HeightmapGenerator> makeCpuHeightmapGenerator();

/// @brief Copies the plan's geometry into `out` and sizes its layers.
void prepareOutput(const HeightmapPlan& plan, HeightMap& out);

}  // namespace raymap::heightmap
