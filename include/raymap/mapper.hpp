// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper: a 3D occupancy map with its integration backend (CPU, OpenCL or CUDA), the ray
// preparation and the batching, behind one small value-typed API that speaks Eigen.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "raymap/depth_image.hpp"
#include "raymap/error.hpp"
#include "raymap/export.hpp"
#include "raymap/heightmap.hpp"
#include "raymap/map_types.hpp"
#include "raymap/mapper_config.hpp"
#include "raymap/scan.hpp"
#include <Eigen/Geometry>

namespace raymap {

/// @brief A voxel's key: its integer coordinates on the map's grid. Voxel k covers
/// [k * resolution, (k + 1) * resolution) metres on each axis of the world frame.
using VoxelKey = Eigen::Vector3i;

/// @brief An NDT voxel's Gaussian (MapMode::kNdtOm, kNdtTm), world frame. Plain value type.
struct NdtVoxelInfo {
  /// Samples in the Gaussian since it was last started afresh (the NDT rules restart it when a
  /// voxel that turned free is hit again); saturates at 2^32 - 1.
  std::uint32_t samples = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  ///< of those samples, metres
  /// Their covariance (the population covariance, divided by the count), metres squared;
  /// symmetric positive semi-definite; zero for one sample.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  /// NDT-TM only (nullopt for NDT-OM), since the Gaussian started: returns that fell on the
  /// voxel's surfel (or while it was too young to judge), and rays that crossed the surfel and
  /// ended elsewhere (OHM's rules, kernels/common/ndt.h); a return that is neither counts in
  /// neither. Permeability = misses / (hits + misses).
  std::optional<std::uint32_t> hits;
  std::optional<std::uint32_t> misses;
  /// NDT-TM only: running mean and variance of the returns' intensity (the sensor's units).
  std::optional<float> intensity_mean;
  std::optional<float> intensity_variance;
};

/// @brief A TSDF voxel (MapMode::kTsdf). Plain value type.
struct TsdfVoxelInfo {
  /// Signed distance to the surface along the rays, metres, truncated to +-truncation; positive
  /// in front of the surface (towards the sensor).
  float distance_m = 0.0f;
  float weight = 0.0f;  ///< sum of the fused rays' weights (> 0), at most TsdfOptions::max_weight
};

/// @brief A voxel's decay rate (MapOptions::decay_rate). Plain value type.
struct DecayVoxelInfo {
  float traversal_m = 0.0f;   ///< metres of ray path inside the voxel
  std::uint32_t samples = 0;  ///< returns that fell in it
  /// Reflections per metre of ray path: samples / traversal_m; 0 for a voxel crossed but never
  /// hit, +infinity for samples without path length (each on the face its ray entered by).
  float rate_per_m = 0.0f;
};

/// @brief What the map holds for one voxel. Plain value type.
struct VoxelInfo {
  VoxelKey key = VoxelKey::Zero();
  VoxelState state = VoxelState::kUnobserved;
  /// Occupancy log-odds; nullopt when unobserved (or the map has no occupancy layer).
  std::optional<float> log_odds;
  /// Occupancy probability (from log_odds); nullopt when unobserved.
  std::optional<double> probability;
  /// The mean of the samples (returns) that fell in the voxel, world frame, metres; nullopt
  /// without samples or without the voxel-mean layer.
  std::optional<Eigen::Vector3d> mean;
  std::uint32_t samples = 0;  ///< returns that fell in the voxel (0 without the voxel-mean layer)
  /// NDT maps: the voxel's Gaussian; nullopt before its first sample (or in another mode).
  std::optional<NdtVoxelInfo> ndt;
  /// TSDF maps: distance and weight; nullopt where no ray updated it (or in another mode).
  std::optional<TsdfVoxelInfo> tsdf;
  /// Maps with decay rates: nullopt where no ray entered the voxel (its rate is unknown).
  std::optional<DecayVoxelInfo> decay;
};

/// @brief What a Mapper did so far. Plain counters.
struct MapperCounters {
  std::uint64_t scans = 0;               ///< integrate() calls that carried at least one ray
  std::uint64_t rays_in = 0;             ///< rays offered (points with a pose included)
  std::uint64_t rays_integrated = 0;     ///< rays that went into the map (clipped ones included)
  std::uint64_t rays_invalid = 0;        ///< NaN or infinite coordinates (rejected)
  std::uint64_t rays_too_short = 0;      ///< shorter than RayOptions::min_range (rejected)
  std::uint64_t rays_out_of_bounds = 0;  ///< beyond the map's key range or max_ray_length
                                         ///< (rejected), or outside a rolling window
  std::uint64_t rays_clipped = 0;        ///< shortened to RayOptions::max_range (integrated)
  std::uint64_t rays_no_return = 0;      ///< free-space-only rays (integrated)
  std::uint64_t points_no_pose = 0;      ///< points left out: the pose function had no pose
  /// Depth pixels (or blocks, with down-sampling) without a valid depth that gave no ray (no
  /// return without invalid_as_free, or nearer than DepthOptions::min_range).
  std::uint64_t depth_no_depth = 0;
  std::uint64_t batches = 0;       ///< backend calls
  std::uint64_t rays_pending = 0;  ///< prepared rays waiting in the batch (see flush())
  /// Device backends planning on the device: rays the device prepared (range limits, keys),
  /// and of them points it deskewed first (integrate() with a pose table). 0 on the CPU.
  std::uint64_t rays_prepared_on_device = 0;
  std::uint64_t points_deskewed_on_device = 0;
};

/// @brief Voxel counts over the stored map.
struct MapCounts {
  std::uint64_t regions = 0;  ///< regions of region_voxels³ voxels allocated
  std::uint64_t voxels_free = 0;
  std::uint64_t voxels_occupied = 0;
};

/// @brief A 3D occupancy map with its integration backend: integrate scans, query voxels, make
/// height maps, save and load.
///
/// Rays go through the same preparation (range limits, invalid rays counted) and the same
/// batching as `raymap populate` and raymapd: prepared rays collect in a batch that is integrated
/// when full, at the end of each scan under per-scan semantics, and by flush(). Queries read the
/// map on the host, so they see what was integrated up to the last flush() (which also waits for
/// a device backend); save() and heightmap() flush first themselves.
///
/// Thread-safety: none: one thread at a time uses a Mapper (queries included, since integration
/// updates the map in place); different Mappers are independent. The CPU backend's worker
/// threads and a device's queue are internal.
/// Real-time: integrate() and flush() never do file I/O and, once the backend has seen a batch
/// (its scratch sized), allocate nothing: the conversion buffer and the batch are allocated by
/// create()/load(), and regions come from the preallocated pool. create(), load(), save() and
/// heightmap() allocate and are for start-up, shutdown or a non-real-time thread. No call throws
/// (errors are values), except std::bad_alloc where memory runs out.
class Mapper {
 public:
  /// @brief Builds an empty map and starts its backend. Errors name the option and the reason
  /// (an out-of-range value, a backend this build lacks, a device that fails to start).
  static Result<Mapper> create(const MapperConfig& config);
  /// @brief Loads a map saved by save() or `raymap populate` (its geometry, semantics, mode and
  /// probabilities come from the file) and starts `backend` over it; `rays` applies to what is
  /// integrated next. Errors name the file and the reason; nothing is loaded then.
  static Result<Mapper> load(const std::string& path, const RayOptions& rays = {},
                             const BackendOptions& backend = {});

