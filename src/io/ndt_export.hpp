// SPDX-License-Identifier: BSD-3-Clause
// Exporting the Gaussians of an NDT-OM / NDT-TM map as PLY files a person can look at: one
// ellipsoid mesh per Gaussian, or one point per Gaussian with its surface normal.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "raymap/error.hpp"
#include <Eigen/Core>

#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// What sets the colour of an exported Gaussian (docs/cli.md, "export --mode ndt").
enum class NdtColour : std::uint8_t {
  kHeight,        ///< z of the mean, over the exported range of z
  kIntensity,     ///< NDT-TM: mean return intensity, over the exported range
  kPermeability,  ///< NDT-TM: miss / (hit + miss), 0 to 1
};

/// @brief Parses "height", "intensity" or "permeability".
Result<NdtColour> ndtColourFromString(const std::string& text);
const char* toString(NdtColour colour) noexcept;

/// @brief Which Gaussians are exported and how they look.
struct NdtExportOptions {
  static constexpr double kDefaultSigmas = 2.0;
  /// Smallest half-axis, as a fraction of the voxel edge, unless min_axis_m is given.
  static constexpr double kDefaultMinAxisVoxels = 0.05;

  /// Half-axis of an ellipsoid = sigmas x the standard deviation along that axis.
  double sigmas = kDefaultSigmas;
  /// Smallest half-axis in metres, so that a flat surfel stays visible; unset: 0.05 voxel edges.
  std::optional<double> min_axis_m;
  NdtColour colour = NdtColour::kHeight;

  /// @brief Checks sigmas in (0, 100], min_axis_m >= 0 and finite.
  Expected<void, Error> validate() const;
};

/// @brief The colour ramp shared by the NDT exports: value 0 blue, 0.25 cyan, 0.5 green,
/// 0.75 yellow, 1 red, linear in between (values outside [0, 1] are clamped).
struct Rgb8 {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
};
Rgb8 rampColour(double value) noexcept;

/// @brief The principal axes of a symmetric 3x3 covariance.
struct PrincipalAxes {
  Eigen::Vector3d variances;  ///< eigenvalues in ascending order (units of the input)
  Eigen::Matrix3d axes;       ///< unit eigenvectors as columns, in the same order; right-handed
};

/// @brief Decomposes the covariance given by its packed lower triangle (a00, a10, a11, a20, a21,
/// a22, the packing of kernels/common/ndt.h) with Eigen's SelfAdjointEigenSolver (Householder
/// tridiagonalisation and QL: robust for the singular and repeated-eigenvalue covariances of flat
/// and thin structures). The third axis is negated where needed so that the axes form a rotation
/// (the ellipsoid meshes keep their faces turned outwards).
PrincipalAxes principalAxes(const std::array<double, 6>& packed) noexcept;

/// Vertices and triangles of the low-poly sphere each ellipsoid is made of (a UV sphere of 8
/// longitudes and 6 latitude bands).
inline constexpr std::uint32_t kEllipsoidVertices = 42;
inline constexpr std::uint32_t kEllipsoidFaces = 80;

/// @brief Writes a binary little-endian PLY triangle mesh: for every occupied voxel whose NDT
/// Gaussian has at least one sample, an ellipsoid centred at the sample mean (world frame,
/// metres), its axes along the eigenvectors of the covariance, each half-axis sigmas x sqrt
/// (eigenvalue), at least the minimum axis. Vertices carry float x, y, z and uchar red, green,
/// blue; faces `list uchar int vertex_indices`. Written via a temporary file and rename.
/// @return the number of ellipsoids. Fails for maps without an NDT layer, for intensity or
/// permeability colours on NDT-OM maps, and on I/O errors.
Result<std::uint64_t> exportNdtEllipsoids(const VoxelMap& map, const NdtExportOptions& options,
                                          const std::string& path);

/// @brief Writes a binary little-endian point-cloud PLY: one point per exported Gaussian (the
/// same selection as the ellipsoids) at its mean, float x, y, z, float nx, ny, nz (the unit
/// eigenvector of the smallest eigenvalue, turned so that nz >= 0), uchar red, green, blue and
/// uint count (samples). @return the number of points.
Result<std::uint64_t> exportNdtPoints(const VoxelMap& map, const NdtExportOptions& options,
                                      const std::string& path);

}  // namespace raymap::io
