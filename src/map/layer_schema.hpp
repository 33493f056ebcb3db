// SPDX-License-Identifier: BSD-3-Clause
// The layers a map carries: what each voxel of each layer holds, its size and its "empty" value.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "raymap/error.hpp"

namespace raymap {

/// @brief Identifies a layer type. The numeric values are stored in map files: never renumber.
/// New layers (NDT covariance, hit/miss counts, intensity, traversal, TSDF) are added here, with a
/// LayerSpec in layerSpec() and an update rule in kernels/common; the walkers and the region store
/// handle any layer through its spec.
enum class LayerKind : std::uint8_t {
  kOccupancy = 1,  ///< float log-odds, +inf = unobserved (kernels/common/occupancy.h)
  kVoxelMean = 2,  ///< packed sub-voxel mean + count (kernels/common/voxel_mean.h)
  kScanMark = 3,   ///< per-scan scratch marks (kernels/common/scan_mark.h); never saved
  kNdt = 4,        ///< NDT Gaussian: mean, square-root covariance, count (kernels/common/ndt.h)
  kHitMiss = 5,    ///< NDT-TM hit and miss counts (kernels/common/ndt.h)
  kIntensity = 6,  ///< NDT-TM intensity mean and variance (kernels/common/ndt.h)
  kTraversal = 7,  ///< decay rate: metres of ray path inside the voxel (kernels/common/decay.h)
  kTsdf = 8,       ///< signed distance (metres) and weight (kernels/common/tsdf.h)
};

/// @brief Static description of a layer type.
struct LayerSpec {
  static constexpr std::uint32_t kMaxWordsPerVoxel = 16;

  LayerKind kind;
  std::string_view name;          ///< stable name, used in files and tools
  std::uint32_t bytes_per_voxel;  ///< multiple of 4, at most 64
  /// Value of a voxel nobody has touched, as 32-bit words (little-endian order of the struct).
  std::array<std::uint32_t, kMaxWordsPerVoxel> clear_words;
  bool saved;             ///< written to map files
  std::uint16_t version;  ///< bumped when the layer's encoding changes
  /// Written at every voxel a ray crosses (occupancy, scan marks), so whole stretches of the
  /// layer become resident: the region store backs it with huge pages. The other layers are
  /// written only where samples land (near surfaces) and keep small pages, so a page of them
  /// becomes resident (and is zeroed by the OS) only where a sample is.
  bool dense;

  /// @brief True when the clear value is all zero bits (memory the OS hands out is already clear).
  bool clearsToZero() const noexcept {
    for (std::uint32_t w = 0; w < bytes_per_voxel / 4u; ++w) {
      if (clear_words[w] != 0u) {
        return false;
      }
    }
    return true;
  }
};

/// @brief The spec of a known layer kind; nullopt for values this build does not know (a newer
/// file).
std::optional<LayerSpec> layerSpec(LayerKind kind) noexcept;

/// @brief Looks a layer kind up by its name ("occupancy", "mean", ...).
std::optional<LayerKind> layerKindFromName(std::string_view name) noexcept;

/// @brief The ordered list of layers of a map, fixed at construction. Value type.
class LayerSchema {
 public:
  static constexpr int kMaxLayers = 8;

  /// @brief Adds a layer; adding one twice is a no-op. Fails when the schema is full.
  Expected<void, Error> add(LayerKind kind);
  /// @brief Index of a layer in this schema, or -1.
  int indexOf(LayerKind kind) const noexcept;
  bool has(LayerKind kind) const noexcept { return indexOf(kind) >= 0; }
  int size() const noexcept { return count_; }
  const LayerSpec& at(int index) const noexcept;
  /// @brief Bytes of all layers of one region of `voxels_per_region` voxels.
  std::uint64_t bytesPerRegion(std::uint32_t voxels_per_region) const noexcept;
  /// @brief Bytes a newly created region writes at once: every layer whose clear value is not
  /// zero (the pool's untouched pages are zeros, so zero-clearing layers cost memory only where
  /// they are written later). The least resident memory a region can take.
  std::uint64_t bytesWrittenAtCreation(std::uint32_t voxels_per_region) const noexcept;

  friend bool operator==(const LayerSchema& a, const LayerSchema& b) noexcept;

 private:
  std::array<LayerKind, kMaxLayers> kinds_{};
  std::array<LayerSpec, kMaxLayers> specs_{};
  int count_ = 0;
};

}  // namespace raymap
