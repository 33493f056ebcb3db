// SPDX-License-Identifier: BSD-3-Clause
// openRaySource: maps PLY vertex properties onto rays (ray clouds, or points plus a trajectory).
#include "src/io/ray_source.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "src/core/eigen_conversions.hpp"
#include "src/io/ply_reader.hpp"
#include "src/io/trajectory.hpp"

namespace raymap::io {
namespace {

/// Vertices decoded per step: bounds the staging buffer (kChunkRays x columns doubles) whatever
/// span the caller passes.
constexpr std::size_t kChunkRays = 4096;
/// Largest double below which every integer is exact: scan indices above it are not integers.
constexpr double kMaxExactInteger = 9007199254740992.0;  // 2^53

/// Time property names, highest priority first (LAS/PDAL, Ouster/ROS and generic spellings).
constexpr std::array<std::string_view, 8> kTimeNames{"gps_time",     "gpstime",     "internal_time",
                                                     "internaltime", "offset_time", "offsettime",
                                                     "timestamp",    "time"};

/// The vertex properties a ray is built from; each gets one column in the decoded rows.
enum Field : std::size_t {
  kX,
  kY,
  kZ,
  kNx,
  kNy,
  kNz,
  kTime,
  kIntensity,
  kAlpha,
  kScan,
  kFieldCount,
};

std::string formatNumber(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  return error == std::errc() ? std::string(text, end) : std::string("?");
}

class PlyRaySource final : public RaySource {
 public:
  PlyRaySource(PlyVertexReader ply, RaySourceInfo info, std::array<int, kFieldCount> column,
               std::size_t width, std::optional<Trajectory> trajectory,
               const RaySourceOptions& options, std::vector<double> rows)
      : ply_(std::move(ply)),
        info_(std::move(info)),
        column_(column),
        width_(width),
        trajectory_(std::move(trajectory)),
        sensor_offset_(options.sensor_offset),
        scan_period_s_(options.scan_period_s),
        rows_(std::move(rows)) {}

  Result<std::size_t> read(std::span<Ray> out) override {
    if (error_) {
      return Unexpected(*error_);
    }
    std::size_t done = 0;
    while (done < out.size()) {
      const std::size_t want = std::min(out.size() - done, kChunkRays);
      auto got = ply_.read(std::span<double>(rows_.data(), want * width_));
      if (!got) {
        error_ = std::move(got).error();
        return Unexpected(*error_);
      }
      if (*got == 0) {
        break;
      }
      if (auto built = buildRays(out.subspan(done, *got)); !built) {
        error_ = std::move(built).error();
        return Unexpected(*error_);
      }
      done += *got;
    }
    return done;
  }

  const RaySourceInfo& info() const noexcept override { return info_; }
  double progress() const noexcept override { return ply_.progress(); }

