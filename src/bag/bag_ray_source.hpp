// SPDX-License-Identifier: BSD-3-Clause
// Rays from a rosbag2 recording: PointCloud2 scans deskewed with poses from nav_msgs/Odometry or
// TF, the sensors' extrinsics from /tf_static, exactly as raymapd would have mapped them live.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/bag/bag_reader.hpp"
#include "src/io/ray_source.hpp"
#include "src/io/trajectory.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/point_cloud.hpp"

namespace raymap::bag {

/// @brief Which messages of a bag make the rays, and how (raymapd's configuration keys in
/// brackets: the defaults are the same).
struct BagRaysOptions {
  enum class PoseSource : std::uint8_t { kAuto, kOdometry, kTf };

  /// PointCloud2 or depth Image topics, one sensor each; empty: the bag's only PointCloud2
  /// topic (or, without one, its only Image topic).
  std::vector<std::string> cloud_topics;
  /// The sensor_msgs/msg/CameraInfo topic of each Image topic, in the order of the Image topics
  /// in cloud_topics; missing ones default to the image topic's namespace plus "camera_info"
  /// (/camera/depth/image_rect_raw -> /camera/depth/camera_info).
  std::vector<std::string> camera_info_topics;
  /// Depth images: down-sampling, the minimum range of a block's depth, the length of free rays
  /// for invalid pixels (max_range_m, needed by invalid_as_free), as raymapd's sensors[] keys.
  msgs::DepthDecodeOptions depth;
  /// Messages of a sensor faster than this (by header stamp) are skipped and counted; 0 = all.
  double max_rate_hz = 0.0;
  /// kAuto: the Odometry topic when `pose_topic` is given or the bag has exactly one, else TF
  /// when the bag has /tf; with one Odometry topic and /tf, the one that has messages
  /// (Odometry when both have).
  PoseSource pose_source = PoseSource::kAuto;
  std::string pose_topic;                ///< nav_msgs/msg/Odometry topic (pose.topic)
  std::string world_frame = "odom";      ///< TF poses: the chain's top (pose.world_frame)
  std::string base_frame = "base_link";  ///< the robot's body (pose.base_frame)
  /// Sensor in base_frame when /tf_static has no chain from base_frame to the cloud's frame.
  io::Pose extrinsic;
  /// `extrinsic` was given (bag.sensor_offset): without it, a cloud in a frame other than
  /// base_frame that /tf_static does not connect to it is an error, never mapped as if the
  /// sensor sat at the base's origin.
  bool extrinsic_given = false;
  std::string time_field = "auto";        ///< per-point time: auto, a field name, or none
  float max_time_offset_s = 1.0f;         ///< points further from the stamp are left out, counted
  std::int64_t pose_hold_ns = 20000000;   ///< newest pose used this far beyond it
  std::int64_t pose_wait_ns = 200000000;  ///< bag time a scan waits for its poses
  std::uint32_t pose_history = 4096;      ///< poses kept for interpolation
  std::uint32_t max_points = 1u << 24;    ///< larger clouds are skipped (counted)
  /// Read what a damaged or cut-off bag holds instead of failing (BagReadOptions).
  bool skip_damaged = false;
};

/// @brief What the reading did with the bag's messages.
struct BagRaysReport {
  std::string pose_source;  ///< "odometry TOPIC" or "tf WORLD -> BASE"
  std::string pose_note;    ///< bag.pose_source: auto, with Odometry and /tf: which, and why
  std::vector<std::string> cloud_topics;
  std::uint64_t messages = 0;               ///< messages read (all topics)
  std::uint64_t clouds = 0;                 ///< PointCloud2 or Image messages on the chosen topics
  std::uint64_t images_no_camera_info = 0;  ///< depth images before their first CameraInfo
  std::uint64_t camera_infos = 0;           ///< CameraInfo messages used
  std::uint64_t camera_infos_skipped = 0;   ///< CameraInfo messages refused (see `skips`)
  std::uint64_t rate_limited = 0;           ///< messages above max_rate_hz (skipped)
  std::uint64_t scans_integrated = 0;       ///< clouds turned into rays
  std::uint64_t scans_no_pose = 0;          ///< clouds no pose covered (as raymapd drops them)
  std::uint64_t clouds_skipped = 0;         ///< clouds that did not decode (see `skips`)
  std::uint64_t poses = 0;                  ///< odometry messages / TF transforms used
  std::uint64_t poses_skipped = 0;          ///< Odometry/TFMessage that did not decode
  std::uint64_t poses_out_of_order = 0;     ///< stamps not after the previous pose's (ignored)
  std::uint64_t points_no_return = 0;
  std::uint64_t points_bad_time = 0;
  std::uint64_t tf_ignored = 0;
  std::uint64_t tf_unresolved = 0;
  std::uint32_t extrinsics_from_tf = 0;
  /// The first skipped messages, each naming its topic, index and reason.
  std::vector<std::string> skips;
  /// Problems of the bag's files that lost nothing (a damaged summary: read in order).
  std::vector<std::string> read_warnings;
  /// skip_damaged: what was skipped as damaged or cut off (BagPass::damage).
  std::vector<std::string> damage;
  bool truncated = false;  ///< skip_damaged: a file was cut off (read up to its last message)
};

/// @brief One cloud (or depth image) of a sensor as recorded, in the sensor's frame, with the
/// sensor's poses in the world: what read() would have turned into one scan's rays.
struct SensorCloud {
  std::uint32_t sensor = 0;   ///< index into BagRaysReport::cloud_topics
  std::string frame_id;       ///< header.frame_id
  std::int64_t stamp_ns = 0;  ///< header.stamp
  /// The points that become rays (a return, or a free-only point of a depth image), sensor
  /// frame, metres; time_s is the point's time relative to stamp_ns.
  std::vector<msgs::ScanPoint> points;
  /// Each point's time, nanoseconds relative to stamp_ns (its time_s rounded as the deskewer
  /// rounds it).
  std::vector<std::int64_t> point_offsets_ns;
  /// The sensor's pose in the world at each distinct point time (increasing, nanoseconds
  /// relative to stamp_ns): the poses the rays are made with (the base's pose from the
  /// odometry or TF history, composed with `extrinsic`).
  std::vector<std::int64_t> pose_offsets_ns;
  std::vector<io::Pose> poses;
  io::Pose extrinsic;  ///< the sensor in base_frame
};

/// @brief A RaySource over a bag (rays in recording order, one scan per cloud).
class BagRaySource : public io::RaySource {
 public:
  /// @brief What the rays were made of, once read() has returned 0.
  virtual const BagRaysReport& report() const noexcept = 0;
  /// @brief Reads the next cloud whose poses are known into `cloud` (its buffers reused),
  /// counted in report() as read() counts it; points without a return, with an unusable time
  /// or without a pose are left out (counted). A source is read either with read() or with
  /// this. @return false at the end of the bag.
  virtual Result<bool> nextCloud(SensorCloud& cloud) = 0;
};

/// @brief Opens `path` (see openBag) and checks the chosen topics and their types.
/// Errors: a topic that is missing or of another type (naming the bag's topics of the right
/// type), no pose source, an unknown time field value.
Result<std::unique_ptr<BagRaySource>> openBagRaySource(const std::string& path,
                                                       const BagRaysOptions& options);

}  // namespace raymap::bag
