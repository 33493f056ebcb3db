// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper: the map, its backend, one RayPreparer and the RayBatcher (the batching loop
// `raymap populate` and raymapd use too), behind the public API of include/raymap/mapper.hpp.
#include "raymap/mapper.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kernels/common/occupancy.h"
#include "kernels/common/voxel_mean.h"
#include "src/core/eigen_conversions.hpp"
#include "src/device/backend_choice.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/io/map_export.hpp"
#include "src/io/map_exports.hpp"
#include "src/io/map_file.hpp"
#include "src/io/sensor_ray.hpp"
#include "src/io/trajectory.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/mapper/mapper_conversions.hpp"
#include "src/mapper/pool_fit.hpp"
#include "src/mapper/tier_report.hpp"
#include "src/mapper/voxel_layers.hpp"
#include "src/msgs/depth_image.hpp"

namespace raymap {
namespace {

/// Rays converted from the caller's scan per RayBatcher::add() call (the conversion buffer).
constexpr std::size_t kChunkRays = 4096;

/// A time in seconds as whole nanoseconds (the deskewing tables' clock); nullopt when it is not
/// finite or beyond the +-292 years an int64 holds.
std::optional<std::int64_t> nanoseconds(double seconds) noexcept {
  const double ns = seconds * 1e9;
  if (!std::isfinite(ns) || std::fabs(ns) > 9.0e18) {
    return std::nullopt;
  }
  return std::llround(ns);
}

}  // namespace

struct Mapper::State {
  State(VoxelMap map_in, const RayFilter& filter) : map(std::move(map_in)), preparer(map, filter) {}

  VoxelMap map;  // never moves: the preparer, the backend and the batcher point at it
  MapOptions options;
  backends::CreatedBackend backend;
  RayPreparer preparer;
  std::unique_ptr<RayBatcher> batcher;
  std::vector<Ray> chunk = std::vector<Ray>(kChunkRays);
  std::size_t chunk_fill = 0;
  std::uint64_t next_scan = 0;
  std::uint64_t points_no_pose = 0;
  std::vector<rm_scan_point> table_points;  // integrateWithTable(): grow to the largest scan
  std::vector<rm_pose_sample> table_poses;
  PixelRayTable depth_rays;                   // integrate(depth): the last camera's pixel rays
  std::vector<msgs::ScanPoint> depth_points;  // grows to the largest image's points
  std::uint64_t depth_no_depth = 0;
  std::string memory_warning;  // why the pool is smaller than map.max_memory asked (create())
  std::unique_ptr<heightmap::HeightmapGenerator> generator;  // made on the first heightmap()
  heightmap::HeightmapPlan plan;
  heightmap::HeightMap grid;