 private:
  /// Turns the first rays.size() decoded rows into rays.
  Expected<void, Error> buildRays(std::span<Ray> rays) {
    const std::uint64_t first_vertex = ply_.verticesRead() - rays.size() + 1;  // 1-based
    const int c_time = column_[kTime];
    const int c_intensity = column_[kIntensity];
    const int c_alpha = column_[kAlpha];
    const int c_scan = column_[kScan];
    const bool scan_from_time = c_scan < 0 && c_time >= 0 && scan_period_s_ > 0.0;
    const auto at = [](const double* row, int c) { return row[static_cast<std::size_t>(c)]; };
    for (std::size_t r = 0; r < rays.size(); ++r) {
      const double* row = rows_.data() + r * width_;
      Ray& ray = rays[r];
      ray.sample = {at(row, column_[kX]), at(row, column_[kY]), at(row, column_[kZ])};
      ray.time_s = c_time >= 0 ? at(row, c_time) : 0.0;
      ray.intensity = c_intensity >= 0 ? static_cast<float>(at(row, c_intensity)) : 0.0f;
      ray.flags = c_alpha >= 0 && at(row, c_alpha) == 0.0 ? kRayNoReturn : 0u;
      if (c_scan >= 0) {
        const double scan = at(row, c_scan);
        if (!(scan >= 0.0 && scan <= kMaxExactInteger) || scan != std::floor(scan)) {
          return fail(ErrorCode::kFormat,
                      info_.path + ": vertex " + std::to_string(first_vertex + r) +
                          ": scan index " + formatNumber(scan) + " is not a non-negative integer");
        }
        ray.scan = static_cast<std::uint64_t>(scan);
      } else if (scan_from_time) {
        if (!first_time_) {
          first_time_ = ray.time_s;
        }
        // Points earlier than the first one (unordered files) stay in scan 0.
        const double index = std::floor((ray.time_s - *first_time_) / scan_period_s_);
        ray.scan =
            index >= 0.0 && index <= kMaxExactInteger ? static_cast<std::uint64_t>(index) : 0u;
      } else {
        ray.scan = 0;
      }
      if (info_.ray_cloud) {
        ray.origin =
            ray.sample + Vec3d{at(row, column_[kNx]), at(row, column_[kNy]), at(row, column_[kNz])};
        continue;
      }
      const std::optional<Pose> pose = trajectory_->poseAt(ray.time_s, segment_hint_);
      if (!pose) {
        return fail(ErrorCode::kInvalidArgument,
                    info_.path + ": point at time " + formatNumber(ray.time_s) +
                        " is outside the trajectory " + trajectory_->path() + " [" +
                        formatNumber(trajectory_->startTime()) + ", " +
                        formatNumber(trajectory_->endTime()) + "] (vertex " +
                        std::to_string(first_vertex + r) + ")");
      }
      // Without orientations the pose's rotation is the identity: origin = position + offset.
      ray.origin = toVec3(pose->transform(toEigen(sensor_offset_)));
    }
    return {};
  }

  PlyVertexReader ply_;
  RaySourceInfo info_;
  std::array<int, kFieldCount> column_;   // column of each field in a decoded row, -1 if absent
  std::size_t width_;                     // columns per decoded row
  std::optional<Trajectory> trajectory_;  // point clouds only
  Vec3d sensor_offset_;
  double scan_period_s_;
  std::vector<double> rows_;          // kChunkRays decoded rows
  std::optional<double> first_time_;  // time of the first vertex (scan from period)
  std::size_t segment_hint_ = 0;
  std::optional<Error> error_;  // a failed source keeps failing the same way
};

using FieldProperties = std::array<std::optional<std::size_t>, kFieldCount>;

/// Finds x, y, z (required), the per-point sensor vector, the time, intensity, alpha and scan
/// properties. `vector_names`: the vector's names as the file spells them (for messages).
Expected<void, Error> findProperties(const PlyElement& vertex, const std::string& path,
                                     FieldProperties& property, std::string& vector_names,
                                     std::string& time_name) {
  for (const auto& [field, name] : {std::pair{kX, "x"}, std::pair{kY, "y"}, std::pair{kZ, "z"}}) {
    property[field] = vertex.findProperty(name);
    if (!property[field]) {
      return fail(ErrorCode::kFormat,
                  path + ": the vertex element has no '" + name + "' property (x, y, z needed)");
    }
  }
  // Per-point sensor vectors: raycloudtools' nx ny nz, or PCL's normal_x normal_y normal_z.
  for (const auto& names : {std::array<const char*, 3>{"nx", "ny", "nz"},
                            std::array<const char*, 3>{"normal_x", "normal_y", "normal_z"}}) {
    std::optional<std::size_t> present;  // first axis the file has
    for (std::size_t axis = 0; axis < 3 && !present; ++axis) {
      present = vertex.findProperty(names[axis]).has_value() ? std::optional(axis) : std::nullopt;
    }
    if (!present) {
      continue;
    }
    for (std::size_t axis = 0; axis < 3; ++axis) {
      property[kNx + axis] = vertex.findProperty(names[axis]);
      if (!property[kNx + axis]) {
        return fail(ErrorCode::kFormat, path + ": the vertex element has '" +
                                            std::string(names[*present]) + "' but no '" +
                                            names[axis] + "' property");
      }
      vector_names += (axis == 0 ? "" : " ") + vertex.properties[*property[kNx + axis]].name;
    }
    break;
  }
  for (const std::string_view name : kTimeNames) {
    if (const auto index = vertex.findProperty(name)) {
      property[kTime] = index;
      time_name = vertex.properties[*index].name;
      break;
    }
  }
  property[kIntensity] = vertex.findProperty("intensity");
  property[kAlpha] = vertex.findProperty("alpha");
  property[kScan] = vertex.findProperty("scan");
  return {};
}

/// A ray cloud holds its origins and takes no trajectory; a point cloud needs one, and times to
/// look it up. @return the trajectory a point cloud's origins come from (none for a ray cloud)
Result<std::optional<Trajectory>> originsSource(const RaySourceInfo& info,
                                                const FieldProperties& property,
                                                const std::string& vector_names,
                                                const RaySourceOptions& options) {
  const std::string& path = info.path;
  // A trajectory with a ray cloud would be ignored (the file holds every origin): refused, so
  // that a user who meant a point cloud, or a different trajectory, is told.
  if (info.ray_cloud && !options.trajectory_path.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                path + " is a ray cloud: its vertices hold the vector to the sensor (" +
                    vector_names + "), so the trajectory " + options.trajectory_path +
                    " would not be used: leave source.trajectory out (it is for point clouds)");
  }
  if (info.ray_cloud) {
    return std::optional<Trajectory>();
  }
  if (options.trajectory_path.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                path +
                    " has no per-point sensor vector (nx ny nz); give a trajectory with "
                    "source.trajectory");
  }
  if (!property[kTime]) {
    return fail(ErrorCode::kFormat,
                path +
                    ": a point cloud needs a per-point time property (gps_time, gpstime, "
                    "internal_time, internaltime, offset_time, offsettime, timestamp or "
                    "time) to look up the trajectory " +
                    options.trajectory_path);
  }
  auto loaded = Trajectory::load(options.trajectory_path);
  if (!loaded) {
    return Unexpected(std::move(loaded).error());
  }
  return std::optional<Trajectory>(std::move(*loaded));
}

}  // namespace

