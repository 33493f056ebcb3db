// SPDX-License-Identifier: BSD-3-Clause
// The surface of a TSDF map as a triangle mesh (marching cubes over the voxel centres).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "src/core/vec3.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief An indexed triangle mesh, world frame. Vertices are shared between the triangles that
/// meet at them.
struct TsdfMesh {
  std::vector<Vec3d> vertices;  ///< metres
  /// Unit vertex normals: the area-weighted mean of the normals of the triangles at the vertex,
  /// pointing out of the surface (towards the positive side, where the sensor was); zero for a
  /// vertex whose triangles all have zero area.
  std::vector<Vec3d> normals;
  std::vector<float> weights;  ///< per vertex: the smaller weight of the edge's two voxels
  /// Vertex indices, counter-clockwise seen from the positive side (right-hand normal outwards).
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// @brief Marching cubes over a TSDF map: a cube for every 2x2x2 block of voxel centres whose
/// eight voxels all have weight >= min_weight (and > 0), with the case table of
/// marching_cubes.hpp. A vertex lies where the linear interpolation of the distance between the
/// two centres of a cube edge is zero: the same point tsdfZeroCrossings() reports for that pair,
/// so every vertex is one of its crossings. A cube with an edge whose sign change is no measured
/// surface (tsdfMeasuredCrossing: a jump from or to a saturated +-tau voxel) is left out whole.
/// Cubes are visited in region order (z, y, x), so the output is deterministic. The mesh is
/// closed wherever the observed, heavy enough voxels enclose the surface; it ends at their edge.
/// A voxel at distance exactly 0 puts several vertices on its centre (triangles of zero area).
/// @pre map has a TSDF layer. Thread-safety: const; may run alongside other const queries.
/// @rt allocates: yes (offline tool).
TsdfMesh tsdfMesh(const VoxelMap& map, float min_weight);

}  // namespace raymap
