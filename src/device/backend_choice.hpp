// SPDX-License-Identifier: BSD-3-Clause
// Which integration backend a command uses, and creating it (with the optional CPU fallback).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "raymap/error.hpp"

#include "src/heightmap/heightmap_generator.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::backends {

/// @brief The backend options of the mapping commands (--backend and friends).
struct BackendChoice {
  std::string name = "cpu";     ///< "cpu", "opencl" or "cuda"
  unsigned threads = 0;         ///< CPU: 0 = all cores, 1 = the single-threaded reference
  std::string opencl_platform;  ///< index or name substring; empty = default
  std::string opencl_device;    ///< index or name substring; empty = first GPU, else first device
  int cuda_device = 0;          ///< CUDA device ordinal
  std::uint64_t gpu_cache_bytes = 0;      ///< device region cache; 0 = automatic
  std::uint32_t gpu_cache_regions = 0;    ///< device region cache in regions (overrides bytes)
  std::string gpu_memory = "auto";        ///< "auto", "cache" or "shared"
  std::string opencl_span_work = "auto";  ///< "auto", "span" or "region" (SpanWork)
  std::string device_planning = "host";   ///< "host" or "device" (gpu::Planning)
  std::size_t gpu_batch_rays = std::size_t{1} << 18;
  bool fallback_cpu = false;  ///< use the CPU backend (with a warning) if the device fails to start
};

/// @brief A created backend, and the warning to show when the fallback was taken.
struct CreatedBackend {
  std::unique_ptr<Backend> backend;
  std::string fallback_warning;  ///< empty unless the CPU fallback replaced the requested backend
  std::string startup_warning;   ///< the backend's Backend::startupWarning()
};

/// @brief Creates the chosen backend for `map`. Errors say what failed and what to do (install
/// a driver, pick another device, backend.fallback: cpu), naming options by configuration key.
Result<CreatedBackend> createBackend(VoxelMap& map, const BackendChoice& choice);

/// @brief A created height-map generator, and the warning to show when the fallback was taken.
struct CreatedHeightmapGenerator {
  std::unique_ptr<heightmap::HeightmapGenerator> generator;
  std::string fallback_warning;
};
/// @brief The height-map generator of the chosen backend (cpu, opencl, cuda; device selection and
/// --fallback as for mapping).
Result<CreatedHeightmapGenerator> createHeightmapGenerator(const BackendChoice& choice);
/// @brief The height-map generator for the map `backend` integrates, running where it runs: on
/// a device backend, that device's generator in the backend's own context (one context per
/// process: it reads the map's layers where integration left them, and nothing needs
/// Backend::synchronise() first); on the CPU backend, the CPU generator.
Result<CreatedHeightmapGenerator> createHeightmapGenerator(Backend& backend);
/// @brief The backends this build has, e.g. {"cpu", "opencl", "cuda"}.
std::vector<std::string> availableBackends();

}  // namespace raymap::backends
