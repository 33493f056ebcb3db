// SPDX-License-Identifier: BSD-3-Clause
// How a device program that shares an integration backend's context (the height-map generator)
// finds the map's regions in the backend's layer buffers: API-agnostic (OpenCL and CUDA).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "raymap/error.hpp"

#include "src/device/staging/staged_backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::gpu {

/// @brief One reader's state for reading regions where a device backend left them. Reused from
/// call to call (keeps its capacity).
///
/// Thread-safety: as the backend's (one thread at a time). Real-time: allocates only when the
/// number of regions read grows.
class ResidentRead {
 public:
  /// @brief Prepares a read of the regions in host store slots `host_slots` of `map`.
  /// `backend` null (a reader with its own context): returns an empty span, the caller uploads
  /// from the host store. Otherwise `map` must be the backend's; returns each region's slot in
  /// the backend's layer buffers (StagedBackend::placeForRead), or, when its device cache cannot
  /// hold them all at once, synchronises the backend and returns an empty span (the caller then
  /// uploads from the now current host store). `api` names the caller in errors ("OpenCL").
  Expected<std::span<const std::uint32_t>, Error> prepare(StagedBackend* backend,
                                                          const VoxelMap& map,
                                                          std::span<const std::uint32_t> host_slots,
                                                          const char* api);

  /// Region bytes the last prepare() uploaded to make the regions resident.
  std::uint64_t bytesUploaded() const noexcept { return bytes_uploaded_; }

 private:
  std::vector<std::uint32_t> device_slots_;
  std::uint64_t bytes_uploaded_ = 0;
};

}  // namespace raymap::gpu
