// SPDX-License-Identifier: BSD-3-Clause
// Reading recorded data as world rays, one scan at a time: ray-cloud PLY files (plain or gzip),
// point clouds with a trajectory, and rosbag2 bags (MCAP or SQLite; PointCloud2 deskewed with
// Odometry or TF poses and /tf_static extrinsics, depth images with their CameraInfo), exactly
// as `raymap populate` reads them. No DDS is involved: a bag is read from its files.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/scan.hpp"
#include <Eigen/Core>

namespace raymap {

/// @brief How a rosbag2 bag becomes rays (`raymap populate`'s bag options; raymapd's sensors[]
/// and pose keys). Plain value type.
struct BagOptions {
  enum class PoseSource : std::uint8_t {
    kAuto,      ///< the Odometry topic when pose_topic is given or the bag has one, else TF
    kOdometry,  ///< nav_msgs/msg/Odometry on pose_topic
    kTf,        ///< the chain world_frame -> base_frame from /tf and /tf_static
  };
  /// PointCloud2 or depth Image (16UC1 mm, 32FC1 m) topics, one sensor each; ROS (/points) or
  /// DDS (rt/points) names. Empty: the only PointCloud2 topic, or without one the only Image.
  std::vector<std::string> topics;
  /// The CameraInfo topic of each Image topic, in their order; missing ones: the image topic's
  /// namespace + camera_info.
  std::vector<std::string> camera_info_topics;
  std::string pose_topic;  ///< empty: the only Odometry topic
  PoseSource pose_source = PoseSource::kAuto;
  std::string world_frame = "odom";      ///< TF poses: the chain's top
  std::string base_frame = "base_link";  ///< the robot's body
  /// The sensor in base_frame (metres) for a cloud frame /tf_static does not connect to it;
  /// without it such a cloud is an error naming the frames.
  std::optional<Eigen::Vector3d> sensor_offset;
  std::string time_field = "auto";  ///< the per-point time field: auto, a name, or none
  /// Depth images: N x N pixel blocks give their nearest valid depth (1 = every pixel).
  std::uint32_t downsample = 1;
  /// Depth images: depths nearer than this are left out of a block's minimum, metres.
  double depth_min_range = 0.0;
  /// Depth images: blocks without a depth clear free space this far when invalid_as_free,
  /// metres (needed then).
  double depth_max_range = 0.0;
  bool invalid_as_free = false;
  double max_rate_hz = 0.0;   ///< a sensor's messages closer together are skipped; 0 = all
  bool skip_damaged = false;  ///< read what a damaged bag holds instead of failing
};

/// @brief How a recording is read. Plain value type.
struct RecordingOptions {
  /// Point clouds without per-point origins: a text trajectory `time x y z [qw qx qy qz]` whose
  /// position at each point's time is the sensor's.
  std::string trajectory_path;
  /// The sensor in the trajectory's body frame, metres.
  Eigen::Vector3d sensor_offset = Eigen::Vector3d::Zero();
  /// Files without a `scan` property: a scan is each `scan_period_s` of point time (a value
  /// <= 0 reads the whole file as one scan). Seconds.
  double scan_period_s = 0.1;
  BagOptions bag;  ///< used when the path is a bag (a folder with metadata.yaml, .mcap, .db3)
};

/// @brief What reading a bag did with its messages (counts; a file has none of this).
struct RecordingReport {
  std::string pose_source;                  ///< "odometry TOPIC" or "tf WORLD -> BASE"
  std::vector<std::string> topics;          ///< the sensor topics read
  std::uint64_t messages = 0;               ///< messages read, all topics
  std::uint64_t clouds = 0;                 ///< clouds and depth images on the sensor topics
  std::uint64_t scans = 0;                  ///< of them turned into rays
  std::uint64_t scans_no_pose = 0;          ///< left out: no pose covered them
  std::uint64_t clouds_skipped = 0;         ///< did not decode (warnings() says why)
  std::uint64_t rate_limited = 0;           ///< skipped by max_rate_hz
  std::uint64_t images_no_camera_info = 0;  ///< depth images before their first CameraInfo
};

/// @brief One point cloud (or depth image) of a bag as its sensor took it: the points in the
/// sensor's frame with the sensor's poses in the world. Plain value type.
struct RecordedCloud {
  std::string topic;          ///< the sensor's topic
  std::string frame_id;       ///< header.frame_id: the sensor's frame
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds since the epoch of the bag's clock
  /// The points that `raymap populate` maps (returns; for a depth image with invalid_as_free,
  /// the free-space points too, no_return set), sensor frame, metres; time_s is the point's
  /// time in seconds after stamp_ns. Points without a return, with a time out of range or
  /// without a pose are left out (counted in the report).
  std::vector<SensorPoint> points;
  /// The sensor's pose in the world (the base's pose from the odometry or TF, composed with
  /// sensor_to_base) at each distinct point time, times in seconds after stamp_ns, increasing:
  /// the poses populate makes this cloud's rays with. Mapper::integrate(points, sensor_poses)
  /// deskews with them.
  std::vector<TimedPose> sensor_poses;
  /// The sensor in the base frame (from /tf_static or BagOptions::sensor_offset).
  Eigen::Isometry3d sensor_to_base = Eigen::Isometry3d::Identity();
};

/// @brief Reads a recording scan by scan as world rays (what `raymap populate` maps).
/// Thread-safety: one thread. Not real-time (file I/O).
class RecordingReader {
 public:
  /// @brief Opens `path`: a bag, else a PLY (ray cloud, or point cloud with
  /// options.trajectory_path). Errors name the file and the reason (a bag's missing topic names
  /// the bag's topics of the right type).
  static Result<RecordingReader> open(const std::string& path,
                                      const RecordingOptions& options = {});
  RecordingReader(RecordingReader&&) noexcept;
  RecordingReader& operator=(RecordingReader&&) noexcept;
  ~RecordingReader();

  /// @brief Reads the next scan (rays with one scan number: a lidar revolution, a depth image)
  /// into `scan`, replacing what it held. @return false once the recording is exhausted (then
  /// `scan` is empty); an error names the file and what is wrong.
  Result<bool> nextScan(std::vector<WorldRay>& scan);
  /// @brief Reads a bag's next cloud (or depth image) into `cloud`, in its sensor's frame with
  /// the sensor's poses, counted in report() as nextScan() counts its scans. A reader reads
  /// scans or clouds, not both. @return false once the bag is exhausted; kUnsupported for a
  /// file (its rays are in the world frame already: nextScan()), kInvalidArgument after
  /// nextScan(); else an error naming the file and what is wrong.
  Result<bool> nextCloud(RecordedCloud& cloud);
  /// Fraction of the recording read so far, 0…1.
  double progress() const noexcept;
  /// True for a bag.
  bool isBag() const noexcept;
  /// @brief A bag's counts so far (complete once nextScan() returned false); zero for a file.
  RecordingReport report() const;
  /// @brief Notes about what was read: a PLY without intensity, a bag's skipped messages or
  /// damage, which pose source `auto` chose.
  std::vector<std::string> warnings() const;

 private:
  struct State;
  explicit RecordingReader(std::unique_ptr<State> state) noexcept;
  std::unique_ptr<State> state_;
};

}  // namespace raymap
