// SPDX-License-Identifier: BSD-3-Clause
// NDT Gaussians of a map as an ellipsoid mesh or as oriented points, binary little-endian PLY.
#include "src/io/ndt_export.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <tuple>
#include <vector>

#include <Eigen/Eigenvalues>

#include "kernels/common/ndt.h"
#include "kernels/common/occupancy.h"
#include "src/core/eigen_conversions.hpp"
#include "src/io/atomic_file.hpp"
#include "src/io/le_buffer.hpp"

namespace raymap::io {
namespace {

constexpr int kSlices = 8;  // longitudes of the unit sphere
constexpr int kStacks = 6;  // latitude bands
static_assert(kEllipsoidVertices == 2 + kSlices * (kStacks - 1));
static_assert(kEllipsoidFaces == 2 * kSlices * (kStacks - 1));
constexpr double kMaxSigmas = 100.0;

/// One exported Gaussian, in the world frame.
struct Gaussian {
  Vec3d mean_m;                   ///< metres
  std::array<double, 3> axes_m;   ///< half-axes along the eigenvectors, metres
  std::array<Vec3d, 3> axes_dir;  ///< eigenvectors, ascending eigenvalue
  double colour_value = 0.0;      ///< height (m), intensity or permeability
  std::uint32_t count = 0;
};

/// Occupied voxels with a Gaussian, regions in coordinate order (z, y, x) and voxels in index
/// order, so the output is deterministic (a tiered map's regions stream through its pool).
Result<std::vector<Gaussian>> collect(const VoxelMap& map, const NdtExportOptions& options) {
  const RegionStore& store = map.store();
  RegionCursor cursor(map);
  const std::int32_t n = map.geometry().region_voxels;
  const double resolution = map.geometry().resolution;
  const double min_axis =
      options.min_axis_m.value_or(NdtExportOptions::kDefaultMinAxisVoxels * resolution);
  const float threshold = map.occupancy().threshold;
  std::vector<Gaussian> out;
  while (cursor.next()) {
    const Vec3i region = cursor.region();
    const std::uint32_t slot = cursor.slot();
    const float* occupancy = store.layerData<float>(slot, map.occupancyLayer());
    const rm_ndt_voxel* ndt = store.layerData<rm_ndt_voxel>(slot, map.ndtLayer());
    const rm_ndt_hit_miss* hit_miss =
        map.hitMissLayer() >= 0 ? store.layerData<rm_ndt_hit_miss>(slot, map.hitMissLayer())
                                : nullptr;
    const rm_ndt_intensity* intensity =
        map.intensityLayer() >= 0 ? store.layerData<rm_ndt_intensity>(slot, map.intensityLayer())
                                  : nullptr;
    std::uint32_t index = 0;
    for (std::int32_t z = 0; z < n; ++z) {
      for (std::int32_t y = 0; y < n; ++y) {
        for (std::int32_t x = 0; x < n; ++x, ++index) {
          const rm_ndt_voxel& v = ndt[index];
          if (v.count == 0 || rm_occupancy_occupied(occupancy[index], threshold) == 0) {
            continue;
          }
          const Vec3i voxel{region.x * n + x, region.y * n + y, region.z * n + z};
          Gaussian g;
          g.count = v.count;
          g.mean_m = map.pointInVoxel(voxel, rm_ndt_mean(&v));
          float p[6];
          rm_ndt_covariance(v.s, p);
          std::array<double, 6> p_m2{};  // metres squared
          for (std::size_t k = 0; k < 6; ++k) {
            p_m2[k] = static_cast<double>(p[k]) * resolution * resolution;
          }
          const PrincipalAxes e = principalAxes(p_m2);
          for (int k = 0; k < 3; ++k) {
            const auto at = static_cast<std::size_t>(k);
            g.axes_m[at] =
                std::max(options.sigmas * std::sqrt(std::max(e.variances[k], 0.0)), min_axis);
            g.axes_dir[at] = toVec3(e.axes.col(k));
          }
          switch (options.colour) {
            case NdtColour::kHeight:
              g.colour_value = g.mean_m.z;
              break;
            case NdtColour::kIntensity:
              g.colour_value = static_cast<double>(intensity[index].mean);
              break;
            case NdtColour::kPermeability: {
              const double total = static_cast<double>(hit_miss[index].hit) + hit_miss[index].miss;
              g.colour_value = total > 0 ? hit_miss[index].miss / total : 0.0;
              break;
            }
          }
          out.push_back(g);
        }
      }
    }
  }
  if (auto ok = cursor.status(); !ok) {
    return Unexpected(ok.error());
  }
  return out;
}

/// Maps colour values to [0, 1]: permeability as is, the others over their exported range.
std::vector<Rgb8> colours(const std::vector<Gaussian>& gaussians, NdtColour colour) {
  double lo = 0.0;
  double hi = 1.0;
  if (colour != NdtColour::kPermeability && !gaussians.empty()) {
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    for (const Gaussian& g : gaussians) {
      lo = std::min(lo, g.colour_value);
      hi = std::max(hi, g.colour_value);
    }
  }
  const double span = hi > lo ? hi - lo : 1.0;
  std::vector<Rgb8> out;
  out.reserve(gaussians.size());
  for (const Gaussian& g : gaussians) {
    out.push_back(rampColour((g.colour_value - lo) / span));
  }
  return out;
}

Expected<void, Error> checkMap(const VoxelMap& map, const NdtExportOptions& options) {
  if (auto ok = options.validate(); !ok) {
    return ok;
  }
  if (map.ndtLayer() < 0 || map.occupancyLayer() < 0) {
    return fail(ErrorCode::kUnsupported, std::string("the map is an ") + toString(map.mode()) +
                                             " map without NDT Gaussians (build it with "
                                             "map.mode: ndt-om or ndt-tm)");
  }
  if (options.colour == NdtColour::kIntensity && map.intensityLayer() < 0) {
    return fail(ErrorCode::kUnsupported, "colour by intensity needs an ndt-tm map (this one is " +
                                             std::string(toString(map.mode())) + ")");
  }
  if (options.colour == NdtColour::kPermeability && map.hitMissLayer() < 0) {
    return fail(ErrorCode::kUnsupported,
                "colour by permeability needs an ndt-tm map (this one is " +
                    std::string(toString(map.mode())) + ")");
  }
  return {};
}

void putRgb(LeBuffer& out, Rgb8 c) {
  out.u8(c.r);
  out.u8(c.g);
  out.u8(c.b);
}

std::string commentLine(const VoxelMap& map, const NdtExportOptions& options) {
  char text[256];
  std::snprintf(text, sizeof(text),
                "comment raymap NDT export: %s map, resolution %g m, world frame, metres, %g "
                "sigma, colour %s\n",
                toString(map.mode()), map.geometry().resolution, options.sigmas,
                toString(options.colour));
  return text;
}

/// Unit-sphere vertices: north pole, rings from north to south, south pole.
std::array<Vec3d, kEllipsoidVertices> unitSphere() {
  std::array<Vec3d, kEllipsoidVertices> v{};
  std::size_t at = 0;
  v[at++] = Vec3d{0, 0, 1};
  for (int stack = 1; stack < kStacks; ++stack) {
    const double polar = std::numbers::pi * stack / kStacks;
    for (int slice = 0; slice < kSlices; ++slice) {
      const double azimuth = 2.0 * std::numbers::pi * slice / kSlices;
      v[at++] = Vec3d{std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                      std::cos(polar)};
    }
  }
  v[at] = Vec3d{0, 0, -1};
  return v;
}

/// Triangles of the unit sphere (counter-clockwise seen from outside), as vertex indices.
std::vector<std::array<std::uint32_t, 3>> unitSphereFaces() {
  std::vector<std::array<std::uint32_t, 3>> faces;
  const auto ring = [](int stack, int slice) {
    return static_cast<std::uint32_t>(1 + (stack - 1) * kSlices + (slice % kSlices));
  };
  const std::uint32_t south = kEllipsoidVertices - 1;
  for (int s = 0; s < kSlices; ++s) {
    faces.push_back({0u, ring(1, s), ring(1, s + 1)});
  }
  for (int stack = 1; stack < kStacks - 1; ++stack) {
    for (int s = 0; s < kSlices; ++s) {
      faces.push_back({ring(stack, s), ring(stack + 1, s), ring(stack + 1, s + 1)});
      faces.push_back({ring(stack, s), ring(stack + 1, s + 1), ring(stack, s + 1)});
    }
  }
  for (int s = 0; s < kSlices; ++s) {
    faces.push_back({ring(kStacks - 1, s), south, ring(kStacks - 1, s + 1)});
  }
  return faces;
}

}  // namespace

PrincipalAxes principalAxes(const std::array<double, 6>& p) noexcept {
  Eigen::Matrix3d covariance;
  covariance << p[0], p[1], p[3],  //
      p[1], p[2], p[4],            //
      p[3], p[4], p[5];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  PrincipalAxes out{solver.eigenvalues(), solver.eigenvectors()};
  if (out.axes.determinant() < 0.0) {
    out.axes.col(2) = -out.axes.col(2);  // a reflection: make the frame right-handed
  }
  return out;
}

Result<NdtColour> ndtColourFromString(const std::string& text) {
  for (const NdtColour c : {NdtColour::kHeight, NdtColour::kIntensity, NdtColour::kPermeability}) {
    if (text == toString(c)) {
      return c;
    }
  }
  return fail(ErrorCode::kInvalidArgument,
              "unknown colour '" + text + "' (expected height, intensity or permeability)");
}

const char* toString(NdtColour colour) noexcept {
  switch (colour) {
    case NdtColour::kHeight:
      return "height";
    case NdtColour::kIntensity:
      return "intensity";
    case NdtColour::kPermeability:
      return "permeability";
  }
  return "unknown";
}

Expected<void, Error> NdtExportOptions::validate() const {
  if (!std::isfinite(sigmas) || !(sigmas > 0.0) || sigmas > kMaxSigmas) {
    return fail(ErrorCode::kInvalidArgument, "export.sigmas must be in (0, 100]");
  }
  if (min_axis_m && (!std::isfinite(*min_axis_m) || *min_axis_m < 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "export.min_axis must be a non-negative length in metres");
  }
  return {};
}

Rgb8 rampColour(double value) noexcept {
  static constexpr std::array<std::array<double, 3>, 5> kStops = {
      {{0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}}};
  const double t = std::clamp(std::isfinite(value) ? value : 0.0, 0.0, 1.0) * 4.0;
  const auto lo = static_cast<std::size_t>(std::min(std::floor(t), 3.0));
  const double f = t - static_cast<double>(lo);
  const auto channel = [&](std::size_t c) {
    return static_cast<std::uint8_t>(
        std::lround(kStops[lo][c] + (kStops[lo + 1][c] - kStops[lo][c]) * f));
  };
  return Rgb8{channel(0), channel(1), channel(2)};
}

Result<std::uint64_t> exportNdtEllipsoids(const VoxelMap& map, const NdtExportOptions& options,
                                          const std::string& path) {
  if (auto ok = checkMap(map, options); !ok) {
    return Unexpected(ok.error());
  }
  auto collected = collect(map, options);
  if (!collected) {
    return Unexpected(collected.error());
  }
  const std::vector<Gaussian>& gaussians = *collected;
  const std::uint64_t vertex_count = gaussians.size() * std::uint64_t{kEllipsoidVertices};
  if (vertex_count > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
    return fail(ErrorCode::kCapacity, std::to_string(gaussians.size()) +
                                          " ellipsoids are too many for one PLY mesh (int "
                                          "vertex indices); use export.mode: ndt-points");
  }
  const std::vector<Rgb8> rgb = colours(gaussians, options.colour);
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  const std::string header = "ply\nformat binary_little_endian 1.0\n" + commentLine(map, options) +
                             "element vertex " + std::to_string(vertex_count) +
                             "\nproperty float x\nproperty float y\nproperty float z\n"
                             "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                             "element face " +
                             std::to_string(gaussians.size() * std::uint64_t{kEllipsoidFaces}) +
                             "\nproperty list uchar int vertex_indices\nend_header\n";
  if (auto ok = writer->write(header); !ok) {
    return Unexpected(ok.error());
  }
  const std::array<Vec3d, kEllipsoidVertices> sphere = unitSphere();
  LeBuffer out;
  for (std::size_t i = 0; i < gaussians.size(); ++i) {
    const Gaussian& g = gaussians[i];
    for (const Vec3d& u : sphere) {
      const Vec3d p = g.mean_m + g.axes_dir[0] * (u.x * g.axes_m[0]) +
                      g.axes_dir[1] * (u.y * g.axes_m[1]) + g.axes_dir[2] * (u.z * g.axes_m[2]);
      out.f32(p.x);
      out.f32(p.y);
      out.f32(p.z);
      putRgb(out, rgb[i]);
    }
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  const std::vector<std::array<std::uint32_t, 3>> faces = unitSphereFaces();
  for (std::size_t i = 0; i < gaussians.size(); ++i) {
    const auto base = static_cast<std::uint32_t>(i * kEllipsoidVertices);
    for (const auto& face : faces) {
      out.u8(3);
      for (const std::uint32_t corner : face) {
        out.u32(base + corner);
      }
    }
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  if (auto ok = out.finish(*writer); !ok) {
    return Unexpected(ok.error());
  }
  return gaussians.size();
}

Result<std::uint64_t> exportNdtPoints(const VoxelMap& map, const NdtExportOptions& options,
                                      const std::string& path) {
  if (auto ok = checkMap(map, options); !ok) {
    return Unexpected(ok.error());
  }
  auto collected = collect(map, options);
  if (!collected) {
    return Unexpected(collected.error());
  }
  const std::vector<Gaussian>& gaussians = *collected;
  const std::vector<Rgb8> rgb = colours(gaussians, options.colour);
  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  const std::string header = "ply\nformat binary_little_endian 1.0\n" + commentLine(map, options) +
                             "element vertex " + std::to_string(gaussians.size()) +
                             "\nproperty float x\nproperty float y\nproperty float z\n"
                             "property float nx\nproperty float ny\nproperty float nz\n"
                             "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                             "property uint count\nend_header\n";
  if (auto ok = writer->write(header); !ok) {
    return Unexpected(ok.error());
  }
  LeBuffer out;
  for (std::size_t i = 0; i < gaussians.size(); ++i) {
    const Gaussian& g = gaussians[i];
    // The normal of a surfel is its direction of least spread; its sign is arbitrary, so it is
    // turned up (nz >= 0) for a consistent look on ground and roofs.
    const Vec3d normal = g.axes_dir[0].z < 0.0 ? g.axes_dir[0] * -1.0 : g.axes_dir[0];
    out.f32(g.mean_m.x);
    out.f32(g.mean_m.y);
    out.f32(g.mean_m.z);
    out.f32(normal.x);
    out.f32(normal.y);
    out.f32(normal.z);
    putRgb(out, rgb[i]);
    out.u32(g.count);
    if (auto ok = out.flush(*writer, false); !ok) {
      return Unexpected(ok.error());
    }
  }
  if (auto ok = out.finish(*writer); !ok) {
    return Unexpected(ok.error());
  }
  return gaussians.size();
}

}  // namespace raymap::io