  Mapper(Mapper&&) noexcept;
  Mapper& operator=(Mapper&&) noexcept;
  ~Mapper();

  /// @brief Integrates one scan of world-frame rays. Rays that are invalid or outside the limits
  /// are counted (counters()), not errors. @return an error only when the map is full (kCapacity,
  /// raise MapOptions::max_memory_bytes) or the device failed (kIo); rays of the failed batch are
  /// lost, the map keeps what went in before.
  Expected<void, Error> integrate(std::span<const WorldRay> scan);
  /// @brief Integrates one scan of sensor-frame points taken at one pose: p_world =
  /// sensor_to_world * p_sensor, and the sensor at sensor_to_world.translation(). The rotation is
  /// applied as its unit quaternion, as a pose table's and raymapd's are, so the same scan gives
  /// the same map through every overload.
  Expected<void, Error> integrate(std::span<const SensorPoint> scan,
                                  const Eigen::Isometry3d& sensor_to_world);
  /// @brief Integrates one scan of sensor-frame points with the sensor's pose at each point's
  /// time (deskewing a spinning lidar's sweep): `sensor_pose_at` is asked once per distinct time.
  Expected<void, Error> integrate(std::span<const SensorPoint> scan,
                                  const SensorPoseFunction& sensor_pose_at);
  /// @brief Integrates one scan of sensor-frame points with the sensor's pose at each point's
  /// time interpolated from `sensor_poses` (times increasing: position linearly, orientation by
  /// normalised linear interpolation along the shorter arc; a point at or after the last sample
  /// takes it). Points before the first sample or after the last are counted (points_no_pose)
  /// and left out. With a device backend planning on the device, the points, their times and the
  /// table go to the device and are deskewed there; the map is the same either way. The scan goes
  /// in before this returns (as flush() without the wait). @return kInvalidArgument naming the
  /// sample when the times are not finite and increasing or the table is empty; else as
  /// integrate(). Nothing is integrated on an error.
  Expected<void, Error> integrate(std::span<const SensorPoint> scan,
                                  std::span<const TimedPose> sensor_poses);
  /// @brief Integrates one depth image as one scan: each pixel's depth (or each block's nearest,
  /// DepthOptions::downsample) back-projected along the pixel's undistorted ray (`camera`: the
  /// plumb_bob model of sensor_msgs/CameraInfo) in the camera's optical frame (x right, y down, z
  /// forward), then into the world with `camera_to_world`. The pixel rays are computed once per
  /// camera and kept while the intrinsics stay the same. Pixels without depth are counted by the
  /// decoder, not errors (with invalid_as_free they clear free space). @return kInvalidArgument
  /// naming the field for an image whose size differs from the camera's, a step too small, no
  /// data, a camera that validate() refuses, or options out of range (depth.downsample …);
  /// nothing is integrated then. Else as integrate(). Allocates only when the intrinsics change
  /// or an image gives more points than any before.
  Expected<void, Error> integrate(const DepthImageView& image, const CameraIntrinsics& camera,
                                  const Eigen::Isometry3d& camera_to_world,
                                  const DepthOptions& options = {});
  /// @brief Integrates the rays waiting in the batch and waits for the backend (a device's map
  /// is copied back to the host), so that queries see every ray given so far.
  Expected<void, Error> flush();

