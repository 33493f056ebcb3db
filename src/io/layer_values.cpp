// SPDX-License-Identifier: BSD-3-Clause
// findBadLayerValue: which words of each layer are floats, and which of those may be infinite.
#include "src/io/layer_values.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>

#include "kernels/common/ndt.h"
#include "kernels/common/tsdf.h"

namespace raymap::io {
namespace {

/// The float words of one layer's voxels: the first `floats` 32-bit words of each voxel (the
/// voxel's size is the layer schema's).
struct FloatWords {
  std::uint32_t floats = 0;
  bool plus_infinity_allowed = false;
  const char* rule = "";
};

// The layouts these rules rely on (kernels/common/*.h): the floats come first.
static_assert(offsetof(rm_ndt_voxel, count) == 9 * sizeof(float), "NDT: 9 floats, then count");
static_assert(sizeof(rm_ndt_voxel) == 10 * 4);
static_assert(sizeof(rm_ndt_intensity) == 2 * sizeof(float));
static_assert(sizeof(rm_tsdf_voxel) == 2 * sizeof(float));

FloatWords floatWordsOf(LayerKind kind) noexcept {
  switch (kind) {
    case LayerKind::kOccupancy:
      return {1, true, "occupancy is a finite log-odds, or +inf for an unobserved voxel"};
    case LayerKind::kNdt:
      return {9, false, "the NDT mean and covariance factor are finite"};
    case LayerKind::kIntensity:
      return {2, false, "the intensity mean and variance are finite"};
    case LayerKind::kTraversal:
      return {1, false, "the metres of ray path are finite"};
    case LayerKind::kTsdf:
      return {2, false, "the signed distance and its weight are finite"};
    case LayerKind::kVoxelMean:  // packed position and count: integers
    case LayerKind::kHitMiss:    // counts
    case LayerKind::kScanMark:   // never saved
      return {};
  }
  return {};
}

}  // namespace

std::optional<BadLayerValue> findBadLayerValue(LayerKind kind, const std::byte* data,
                                               std::uint32_t voxels) noexcept {
  const FloatWords words = floatWordsOf(kind);
  const auto spec = layerSpec(kind);
  if (words.floats == 0 || !spec) {
    return std::nullopt;
  }
  const std::uint32_t words_per_voxel = spec->bytes_per_voxel / 4u;
  for (std::uint32_t v = 0; v < voxels; ++v) {
    for (std::uint32_t w = 0; w < words.floats; ++w) {
      float value = 0.0f;
      std::memcpy(&value, data + (std::size_t{v} * words_per_voxel + w) * sizeof(float),
                  sizeof(value));
      if (std::isfinite(value) || (words.plus_infinity_allowed && value > 0.0f)) {
        continue;  // +inf is the only non-finite value that compares above 0
      }
      return BadLayerValue{v, value, words.rule};
    }
  }
  return std::nullopt;
}

}  // namespace raymap::io
