// SPDX-License-Identifier: BSD-3-Clause
#include "src/device/staging/resident_read.hpp"

#include <string>

namespace raymap::gpu {

Expected<std::span<const std::uint32_t>, Error> ResidentRead::prepare(
    StagedBackend* backend, const VoxelMap& map, std::span<const std::uint32_t> host_slots,
    const char* api) {
  bytes_uploaded_ = 0;
  if (backend == nullptr) {
    return std::span<const std::uint32_t>{};
  }
  // Error texts are built on the error paths only: this runs every height-map cycle.
  const auto who = [api] { return std::string(api) + " height map: "; };
  if (&map != &backend->integratedMap()) {
    return fail(ErrorCode::kInvalidArgument,
                who() + "the map is not the one its backend integrates into");
  }
  device_slots_.resize(host_slots.size());
  auto placed = backend->placeForRead(host_slots, device_slots_);
  if (!placed) {
    return fail(ErrorCode::kUnsupported,
                who() + "making the regions resident: " + toString(placed.error()));
  }
  bytes_uploaded_ = placed->bytes_uploaded;
  if (placed->resident) {
    return std::span<const std::uint32_t>(device_slots_);
  }
  // The regions under the box do not fit the device cache together: read the host store.
  if (auto ok = backend->synchronise(); !ok) {
    return fail(ErrorCode::kUnsupported, who() + "synchronising the map: " + toString(ok.error()));
  }
  return std::span<const std::uint32_t>{};
}

}  // namespace raymap::gpu