  /// Starts the backend over the map, and the batcher that feeds it.
  Expected<void, Error> startBackend(const BackendOptions& choice) {
    auto made = backends::createBackend(map, mapper::toBackendChoice(choice));
    if (!made) {
      return Unexpected(made.error());
    }
    backend = std::move(*made);
    batcher = std::make_unique<RayBatcher>(
        map, *backend.backend,
        choice.batch_rays != 0 ? choice.batch_rays : backend.backend->preferredBatchRays());
    return {};
  }
  Error integrateError(IntegrateError error) const {
    return integrateFailure(map, *backend.backend, error, "MapOptions::max_memory_bytes");
  }
  /// Integrates the converted rays (one scan) and empties the conversion buffer.
  Expected<void, Error> drainChunk() noexcept {
    const std::span<const Ray> rays(chunk.data(), chunk_fill);
    chunk_fill = 0;
    if (auto ok = batcher->add(preparer, rays); !ok) {
      return Unexpected(integrateError(ok.error()));
    }
    return {};
  }
  Expected<void, Error> push(const Ray& ray) noexcept {
    chunk[chunk_fill++] = ray;
    return chunk_fill == chunk.size() ? drainChunk() : Expected<void, Error>{};
  }
  /// Ends a scan: its last rays go to the batcher (which counts the scan), and the next scan
  /// gets its own number.
  Expected<void, Error> endScan() noexcept {
    ++next_scan;
    return drainChunk();
  }
  /// One scan of sensor-frame points; `pose_at(time)` gives the sensor's pose (or nullopt), asked
  /// once per distinct point time (a lidar's points come in blocks of one time).
  template <class PoseAt>
  Expected<void, Error> integratePoints(std::span<const SensorPoint> scan, const PoseAt& pose_at) {
    Ray ray;
    ray.scan = next_scan;
    io::Pose pose;
    bool have_pose = false;
    double pose_time = std::numeric_limits<double>::quiet_NaN();
    for (const SensorPoint& p : scan) {
      if (!(p.time_s == pose_time)) {  // NaN never equals: the first point always asks
        const std::optional<Eigen::Isometry3d> asked = pose_at(p.time_s);
        pose_time = p.time_s;
        have_pose = asked.has_value();
        if (have_pose) {
          // As a pose (a unit quaternion), converted as a pose table's and raymapd's are.
          pose = io::Pose::fromIsometry(*asked);
        }
      }
      if (!have_pose) {
        ++points_no_pose;
        continue;
      }
      io::aimRay(pose, p.position, ray);
      ray.time_s = p.time_s;
      ray.intensity = p.intensity;
      ray.flags = p.no_return ? kRayNoReturn : 0u;
      if (auto ok = push(ray); !ok) {
        return ok;
      }
    }
    return endScan();
  }
  /// One depth image (Mapper::integrate's contract for depth images).
  Expected<void, Error> integrateDepth(const DepthImageView& image, const CameraIntrinsics& camera,
                                       const Eigen::Isometry3d& camera_to_world,
                                       const DepthOptions& depth) {
    auto settings = mapper::toDepthDecodeOptions(depth);
    if (!settings) {
      return Unexpected(settings.error());
    }
    auto pixels = mapper::toDepthPixels(image, camera);
    if (!pixels) {
      return Unexpected(pixels.error());
    }
    if (!depth_rays.matches(camera)) {
      if (auto built = depth_rays.build(camera); !built) {
        return Unexpected(built.error());  // names the camera's field ("camera focal lengths …")
      }
    }
    const std::size_t capacity =
        msgs::depthPointCapacity(image.width, image.height, depth.downsample);
    if (depth_points.size() < capacity) {
      depth_points.resize(capacity);
    }
    const msgs::DepthImageHeader decoded =
        msgs::decodeDepthPixels(*pixels, depth_rays, *settings, depth_points);
    depth_no_depth += decoded.invalid - decoded.free_only;
    Ray ray;
    ray.scan = next_scan;
    const io::Pose camera_pose = io::Pose::fromIsometry(camera_to_world);
    for (const msgs::ScanPoint& p : std::span(depth_points).first(decoded.points)) {
      io::aimRay(camera_pose,
                 {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)},
                 ray);
      ray.flags = (p.flags & msgs::kPointFreeOnly) != 0u ? kRayNoReturn : 0u;
      if (auto ok = push(ray); !ok) {
        return ok;
      }
    }
    return endScan();
  }
  /// One scan deskewed from a table of sensor poses (Mapper::integrate's contract).
  Expected<void, Error> integrateWithTable(std::span<const SensorPoint> scan,
                                           std::span<const TimedPose> sensor_poses) {
    if (sensor_poses.empty()) {
      return fail(ErrorCode::kInvalidArgument, "sensor_poses: at least one pose is needed");
    }
    table_poses.clear();
    for (std::size_t i = 0; i < sensor_poses.size(); ++i) {
      const TimedPose& p = sensor_poses[i];
      const std::optional<std::int64_t> ns = nanoseconds(p.time_s);
      if (!ns || (i > 0 && !(p.time_s > sensor_poses[i - 1].time_s))) {
        return fail(ErrorCode::kInvalidArgument,
                    "sensor_poses[" + std::to_string(i) +
                        "]: times must be finite seconds and increase from one sample to the next");
      }
      const std::int64_t t = *ns;
      if (i > 0 && t <= table_poses.back().time_ns) {
        return fail(ErrorCode::kInvalidArgument,
                    "sensor_poses[" + std::to_string(i) +
                        "]: less than a nanosecond after the sample before it");
      }
      const io::Pose pose = io::Pose::fromIsometry(p.sensor_to_world);
      table_poses.push_back(rm_pose_sample{t, 0, io::toRmPose(pose)});
    }
    const std::int64_t first = table_poses.front().time_ns;
    const std::int64_t last = table_poses.back().time_ns;
    table_points.clear();
    for (const SensorPoint& p : scan) {
      const std::optional<std::int64_t> t = nanoseconds(p.time_s);
      if (!t || *t < first || *t > last) {
        ++points_no_pose;
        continue;
      }
      table_points.push_back(rm_scan_point{static_cast<float>(p.position.x()),
                                           static_cast<float>(p.position.y()),
                                           static_cast<float>(p.position.z()), p.intensity,
                                           p.no_return ? RM_RAW_RAY_NO_RETURN : 0u, 0u, *t});
    }
    // The sensor's pose is the table's: no extrinsic.
    const rm_deskew_segment segment{rm_pose{rm_vec3d{0.0, 0.0, 0.0}, rm_quat{1.0, 0.0, 0.0, 0.0}},
                                    0u, static_cast<rm_u32>(table_poses.size())};
    const std::uint64_t scan_number = next_scan;
    const DeskewTables tables{table_poses, std::span<const rm_deskew_segment>(&segment, 1),
                              std::span<const std::uint64_t>(&scan_number, 1)};
    ++next_scan;
    if (auto ok = batcher->integratePoints(preparer, table_points, tables); !ok) {
      return Unexpected(integrateError(ok.error()));
    }
    return {};
  }
  Expected<void, Error> synchronise() noexcept {
    if (auto ok = batcher->flush(); !ok) {
      return Unexpected(integrateError(ok.error()));
    }
    if (auto ok = backend.backend->synchronise(); !ok) {
      return Unexpected(integrateError(ok.error()));
    }
    return {};
  }
};

