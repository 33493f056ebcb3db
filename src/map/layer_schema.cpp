// SPDX-License-Identifier: BSD-3-Clause
// The table of known layers.
#include "src/map/layer_schema.hpp"

#include <bit>
#include <limits>
#include <string>

#include "raymap/assert.hpp"

#include "kernels/common/ndt.h"
#include "kernels/common/tsdf.h"

namespace raymap {
namespace {

// +inf as a float bit pattern: the occupancy value of an unobserved voxel.
constexpr std::uint32_t kUnobservedBits = 0x7F800000u;
static_assert(std::bit_cast<std::uint32_t>(std::numeric_limits<float>::infinity()) ==
              kUnobservedBits);

constexpr std::array<LayerSpec, 8> kKnownLayers = {{
    {LayerKind::kOccupancy, "occupancy", 4, {kUnobservedBits}, true, 1, true},
    {LayerKind::kVoxelMean, "mean", 8, {0u, 0u}, true, 1, false},
    {LayerKind::kScanMark, "scan_mark", 4, {0u}, false, 1, true},
    {LayerKind::kNdt, "ndt", sizeof(rm_ndt_voxel), {}, true, 1, false},
    {LayerKind::kHitMiss, "hit_miss", sizeof(rm_ndt_hit_miss), {}, true, 1, false},
    {LayerKind::kIntensity, "intensity", sizeof(rm_ndt_intensity), {}, true, 1, false},
    {LayerKind::kTraversal, "traversal", 4, {0u}, true, 1, true},
    {LayerKind::kTsdf, "tsdf", sizeof(rm_tsdf_voxel), {0u, 0u}, true, 1, true},
}};
static_assert(sizeof(rm_ndt_voxel) == 40 && sizeof(rm_ndt_hit_miss) == 8 &&
              sizeof(rm_ndt_intensity) == 8);

}  // namespace

std::optional<LayerSpec> layerSpec(LayerKind kind) noexcept {
  for (const LayerSpec& spec : kKnownLayers) {
    if (spec.kind == kind) {
      return spec;
    }
  }
  return std::nullopt;
}

std::optional<LayerKind> layerKindFromName(std::string_view name) noexcept {
  for (const LayerSpec& spec : kKnownLayers) {
    if (spec.name == name) {
      return spec.kind;
    }
  }
  return std::nullopt;
}

Expected<void, Error> LayerSchema::add(LayerKind kind) {
  if (has(kind)) {
    return {};
  }
  const std::optional<LayerSpec> spec = layerSpec(kind);
  if (!spec) {
    return fail(ErrorCode::kUnsupported,
                "unknown layer kind " + std::to_string(static_cast<int>(kind)));
  }
  if (count_ >= kMaxLayers) {
    return fail(ErrorCode::kCapacity,
                "a map holds at most " + std::to_string(kMaxLayers) + " layers");
  }
  kinds_[static_cast<std::size_t>(count_)] = kind;
  specs_[static_cast<std::size_t>(count_)] = *spec;
  ++count_;
  return {};
}

int LayerSchema::indexOf(LayerKind kind) const noexcept {
  for (int i = 0; i < count_; ++i) {
    if (kinds_[static_cast<std::size_t>(i)] == kind) {
      return i;
    }
  }
  return -1;
}

const LayerSpec& LayerSchema::at(int index) const noexcept {
  RAYMAP_EXPECTS(index >= 0 && index < count_);
  return specs_[static_cast<std::size_t>(index)];
}

std::uint64_t LayerSchema::bytesPerRegion(std::uint32_t voxels_per_region) const noexcept {
  std::uint64_t bytes = 0;
  for (int i = 0; i < count_; ++i) {
    bytes += std::uint64_t{specs_[static_cast<std::size_t>(i)].bytes_per_voxel} * voxels_per_region;
  }
  return bytes;
}

std::uint64_t LayerSchema::bytesWrittenAtCreation(std::uint32_t voxels_per_region) const noexcept {
  std::uint64_t bytes = 0;
  for (int i = 0; i < count_; ++i) {
    const LayerSpec& spec = specs_[static_cast<std::size_t>(i)];
    if (!spec.clearsToZero()) {
      bytes += std::uint64_t{spec.bytes_per_voxel} * voxels_per_region;
    }
  }
  return bytes;
}

bool operator==(const LayerSchema& a, const LayerSchema& b) noexcept {
  if (a.count_ != b.count_) {
    return false;
  }
  for (int i = 0; i < a.count_; ++i) {
    if (a.kinds_[static_cast<std::size_t>(i)] != b.kinds_[static_cast<std::size_t>(i)]) {
      return false;
    }
  }
  return true;
}

}  // namespace raymap
