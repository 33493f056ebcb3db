// SPDX-License-Identifier: BSD-3-Clause
// Height maps on an OpenCL device: the kernels of kernels/device/heightmap_kernels.h.
#pragma once
#include <memory>

#include "raymap/error.hpp"

#include "src/device/opencl/cl_runtime.hpp"
#include "src/device/opencl/program_cache.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/map/backend.hpp"

namespace raymap {

/// @brief Which device, and the program cache.
struct OpenClHeightmapOptions {
  opencl::DeviceSelector device;
  opencl::ProgramCacheOptions program_cache;
};

/// @brief Creates an OpenCL height-map generator: picks the device, builds the embedded program
/// (binary cached on disk). generate() uploads the occupancy (and voxel-mean) layer of every map
/// region under the box, runs one work-item per column (flood fill: one launch per ring) and reads
/// the layers back; it produces the same height map as the CPU generator. Device buffers grow to
/// the largest request seen and are then reused (no allocation in steady state).
/// Errors: no platform or device, a program that does not build (the log is in the message), or
/// buffers the device refuses. Thread-safety: one thread at a time.
Result<std::unique_ptr<heightmap::HeightmapGenerator>> createOpenClHeightmapGenerator(
    const OpenClHeightmapOptions& options);

/// @brief Creates an OpenCL height-map generator in the context of `backend`, an OpenCL
/// integration backend (which must outlive it), for the map that backend integrates into: its
/// kernels run on the backend's queue after the batches integrated so far and read the
/// occupancy, voxel-mean and NDT layers where integration left them (device region cache slots,
/// or the shared host pool), through a table of each region's slot. Only that table, the plan's
/// region table and the output layers are copied; no Backend::synchronise() is needed before
/// generate() (readsHostStore() is false). When the regions under the box do not fit the device
/// cache at once, generate() synchronises the backend and uploads them as the standalone
/// generator does. Errors: `backend` is not an OpenCL backend; the program does not build.
/// Thread-safety: as the backend's; generate() must not run concurrently with its integrate().
Result<std::unique_ptr<heightmap::HeightmapGenerator>> createOpenClHeightmapGenerator(
    Backend& backend, const opencl::ProgramCacheOptions& program_cache);

}  // namespace raymap