Mapper::Mapper(std::unique_ptr<State> state) noexcept : state_(std::move(state)) {}
Mapper::Mapper(Mapper&&) noexcept = default;
Mapper& Mapper::operator=(Mapper&&) noexcept = default;
Mapper::~Mapper() = default;

Result<Mapper> Mapper::create(const MapperConfig& config) {
  auto map_config = mapper::toMapConfig(config.map);
  if (!map_config) {
    return Unexpected(map_config.error());
  }
  map_config->device_scan_marks = config.backend.name != "cpu";  // the CPU keeps bits
  // A global pool no larger than this machine can fill, as raymap populate sizes it: each slot
  // costs bookkeeping up front, so a budget far beyond the memory would only cost memory.
  std::string memory_warning = mapper::fitPoolToMemory(*map_config);
  auto map = VoxelMap::create(*map_config);
  if (!map) {
    return Unexpected(map.error());
  }
  auto filter = mapper::toRayFilter(config.rays, config.backend.name != "cpu");
  if (!filter) {
    return Unexpected(filter.error());
  }
  auto state = std::make_unique<State>(std::move(*map), *filter);
  state->options = config.map;
  state->memory_warning = std::move(memory_warning);
  if (auto ok = state->startBackend(config.backend); !ok) {
    return Unexpected(ok.error());
  }
  return Mapper(std::move(state));
}

Result<Mapper> Mapper::load(const std::string& path, const RayOptions& rays,
                            const BackendOptions& backend_options) {
  io::MapLoadOptions load_options;
  load_options.memory_budget_bytes = MapConfig::kDefaultMemoryBudget;
  auto map = io::loadMap(path, load_options);
  if (!map) {
    return Unexpected(map.error());
  }
  auto filter = mapper::toRayFilter(rays, backend_options.name != "cpu");
  if (!filter) {
    return Unexpected(filter.error());
  }
  auto state = std::make_unique<State>(std::move(*map), *filter);
  state->options = mapper::toMapOptions(state->map.config());
  if (auto ok = state->startBackend(backend_options); !ok) {
    return Unexpected(ok.error());
  }
  return Mapper(std::move(state));
}

Expected<void, Error> Mapper::integrate(std::span<const WorldRay> scan) {
  State& s = *state_;
  Ray ray;
  ray.scan = s.next_scan;
  for (const WorldRay& in : scan) {
    ray.origin = toVec3(in.origin);
    ray.sample = toVec3(in.end);
    ray.intensity = in.intensity;
    ray.flags = in.no_return ? kRayNoReturn : 0u;
    if (auto ok = s.push(ray); !ok) {
      return ok;
    }
  }
  return s.endScan();
}

