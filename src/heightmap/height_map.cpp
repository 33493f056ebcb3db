// SPDX-License-Identifier: BSD-3-Clause
#include "src/heightmap/height_map.hpp"

#include <cmath>

namespace raymap::heightmap {

std::string_view toString(CellKind kind) noexcept {
  switch (kind) {
    case CellKind::kUnknown:
      return "unknown";
    case CellKind::kSurface:
      return "surface";
    case CellKind::kVirtualSurface:
      return "virtual";
    case CellKind::kVacant:
      return "vacant";
  }
  return "unknown";
}

std::string_view toString(HeightmapMode mode) noexcept {
  return mode == HeightmapMode::kFill ? "fill" : "planar";
}

bool HeightMap::cellOf(double x, double y, int* i, int* j) const noexcept {
  // The voxel column holding (x, y), computed as VoxelMap::voxelOf() does (floor of p times the
  // inverse resolution), so that a point on a voxel face lands in the same column here and there.
  const double inverse = 1.0 / resolution;
  const double top_x = std::round((centre_x + 0.5 * cells_x * resolution) * inverse) - 1.0;
  const double top_y = std::round((centre_y + 0.5 * cells_y * resolution) * inverse) - 1.0;
  const double fi = top_x - std::floor(x * inverse);
  const double fj = top_y - std::floor(y * inverse);
  if (!(fi >= 0.0 && fi < cells_x && fj >= 0.0 && fj < cells_y)) {
    return false;
  }
  *i = static_cast<int>(fi);
  *j = static_cast<int>(fj);
  return true;
}

void HeightMap::resizeLayers() {
  const std::size_t n = cellCount();
  elevation.resize(n);
  clearance.resize(n);
  kind.resize(n);
  observed_count.resize(n);
  reference.resize(n);
  const std::size_t normals = has_normals ? n : 0;
  normal_x.resize(normals);
  normal_y.resize(normals);
  normal_z.resize(normals);
}

}  // namespace raymap::heightmap