  /// @brief Centres the rolling window (MapOptions::window) on `centre` (world frame, metres; to
  /// the nearest region): the rays waiting in the batch go in first, then regions that leave the
  /// window are emptied and recycled for the ones that enter it. Call it as the robot moves (a
  /// service does so before each height map). @return the regions recycled; 0 for a map without
  /// a window. Errors as flush(). Allocates: no.
  Result<std::uint32_t> moveWindow(const Eigen::Vector3d& centre);

  /// @brief The key of the voxel holding `point` (world frame, metres); nullopt beyond the
  /// map's key range (or for a non-finite point).
  std::optional<VoxelKey> key(const Eigen::Vector3d& point) const noexcept;
  /// @brief The centre of voxel `key`, world frame, metres.
  Eigen::Vector3d centre(const VoxelKey& key) const noexcept;
  /// @brief The state of the voxel holding `point` (world frame); unobserved beyond the key range.
  VoxelState occupancy(const Eigen::Vector3d& point) const noexcept;
  VoxelState occupancy(const VoxelKey& key) const noexcept;
  /// @brief Everything stored for a voxel.
  VoxelInfo voxel(const VoxelKey& key) const noexcept;
  /// @brief Voxel counts over the map (walks every stored region: not for a tight loop).
  MapCounts counts() const noexcept;
  /// @brief The keys of every voxel in `state` (kOccupied or kFree), in a fixed order (regions
  /// by z, y, x; voxels by index); centre() gives each one's position. Walks every stored region
  /// (a tiered map's cold regions stream through its pool) and allocates the list: not for a
  /// tight loop. Sees what was integrated up to the last flush(). @return kInvalidArgument for
  /// kUnobserved (the unobserved space has no end), kUnsupported for a map without occupancy.
  Result<std::vector<VoxelKey>> voxels(VoxelState state) const;

  /// @brief A height map around `request.centre`, made where the map is (on the device for a
  /// device backend). Errors name the option and the reason (a map without occupancy, a size
  /// beyond 8192 cells, a centre outside the stored map).
  Result<HeightMap> heightmap(const HeightmapRequest& request);

  /// @brief The Nav2 costmap of the height map `request` asks for (heightmap(), then each cell's
  /// cost from its step, slope and clearance as raymapd publishes it). Errors as heightmap(), and
  /// for options out of range naming the key (costmap.max_step …).
  Result<Costmap> costmap(const HeightmapRequest& request, const CostmapOptions& options = {});

  /// @brief Writes the map to `path` as a PLY file the way `raymap export` does (points,
  /// NDT ellipsoids, a TSDF surface or mesh: ExportRequest), via a temporary file renamed into
  /// place. Errors name the key of an option that does not fit the kind, or say which layer the
  /// map lacks; an existing file at `path` is then left as it was.
  Result<ExportCounts> exportPly(const std::string& path, const ExportRequest& request = {});

  /// @brief Writes the map to `path` (the .rmap format of `raymap populate`; a temporary file
  /// renamed into place, so a failure leaves any existing file as it was).
  Expected<void, Error> save(const std::string& path);

  MapperCounters counters() const noexcept;
  /// The map's settings (as created, or as read from the file by load()).
  const MapOptions& mapOptions() const noexcept;
  /// "cpu", "opencl" or "cuda": where integration runs.
  std::string backendName() const;
  /// Why the CPU fallback replaced the requested backend (BackendOptions::fallback_cpu); empty
  /// when it did not.
  const std::string& fallbackWarning() const noexcept;
  /// Why the map holds fewer regions than MapOptions::max_memory_bytes asked (create() sized a
  /// global map's pool to what this machine can fill: its available memory, cgroup limit or
  /// RLIMIT_AS, as `raymap populate` does); empty when the machine holds what was asked.
  const std::string& memoryWarning() const noexcept;

 private:
  struct State;
  explicit Mapper(std::unique_ptr<State> state) noexcept;
  std::unique_ptr<State> state_;
};

}  // namespace raymap
