// SPDX-License-Identifier: BSD-3-Clause
// The surface of a TSDF map as a PLY: zero crossings as points, or a marching cubes mesh.
#include "src/io/tsdf_export.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "src/io/atomic_file.hpp"
#include "src/io/le_buffer.hpp"
#include "src/map/tsdf_mesh.hpp"
#include "src/map/tsdf_surface.hpp"

namespace raymap::io {
namespace {

Expected<void, Error> checkTsdfExport(const VoxelMap& map, double min_weight) {
  if (map.tsdfLayer() < 0) {
    return fail(ErrorCode::kUnsupported, "the map has no TSDF layer (it is a " +
                                             mapModeName(map.config()) +
                                             " map; build one with map.mode: tsdf)");
  }
  if (!std::isfinite(min_weight) || min_weight < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "export.min_weight must be a finite weight >= 0");
  }
  return {};
}

/// The header up to the vertex properties' end: format, comment and the vertex element with
/// x y z nx ny nz weight (both exports write vertices alike).
std::string vertexHeader(const VoxelMap& map, const char* what, double min_weight,
                         std::uint64_t vertices) {
  char comment[160];
  std::snprintf(comment, sizeof(comment),
                "comment raymap TSDF %s, truncation %g m, min weight %g\n", what,
                map.config().tsdf.truncationMetres(map.geometry().resolution), min_weight);
  return "ply\nformat binary_little_endian 1.0\n" + std::string(comment) + "element vertex " +
         std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\n"
         "property float weight\n";
}

void putVertex(LeBuffer& out, Vec3d p, Vec3d normal, float weight) {
  out.f32(p.x);
  out.f32(p.y);
  out.f32(p.z);
  out.f32(normal.x);
  out.f32(normal.y);
  out.f32(normal.z);
  out.f32(static_cast<double>(weight));
}

}  // namespace

Result<std::uint64_t> exportTsdfSurface(const VoxelMap& map, const std::string& path,
                                        double min_weight) {
  if (auto ok = checkTsdfExport(map, min_weight); !ok) {
    return Unexpected(ok.error());
  }
  const std::vector<TsdfSurfacePoint> points =
      tsdfZeroCrossings(map, static_cast<float>(min_weight));
  if (auto failure = map.tierFailure()) {
    return Unexpected(*failure);  // a cold region could not be read back: no partial surface
  }
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  const std::string header =
      vertexHeader(map, "zero crossings", min_weight, points.size()) + "end_header\n";
  if (auto ok = writer->write(header); !ok) {
    return Unexpected(ok.error());
  }
  LeBuffer out;
  for (const TsdfSurfacePoint& p : points) {
    putVertex(out, p.p_world, p.normal, p.weight);
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  if (auto ok = out.finish(*writer); !ok) {
    return Unexpected(ok.error());
  }
  return points.size();
}

Result<TsdfMeshCounts> exportTsdfMesh(const VoxelMap& map, const std::string& path,
                                      double min_weight) {
  if (auto ok = checkTsdfExport(map, min_weight); !ok) {
    return Unexpected(ok.error());
  }
  const TsdfMesh mesh = tsdfMesh(map, static_cast<float>(min_weight));
  if (auto failure = map.tierFailure()) {
    return Unexpected(*failure);  // a cold region could not be read back: no partial mesh
  }
  if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    return fail(ErrorCode::kCapacity, std::to_string(mesh.vertices.size()) +
                                          " vertices are too many for one PLY mesh (int vertex "
                                          "indices); export the points with export.mode: tsdf");
  }
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  const std::string header =
      vertexHeader(map, "marching cubes mesh", min_weight, mesh.vertices.size()) + "element face " +
      std::to_string(mesh.triangles.size()) +
      "\nproperty list uchar int vertex_indices\nend_header\n";
  if (auto ok = writer->write(header); !ok) {
    return Unexpected(ok.error());
  }
  LeBuffer out;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    putVertex(out, mesh.vertices[i], mesh.normals[i], mesh.weights[i]);
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  for (const auto& triangle : mesh.triangles) {
    out.u8(3);
    for (const std::uint32_t v : triangle) {
      out.u32(v);
    }
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  if (auto ok = out.finish(*writer); !ok) {
    return Unexpected(ok.error());
  }
  return TsdfMeshCounts{mesh.vertices.size(), mesh.triangles.size()};
}

}  // namespace raymap::io