Expected<void, Error> Mapper::integrate(std::span<const SensorPoint> scan,
                                        const Eigen::Isometry3d& sensor_to_world) {
  return state_->integratePoints(scan, [&sensor_to_world](double) {
    return std::optional<Eigen::Isometry3d>(sensor_to_world);
  });
}

Expected<void, Error> Mapper::integrate(std::span<const SensorPoint> scan,
                                        const SensorPoseFunction& sensor_pose_at) {
  return state_->integratePoints(scan, sensor_pose_at);
}

Expected<void, Error> Mapper::integrate(std::span<const SensorPoint> scan,
                                        std::span<const TimedPose> sensor_poses) {
  return state_->integrateWithTable(scan, sensor_poses);
}

Expected<void, Error> Mapper::integrate(const DepthImageView& image, const CameraIntrinsics& camera,
                                        const Eigen::Isometry3d& camera_to_world,
                                        const DepthOptions& options) {
  return state_->integrateDepth(image, camera, camera_to_world, options);
}

Expected<void, Error> Mapper::flush() { return state_->synchronise(); }

Result<std::uint32_t> Mapper::moveWindow(const Eigen::Vector3d& centre) {
  State& s = *state_;
  if (s.map.config().policy != StorePolicy::kRolling) {
    return std::uint32_t{0};
  }
  // The batch's rays were prepared against the window they arrived in: they go in first.
  if (auto ok = s.batcher->flush(); !ok) {
    return Unexpected(s.integrateError(ok.error()));
  }
  return s.map.setWindowCentre(toVec3(centre));
}

std::optional<VoxelKey> Mapper::key(const Eigen::Vector3d& point) const noexcept {
  const Vec3d p = toVec3(point);
  if (!p.isFinite() || !state_->map.voxelInRange(p)) {
    return std::nullopt;
  }
  const Vec3i v = state_->map.voxelOf(p);
  return VoxelKey(v.x, v.y, v.z);
}

Eigen::Vector3d Mapper::centre(const VoxelKey& key) const noexcept {
  return toEigen(state_->map.voxelCentre(Vec3i{key.x(), key.y(), key.z()}));
}

VoxelState Mapper::occupancy(const Eigen::Vector3d& point) const noexcept {
  const std::optional<VoxelKey> k = key(point);
  return k ? occupancy(*k) : VoxelState::kUnobserved;
}

VoxelState Mapper::occupancy(const VoxelKey& key) const noexcept {
  return state_->map.state(Vec3i{key.x(), key.y(), key.z()});
}

VoxelInfo Mapper::voxel(const VoxelKey& key) const noexcept {
  const VoxelMap& map = state_->map;
  const Vec3i v{key.x(), key.y(), key.z()};
  VoxelInfo info;
  info.key = key;
  info.state = map.state(v);
  if (info.state != VoxelState::kUnobserved) {
    const float value = map.occupancyValue(v);
    info.log_odds = value;
    info.probability = probability(value);
  }
  if (map.meanLayer() >= 0) {
    const rm_voxel_mean mean = map.mean(v);
    info.samples = mean.count;
    if (mean.count > 0) {
      info.mean = toEigen(map.pointInVoxel(v, rm_mean_decode(mean.packed, mean.count)));
    }
  }
  info.ndt = mapper::ndtVoxel(map, v);
  info.tsdf = mapper::tsdfVoxel(map, v);
  info.decay = mapper::decayVoxel(map, v);
  return info;
}

MapCounts Mapper::counts() const noexcept {
  const MapSummary summary = state_->map.summarise();
  return MapCounts{summary.regions, summary.voxels_free, summary.voxels_occupied};
}

Result<std::vector<VoxelKey>> Mapper::voxels(VoxelState state) const {
  if (state == VoxelState::kUnobserved) {
    return fail(ErrorCode::kInvalidArgument,
                "voxels: list occupied or free voxels; the unobserved space has no end");
  }
  auto keys =
      io::selectedVoxels(state_->map, state == VoxelState::kOccupied ? io::ExportMode::kOccupied
                                                                     : io::ExportMode::kFree);
  if (!keys) {
    return Unexpected(keys.error());
  }
  std::vector<VoxelKey> out;
  out.reserve(keys->size());
  for (const Vec3i& key : *keys) {
    out.emplace_back(key.x, key.y, key.z);
  }
  return out;
}

