// SPDX-License-Identifier: BSD-3-Clause
// Exports of a map for viewers and other tools (PLY files), as `raymap export` writes them
// (docs/cli.md, "export"; docs/library.md, "Exports").
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace raymap {

/// @brief What an export writes.
enum class ExportKind : std::uint8_t {
  kOccupied,   ///< occupied voxels at their voxel mean (centre without samples): points
  kFree,       ///< free voxels at their centres: points
  kMean,       ///< every voxel with samples at its mean, whatever its state: points
  kDecay,      ///< decay-rate maps: voxels whose rate is at least decay_threshold: points
  kNdt,        ///< NDT maps: a triangle-mesh ellipsoid per occupied Gaussian
  kNdtPoints,  ///< NDT maps: the Gaussians' means with normals: points
  kTsdf,       ///< TSDF maps: the surface's zero crossings with normals: points
  kTsdfMesh,   ///< TSDF maps: the surface as a triangle mesh (marching cubes)
};

/// @brief What sets the colour of an exported NDT Gaussian.
enum class ExportColour : std::uint8_t {
  kHeight,        ///< z of the mean, over the exported range of z
  kIntensity,     ///< NDT-TM: mean return intensity
  kPermeability,  ///< NDT-TM: miss / (hit + miss)
};

/// kTsdf, kTsdfMesh: ExportRequest::tsdf_min_weight when unset (rays of weight).
inline constexpr double kDefaultTsdfMinWeight = 1.0;

/// @brief One export. The optional fields belong to some kinds only: setting one for another
/// kind is refused naming its key (export.threshold, export.sigmas, export.min_axis,
/// export.colour, export.min_weight), as `raymap export` refuses the flag. Value type.
struct ExportRequest {
  ExportKind kind = ExportKind::kOccupied;
  /// kDecay: the lowest rate exported, reflections per metre of ray path; default 0 (every voxel
  /// a ray entered).
  std::optional<double> decay_threshold;
  /// kNdt (accepted for kNdtPoints too): ellipsoid half-axes in standard deviations, (0, 100];
  /// default 2.
  std::optional<double> ndt_sigmas;
  /// kNdt (accepted for kNdtPoints too): the smallest half-axis, metres, so flat surfels stay
  /// visible; default 0.05 voxel edges.
  std::optional<double> ndt_min_axis;
  /// kNdt, kNdtPoints: default kHeight.
  std::optional<ExportColour> ndt_colour;
  /// kTsdf: crossings between voxels lighter than this are left out; kTsdfMesh: cubes with a
  /// voxel lighter than this; rays of weight, default 1.
  std::optional<double> tsdf_min_weight;
};

/// @brief What an export wrote.
struct ExportCounts {
  /// Points (kOccupied … kDecay, kNdtPoints, kTsdf), ellipsoids (kNdt) or triangles (kTsdfMesh).
  std::uint64_t items = 0;
  std::uint64_t vertices = 0;  ///< kTsdfMesh: the mesh's vertices (0 otherwise)
};

/// @brief The kind's name as `raymap export --mode` takes it ("occupied", "ndt-points", …).
std::string_view toString(ExportKind kind) noexcept;
/// @brief The kind named `name`; nullopt for an unknown name.
std::optional<ExportKind> exportKindFromName(std::string_view name) noexcept;
/// @brief "height", "intensity" or "permeability" (`raymap export --colour`).
std::string_view toString(ExportColour colour) noexcept;
/// @brief The colour named `name`; nullopt for an unknown name.
std::optional<ExportColour> exportColourFromName(std::string_view name) noexcept;

}  // namespace raymap
