// SPDX-License-Identifier: BSD-3-Clause
// Exporting occupied, free or mean voxels of a map as a binary little-endian point-cloud PLY.
#include "src/io/map_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>
#include <vector>

#include "kernels/common/decay.h"
#include "kernels/common/occupancy.h"
#include "kernels/common/voxel_mean.h"
#include "src/core/byte_order.hpp"
#include "src/io/atomic_file.hpp"

namespace raymap::io {
namespace {

// float x y z probability, uint count; kDecay adds float decay_rate traversal.
constexpr std::size_t kRecordBytes = 5 * 4;
constexpr std::size_t kDecayRecordBytes = 7 * 4;
constexpr std::size_t kPointsPerChunk = 16384;
// Written for voxels no ray observed (mean mode only): the prior, "unknown".
constexpr float kUnobservedProbability = 0.5f;

struct Point {
  Vec3i voxel;    ///< the voxel's key
  Vec3d p_world;  ///< metres
  float probability = 0.0f;
  std::uint32_t count = 0;
  float decay_rate = 0.0f;  ///< kDecay: per metre
  float traversal = 0.0f;   ///< kDecay: metres
};

/// Calls fn(point) for every voxel `mode` selects: regions in coordinate order (z, y, x), voxels
/// in index order, so the output is deterministic. A tiered map's regions stream through its
/// pool; a cold region that cannot be read back fails the walk.
template <class Fn>
Expected<void, Error> forEachPoint(const VoxelMap& map, ExportMode mode,
                                   const ExportOptions& options, Fn&& fn) {
  const RegionStore& store = map.store();
  RegionCursor cursor(map);

  const std::int32_t n = map.geometry().region_voxels;
  const float threshold = map.occupancy().threshold;
  const int mean_layer = map.meanLayer();
  const auto decay_threshold = static_cast<float>(options.decay_threshold);
  while (cursor.next()) {
    const Vec3i region = cursor.region();
    const std::uint32_t slot = cursor.slot();
    // Maps of decay rates only have no occupancy: every voxel reads as unobserved.
    const float* occupancy =
        map.occupancyLayer() >= 0 ? store.layerData<float>(slot, map.occupancyLayer()) : nullptr;
    const float* traversal =
        map.traversalLayer() >= 0 ? store.layerData<float>(slot, map.traversalLayer()) : nullptr;
    const rm_voxel_mean* means =
        mean_layer >= 0 ? store.layerData<rm_voxel_mean>(slot, mean_layer) : nullptr;
    std::uint32_t index = 0;
    for (std::int32_t z = 0; z < n; ++z) {
      for (std::int32_t y = 0; y < n; ++y) {
        for (std::int32_t x = 0; x < n; ++x, ++index) {
          const float value = occupancy != nullptr ? occupancy[index] : RM_OCC_UNOBSERVED;
          const rm_voxel_mean mean = means != nullptr ? means[index] : rm_voxel_mean{0u, 0u};
          const bool observed = rm_occupancy_observed(value) != 0;
          bool selected = false;
          bool at_mean = false;
          const float metres = traversal != nullptr ? traversal[index] : 0.0f;
          const float rate = rm_decay_rate(mean.count, metres);
          switch (mode) {
            case ExportMode::kOccupied:
              selected = rm_occupancy_occupied(value, threshold) != 0;
              at_mean = true;
              break;
            case ExportMode::kFree:
              selected = observed && rm_occupancy_free(value, threshold) != 0;
              break;
            case ExportMode::kMean:
              selected = mean.count > 0;
              at_mean = true;
              break;
            case ExportMode::kDecay:
              selected = rate >= decay_threshold;  // false for NaN: no ray entered the voxel
              at_mean = true;
              break;
          }
          if (!selected) {
            continue;
          }
          const Vec3i voxel{region.x * n + x, region.y * n + y, region.z * n + z};
          Point point;
          point.voxel = voxel;
          // Voxel-local mean in voxel units (the centre when the voxel has no samples).
          const rm_vec3f local =
              at_mean ? rm_mean_decode(mean.packed, mean.count) : rm_vec3f_make(0.5f, 0.5f, 0.5f);
          point.p_world = map.pointInVoxel(voxel, local);
          point.probability =
              observed ? static_cast<float>(probability(value)) : kUnobservedProbability;
          point.count = mean.count;
          point.decay_rate = std::min(rate, std::numeric_limits<float>::max());
          point.traversal = metres;
          fn(point);
        }
      }
    }
  }
  return cursor.status();
}

/// The layers every mode reads: occupied and free voxels need occupancy, the others occupancy or
/// the voxel mean.
Expected<void, Error> checkOccupancyLayer(const VoxelMap& map, ExportMode mode) {
  const bool needs_occupancy = mode == ExportMode::kOccupied || mode == ExportMode::kFree;
  if (map.occupancyLayer() < 0 && (needs_occupancy || map.meanLayer() < 0)) {
    return fail(ErrorCode::kUnsupported,
                std::string("the map has no occupancy layer: nothing to export as ") +
                    (needs_occupancy ? "occupied or free voxels" : "voxels"));
  }
  return {};
}

}  // namespace

Result<std::vector<Vec3i>> selectedVoxels(const VoxelMap& map, ExportMode mode) {
  if (mode == ExportMode::kDecay) {
    return fail(ErrorCode::kInvalidArgument, "selectedVoxels: decay voxels need a threshold");
  }
  if (auto ok = checkOccupancyLayer(map, mode); !ok) {
    return Unexpected(ok.error());
  }
  std::vector<Vec3i> keys;
  if (auto ok = forEachPoint(map, mode, ExportOptions{},
                             [&](const Point& point) { keys.push_back(point.voxel); });
      !ok) {
    return Unexpected(ok.error());
  }
  return keys;
}

namespace {

std::string headerText(const VoxelMap& map, ExportMode mode, std::uint64_t count) {
  char resolution[64];
  std::snprintf(resolution, sizeof(resolution), "%g", map.geometry().resolution);
  return std::string(
             "ply\n"
             "format binary_little_endian 1.0\n"
             "comment raymap map export: ") +
         toString(mode) + " voxels, resolution " + resolution +
         " m, world frame, metres\n"
         "element vertex " +
         std::to_string(count) +
         "\n"
         "property float x\n"
         "property float y\n"
         "property float z\n"
         "property float probability\n"
         "property uint count\n" +
         (mode == ExportMode::kDecay ? "property float decay_rate\nproperty float traversal\n"
                                     : "") +
         "end_header\n";
}

}  // namespace

Result<ExportMode> exportModeFromString(const std::string& text) {
  for (const ExportMode mode :
       {ExportMode::kOccupied, ExportMode::kFree, ExportMode::kMean, ExportMode::kDecay}) {
    if (text == toString(mode)) {
      return mode;
    }
  }
  return fail(ErrorCode::kInvalidArgument,
              "unknown export mode '" + text + "' (expected occupied, free, mean or decay)");
}

const char* toString(ExportMode mode) noexcept {
  switch (mode) {
    case ExportMode::kOccupied:
      return "occupied";
    case ExportMode::kFree:
      return "free";
    case ExportMode::kMean:
      return "mean";
    case ExportMode::kDecay:
      return "decay";
  }
  return "unknown";
}

Result<std::uint64_t> exportPly(const VoxelMap& map, ExportMode mode, const std::string& path,
                                const ExportOptions& options) {
  if (auto ok = checkOccupancyLayer(map, mode); !ok) {
    return Unexpected(ok.error());
  }
  if (mode == ExportMode::kDecay) {
    if (map.traversalLayer() < 0 || map.meanLayer() < 0) {
      return fail(ErrorCode::kUnsupported,
                  "the map has no traversal layer: decay rates need a map built with map.mode: "
                  "decay or map.decay_rate: true");
    }
    if (!std::isfinite(options.decay_threshold) || options.decay_threshold < 0.0) {
      return fail(ErrorCode::kInvalidArgument,
                  "decay-rate threshold must be a finite number of reflections per metre >= 0");
    }
  }
  const std::size_t record_bytes = mode == ExportMode::kDecay ? kDecayRecordBytes : kRecordBytes;
  // Count first so that the header is final before any point is written (one cheap extra pass
  // over the voxels instead of patching the file).
  std::uint64_t count = 0;
  if (auto ok = forEachPoint(map, mode, options, [&](const Point&) { ++count; }); !ok) {
    return Unexpected(ok.error());
  }

  auto writer = AtomicFileWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = writer->write(headerText(map, mode, count)); !ok) {
    return Unexpected(ok.error());
  }
  std::vector<std::byte> buffer;
  buffer.reserve(kPointsPerChunk * record_bytes);
  Expected<void, Error> status;
  const auto flush = [&]() {
    if (status && !buffer.empty()) {
      status = writer->write(buffer);
    }
    buffer.clear();
  };
  auto walked = forEachPoint(map, mode, options, [&](const Point& point) {
    std::byte record[kDecayRecordBytes];
    std::byte* out = record;
    out = storeLe(out, static_cast<float>(point.p_world.x));
    out = storeLe(out, static_cast<float>(point.p_world.y));
    out = storeLe(out, static_cast<float>(point.p_world.z));
    out = storeLe(out, point.probability);
    out = storeLe(out, point.count);
    if (mode == ExportMode::kDecay) {
      out = storeLe(out, point.decay_rate);
      storeLe(out, point.traversal);
    }
    buffer.insert(buffer.end(), record, record + record_bytes);
    if (buffer.size() >= kPointsPerChunk * record_bytes) {
      flush();
    }
  });
  flush();
  if (!walked) {
    return Unexpected(walked.error());
  }
  if (!status) {
    return Unexpected(status.error());
  }
  if (auto ok = writer->commit(); !ok) {
    return Unexpected(ok.error());
  }
  return count;
}

}  // namespace raymap::io