Result<std::unique_ptr<RaySource>> openRaySource(const std::string& path,
                                                 const RaySourceOptions& options) {
  auto ply = PlyVertexReader::open(path);
  if (!ply) {
    return Unexpected(std::move(ply).error());
  }
  const PlyElement& vertex = ply->vertex();
  FieldProperties property{};
  std::string vector_names;
  std::string time_name;
  if (auto found = findProperties(vertex, path, property, vector_names, time_name); !found) {
    return Unexpected(found.error());
  }
  RaySourceInfo info;
  info.path = path;
  info.format = toString(ply->header().format);
  info.compressed = ply->compressed();
  info.ray_cloud = property[kNx].has_value();
  info.declared_rays = vertex.count;
  info.time_property = time_name;
  info.has_scan = property[kScan].has_value();
  info.has_intensity = property[kIntensity].has_value();
  info.has_alpha = property[kAlpha].has_value();
  auto trajectory = originsSource(info, property, vector_names, options);
  if (!trajectory) {
    return Unexpected(std::move(trajectory).error());
  }
  std::array<int, kFieldCount> column{};
  std::vector<std::size_t> selected;
  for (std::size_t field = 0; field < kFieldCount; ++field) {
    column[field] = property[field] ? static_cast<int>(selected.size()) : -1;
    if (property[field]) {
      selected.push_back(*property[field]);
    }
  }
  if (auto chosen = ply->selectColumns(selected); !chosen) {
    return Unexpected(std::move(chosen).error());
  }
  std::vector<double> rows(kChunkRays * selected.size());
  return std::unique_ptr<RaySource>(
      std::make_unique<PlyRaySource>(std::move(*ply), std::move(info), column, selected.size(),
                                     std::move(*trajectory), options, std::move(rows)));
}

}  // namespace raymap::io
