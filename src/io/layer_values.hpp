// SPDX-License-Identifier: BSD-3-Clause
// The values each saved layer can hold, so that a loaded map with others (NaN, an infinity in a
// layer of finite numbers) is refused instead of answering queries with them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "src/map/layer_schema.hpp"

namespace raymap::io {

/// @brief A voxel value no writer produces: where it is, and what the layer holds instead.
struct BadLayerValue {
  std::uint32_t voxel = 0;  ///< index of the voxel in its region
  float value = 0.0f;       ///< NaN or an infinity
  const char* rule = "";    ///< what that word of the layer holds, for messages
};

/// @brief Finds the first float of a decoded region layer (`voxels` voxels of `kind`, in the
/// in-memory layout) that is NaN, or infinite where the layer holds finite numbers only: every
/// float of every layer must be finite, except an occupancy of +inf (unobserved, the clear
/// value). Integer words (counts, packed means) take any value. Allocates nothing.
/// @return nullopt when every value is one a writer can produce.
std::optional<BadLayerValue> findBadLayerValue(LayerKind kind, const std::byte* data,
                                               std::uint32_t voxels) noexcept;

}  // namespace raymap::io
