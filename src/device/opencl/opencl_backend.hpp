// SPDX-License-Identifier: BSD-3-Clause
// The OpenCL backend: occupancy integration on an OpenCL 1.2 device with a preallocated device
// region cache and double-buffered batches.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/device/opencl/cl_runtime.hpp"
#include "src/device/opencl/program_cache.hpp"
#include "src/device/staging/device_options.hpp"
#include "src/device/staging/staged_backend.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// How the span kernel shares a batch's work among work-items (docs/architecture.md, "Span work on
/// CPU devices").
enum class SpanWork : std::uint8_t {
  kAuto,       ///< per region on CPU devices (PoCL), per span record on GPUs
  kPerSpan,    ///< one work-item per span record; voxel updates are atomic
  kPerRegion,  ///< one work-item per region, its spans in ray order; voxel updates are plain
};

/// @brief The span work named `name` as `--opencl-span-work` and raymapd's
/// `backend.opencl_span_work` spell it ("auto", "span", "region"); nullopt for any other name.
std::optional<SpanWork> spanWorkNamed(std::string_view name) noexcept;

/// @brief Options of the OpenCL backend: the shared device options (memory, cache, batches) and
/// the OpenCL ones.
struct OpenClBackendOptions : DeviceBackendOptions {
  opencl::DeviceSelector device;  ///< platform/device by index or name substring
  /// Use 32-bit counters even where the device has cl_khr_int64_base_atomics (tests both paths).
  bool force_32bit_atomics = false;
  opencl::ProgramCacheOptions program_cache;
  SpanWork span_work = SpanWork::kAuto;
  /// Appended to the kernel build options (tuning, tests).
  std::string extra_build_options;
};

/// @brief Creates an OpenCL backend integrating into `map` (which must outlive it).
///
/// Design (see docs/architecture.md, "Device backends"; the batch loop is gpu::StagedBackend's):
///  - At creation: picks the device, builds the embedded kernel source (binary cached on disk),
///    allocates one device buffer per map layer cut into cache slots, and two sets of batch
///    staging buffers. Nothing is allocated on the device afterwards.
///  - integrate(): the host plans a batch (coarse region walk, span records, regions moved into
///    the cache, samples grouped per voxel) while the device may still run the previous batch,
///    then enqueues the copies and kernels and returns without waiting. Regions leave the cache
///    (downloaded to the host store) only when their slot is needed and the batch being planned
///    does not use them.
///  - synchronise(): waits for the device and downloads every region changed since the last call.
///  - Shared memory (DeviceMemory::kShared, chosen automatically on devices that share memory with
///    the host when every layer of the host store fits one device allocation): the device works
///    on the host store in place; no cache, no copies, and synchronise() only waits.
///
/// Errors: creation fails with a clear message when no platform exists, the kernel does not build
/// (the build log is in the message) or the buffers cannot be allocated. integrate() returns
/// kDeviceFailure when the device reports an error; the map must then be discarded.
/// Thread-safety: none; the map must not be changed by others between integrate() and
/// synchronise(), except for rolling-window moves, which the next integrate() takes into account.
Result<std::unique_ptr<Backend>> createOpenClBackend(VoxelMap& map,
                                                     const OpenClBackendOptions& options);

namespace opencl {

/// @brief What an OpenCL backend lends to kernels of another program in its context: the
/// height-map generator reads the map's layers where integration left them (device region cache
/// or the shared host pool) instead of through the host store.
/// Thread-safety: as the backend's (one thread at a time, under the map's lock in raymapd).
class BackendDevice {
 public:
  virtual ~BackendDevice() = default;
  /// The backend's context and its one in-order queue.
  virtual const DeviceContext& context() const noexcept = 0;
  /// The buffer of map layer `layer` (a placeholder for -1): the layout of the host store, one
  /// region per slot.
  virtual cl_mem layerBuffer(int layer) const noexcept = 0;
  /// The batch loop: placeForRead(), synchronise().
  virtual gpu::StagedBackend& staged() noexcept = 0;
};

/// @brief `backend` as an OpenCL backend, or nullptr when it is another kind.
BackendDevice* backendDevice(Backend& backend) noexcept;

}  // namespace opencl
}  // namespace raymap