Result<HeightMap> Mapper::heightmap(const HeightmapRequest& request) {
  State& s = *state_;
  if (!s.generator) {
    auto made = backends::createHeightmapGenerator(*s.backend.backend);
    if (!made) {
      return Unexpected(made.error());
    }
    s.generator = std::move(made->generator);
  }
  // A generator in the backend's context reads the map where integration left it; one that
  // reads the host store needs the device's map copied back first.
  if (s.generator->readsHostStore()) {
    if (auto ok = s.synchronise(); !ok) {
      return Unexpected(ok.error());
    }
  } else if (auto ok = s.batcher->flush(); !ok) {
    return Unexpected(s.integrateError(ok.error()));
  }
  if (auto ok = heightmap::planHeightmap(s.map, mapper::toHeightmapOptions(request), s.plan); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = s.generator->generate(s.map, s.plan, s.grid); !ok) {
    return Unexpected(ok.error());
  }
  HeightMap out;
  mapper::copyHeightMap(s.grid, out);
  return out;
}

Result<Costmap> Mapper::costmap(const HeightmapRequest& request, const CostmapOptions& options) {
  auto params = mapper::toCostmapParams(options);
  if (!params) {
    return Unexpected(params.error());
  }
  if (auto made = heightmap(request); !made) {
    return Unexpected(made.error());
  }
  const heightmap::HeightMap& grid = state_->grid;
  Costmap out;
  out.resolution = grid.resolution;
  out.width = grid.cells_x;
  out.height = grid.cells_y;
  const Vec3d origin = heightmap::costmapOrigin(grid);
  out.origin = {origin.x, origin.y};
  out.cells.resize(grid.cellCount());
  heightmap::computeCostmap(grid, *params, out.cells);
  return out;
}

Result<ExportCounts> Mapper::exportPly(const std::string& path, const ExportRequest& request) {
  if (auto ok = state_->synchronise(); !ok) {
    return Unexpected(ok.error());
  }
  auto counts = io::exportMap(state_->map, request, path);
  if (!counts) {
    return counts;
  }
  // A tiered map that could not read a region back wrote an incomplete file: say so.
  if (auto ok = mapper::checkTiers(state_->map); !ok) {
    return Unexpected(ok.error());
  }
  return counts;
}

Expected<void, Error> Mapper::save(const std::string& path) {
  if (auto ok = state_->synchronise(); !ok) {
    return ok;
  }
  return io::saveMap(state_->map, path);
}

MapperCounters Mapper::counters() const noexcept {
  const State& s = *state_;
  const RayCounters& rays = s.preparer.counters();
  MapperCounters c;
  c.scans = s.batcher->counters().scans;
  c.rays_in = rays.rays_in;
  c.rays_integrated = rays.rays_accepted;
  c.rays_invalid = rays.rays_invalid;
  c.rays_too_short = rays.rays_too_short;
  c.rays_out_of_bounds = rays.rays_out_of_bounds + rays.rays_outside_window;
  c.rays_clipped = rays.rays_clipped;
  c.rays_no_return = rays.rays_no_return;
  c.points_no_pose = s.points_no_pose;
  c.depth_no_depth = s.depth_no_depth;
  c.batches = s.batcher->counters().batches;
  c.rays_pending = s.batcher->pending();
  const BackendStats backend = s.backend.backend->stats();
  c.rays_prepared_on_device = backend.rays_prepared_on_device;
  c.points_deskewed_on_device = backend.points_deskewed_on_device;
  return c;
}

const MapOptions& Mapper::mapOptions() const noexcept { return state_->options; }

std::string Mapper::backendName() const { return state_->backend.backend->name(); }

const std::string& Mapper::fallbackWarning() const noexcept {
  return state_->backend.fallback_warning;
}

const std::string& Mapper::memoryWarning() const noexcept { return state_->memory_warning; }

}  // namespace raymap
