// SPDX-License-Identifier: BSD-3-Clause
// What raymap::Mapper::voxel() reports of the NDT, TSDF and decay-rate layers: one voxel's values
// in world units (metres), from the layers' stored forms (voxel units, packed factors).
#pragma once

#include <optional>

#include "raymap/mapper.hpp"

#include "src/core/vec3.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::mapper {

/// @brief The voxel's NDT Gaussian in metres (and NDT-TM's counts and intensity); nullopt for a
/// map without the NDT layer or a voxel without samples. Thread-safety: reads the map (callers
/// keep writers out). Allocates: no.
std::optional<NdtVoxelInfo> ndtVoxel(const VoxelMap& map, Vec3i voxel) noexcept;
/// @brief The voxel's TSDF distance and weight; nullopt without the layer or an update.
std::optional<TsdfVoxelInfo> tsdfVoxel(const VoxelMap& map, Vec3i voxel) noexcept;
/// @brief The voxel's path length, samples and decay rate (rm_decay_rate); nullopt without the
/// traversal layer or where no ray entered (the rate is unknown there).
std::optional<DecayVoxelInfo> decayVoxel(const VoxelMap& map, Vec3i voxel) noexcept;

}  // namespace raymap::mapper
