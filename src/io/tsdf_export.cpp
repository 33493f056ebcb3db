// SPDX-License-Identifier: BSD-3-Clause
// TSDF zero crossings as a PLY point cloud.
#include "src/io/tsdf_export.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

#include "src/io/atomic_file.hpp"
#include "src/io/le_buffer.hpp"
#include "src/map/tsdf_surface.hpp"

namespace raymap::io {

Result<std::uint64_t> exportTsdfSurface(const VoxelMap& map, const std::string& path,
                                        double min_weight) {
  if (map.tsdfLayer() < 0) {
    return fail(ErrorCode::kUnsupported, "the map has no TSDF layer (it is a " +
                                             mapModeName(map.config()) +
                                             " map; build one with populate --mode tsdf)");
  }
  if (!std::isfinite(min_weight) || min_weight < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "min-weight must be a finite weight >= 0");
  }
  const std::vector<TsdfSurfacePoint> points =
      tsdfZeroCrossings(map, static_cast<float>(min_weight));
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  char comment[160];
  std::snprintf(comment, sizeof(comment),
                "comment raymap TSDF zero crossings, truncation %g m, min weight %g\n",
                map.config().tsdf.truncationMetres(map.geometry().resolution), min_weight);
  const std::string header = "ply\nformat binary_little_endian 1.0\n" + std::string(comment) +
                             "element vertex " + std::to_string(points.size()) +
                             "\nproperty float x\nproperty float y\nproperty float z\n"
                             "property float nx\nproperty float ny\nproperty float nz\n"
                             "property float weight\nend_header\n";
  if (auto ok = writer->write(header); !ok) {
    return Unexpected(ok.error());
  }
  LeBuffer out;
  for (const TsdfSurfacePoint& p : points) {
    out.f32(p.p_world.x);
    out.f32(p.p_world.y);
    out.f32(p.p_world.z);
    out.f32(p.normal.x);
    out.f32(p.normal.y);
    out.f32(p.normal.z);
    out.f32(static_cast<double>(p.weight));
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  if (auto ok = out.finish(*writer); !ok) {
    return Unexpected(ok.error());
  }
  return points.size();
}

}  // namespace raymap::io
