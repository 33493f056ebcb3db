// SPDX-License-Identifier: BSD-3-Clause
// Marching cubes over a TSDF map's voxel centres.
#include "src/map/tsdf_mesh.hpp"

#include <algorithm>
#include <cstddef>
#include <functional>
#include <unordered_map>
#include <utility>

#include "raymap/assert.hpp"

#include "src/map/marching_cubes.hpp"
#include "src/map/tsdf_surface.hpp"

namespace raymap {
namespace {

/// A cube edge in the map: its lower voxel (global) and its axis. Neighbouring cubes name a
/// shared edge alike, so its vertex is made once.
struct EdgeKey {
  Vec3i voxel;
  int axis = 0;
  friend bool operator==(const EdgeKey& a, const EdgeKey& b) noexcept = default;
};

struct EdgeKeyHash {
  std::size_t operator()(const EdgeKey& k) const noexcept {
    std::uint64_t h = static_cast<std::uint32_t>(k.voxel.x);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(k.voxel.y);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(k.voxel.z);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(k.axis);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

Vec3i cornerOffset(unsigned corner) {
  return {static_cast<std::int32_t>(corner & 1u), static_cast<std::int32_t>((corner >> 1) & 1u),
          static_cast<std::int32_t>((corner >> 2) & 1u)};
}

class MeshBuilder {
 public:
  explicit MeshBuilder(const VoxelMap& map) : map_(map) {}

  /// Adds the triangles of the cube whose lowest corner is voxel `origin`, given its corners.
  void addCube(Vec3i origin, const std::array<rm_tsdf_voxel, kCubeCorners>& corners,
               unsigned inside_mask) {
    const CubeCase& cube = marchingCubesCase(inside_mask);
    const std::array<CubeEdge, kCubeEdges>& edges = cubeEdges();
    for (std::uint8_t t = 0; t < cube.triangle_count; ++t) {
      std::array<std::uint32_t, 3> triangle{};
      for (std::size_t k = 0; k < 3; ++k) {
        const CubeEdge& edge = edges[cube.triangles[t][k]];
        triangle[k] = vertex(origin + cornerOffset(edge.lower), edge.axis, corners[edge.lower],
                             corners[edge.upper()]);
      }
      mesh_.triangles.push_back(triangle);
    }
  }

  TsdfMesh finish() && {
    mesh_.normals.assign(mesh_.vertices.size(), Vec3d{});
    for (const auto& t : mesh_.triangles) {
      // Unnormalised: its length is twice the triangle's area, which weights the mean.
      const Vec3d n = (mesh_.vertices[t[1]] - mesh_.vertices[t[0]])
                          .cross(mesh_.vertices[t[2]] - mesh_.vertices[t[0]]);
      for (const std::uint32_t v : t) {
        mesh_.normals[v] = mesh_.normals[v] + n;
      }
    }
    for (Vec3d& n : mesh_.normals) {
      const double length = n.norm();
      n = length > 0.0 ? n * (1.0 / length) : Vec3d{};
    }
    return std::move(mesh_);
  }

 private:
  /// The vertex on the edge from voxel `lower` one step along `axis`, made on first use.
  std::uint32_t vertex(Vec3i lower, int axis, rm_tsdf_voxel a, rm_tsdf_voxel b) {
    const auto [it, inserted] =
        index_.try_emplace(EdgeKey{lower, axis}, static_cast<std::uint32_t>(mesh_.vertices.size()));
    if (inserted) {
      Vec3i upper = lower;
      upper[axis] += 1;
      // The same expression as tsdfZeroCrossings(), so the points agree exactly.
      const double f = static_cast<double>(a.distance) /
                       (static_cast<double>(a.distance) - static_cast<double>(b.distance));
      const Vec3d ca = map_.voxelCentre(lower);
      const Vec3d cb = map_.voxelCentre(upper);
      mesh_.vertices.push_back(ca + (cb - ca) * f);
      mesh_.weights.push_back(std::min(a.weight, b.weight));
    }
    return it->second;
  }

  const VoxelMap& map_;
  TsdfMesh mesh_;
  std::unordered_map<EdgeKey, std::uint32_t, EdgeKeyHash> index_;
};

}  // namespace

TsdfMesh tsdfMesh(const VoxelMap& map, float min_weight) {
  RAYMAP_EXPECTS(map.tsdfLayer() >= 0);
  const RegionStore& store = map.store();
  const std::int32_t n = map.geometry().region_voxels;
  const auto tau =
      static_cast<float>(map.config().tsdf.truncationMetres(map.geometry().resolution));
  const auto usable = [&](const rm_tsdf_voxel& v) { return tsdfVoxelUsable(v, min_weight); };
  const std::array<CubeEdge, kCubeEdges>& edges = cubeEdges();
  // Offsets of the corners inside a region's voxel array (x fastest, then y, then z).
  std::array<std::uint32_t, kCubeCorners> step{};
  for (unsigned c = 0; c < kCubeCorners; ++c) {
    const Vec3i o = cornerOffset(c);
    step[c] = static_cast<std::uint32_t>(o.x + n * (o.y + n * o.z));
  }
  MeshBuilder builder(map);
  RegionCursor cursor(map);  // a tiered map's regions stream through its pool
  while (cursor.next()) {
    const Vec3i region = cursor.region();
    const std::uint32_t slot = cursor.slot();
    const rm_tsdf_voxel* tsdf = store.layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    std::uint32_t index = 0;
    for (std::int32_t z = 0; z < n; ++z) {
      for (std::int32_t y = 0; y < n; ++y) {
        for (std::int32_t x = 0; x < n; ++x, ++index) {
          if (!usable(tsdf[index])) {
            continue;
          }
          const Vec3i origin{region.x * n + x, region.y * n + y, region.z * n + z};
          // Inside the region the corners are steps along the array; on its far faces, lookups.
          const bool interior = x + 1 < n && y + 1 < n && z + 1 < n;
          std::array<rm_tsdf_voxel, kCubeCorners> corners{};
          unsigned inside_mask = 0;
          bool complete = true;
          for (unsigned c = 0; c < kCubeCorners && complete; ++c) {
            corners[c] = interior ? tsdf[index + step[c]] : map.tsdf(origin + cornerOffset(c));
            complete = usable(corners[c]);
            inside_mask |= corners[c].distance < 0.0f ? (1u << c) : 0u;
          }
          if (!complete || inside_mask == 0u || inside_mask == 0xFFu) {
            continue;
          }
          bool measured = true;
          for (const CubeEdge& edge : edges) {
            const float a = corners[edge.lower].distance;
            const float b = corners[edge.upper()].distance;
            if ((a >= 0.0f) != (b >= 0.0f) && !tsdfMeasuredCrossing(a, b, tau)) {
              measured = false;
              break;
            }
          }
          if (measured) {
            builder.addCube(origin, corners, inside_mask);
          }
        }
      }
    }
  }
  return std::move(builder).finish();
}

}  // namespace raymap
