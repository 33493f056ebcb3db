// SPDX-License-Identifier: BSD-3-Clause
// The counters and histograms the pipeline threads keep, read by the diagnostics reporter.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "src/msgs/camera_info.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/pipeline/histogram.hpp"

namespace raymap::pipeline {

/// A counter written by one thread and read by others (relaxed: values, not synchronisation).
class Counter {
 public:
  void add(std::uint64_t n = 1) noexcept {
    value_.store(value_.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
  }
  void set(std::uint64_t v) noexcept { value_.store(v, std::memory_order_relaxed); }
  std::uint64_t get() const noexcept { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> value_{0};
};

/// The most sensors the per-sensor counters hold (raymapd's configuration allows no more).
inline constexpr std::size_t kMaxSensors = 16;

/// @brief What happened to one sensor's messages (ingest thread, except scans_integrated).
struct SensorCounters {
  Counter received;  ///< clouds or depth images taken from DDS
  /// Clouds or images missing before those taken, by the gaps in their stamps (StampGaps): lost
  /// on the way (a socket buffer, the network) or never sent.
  Counter missing;
  Counter accepted;          ///< decoded and handed to the integrator
  Counter rate_limited;      ///< dropped: faster than sensors[].max_rate_hz
  Counter rejected;          ///< malformed, too large, wrong frame, or no CameraInfo yet
  Counter no_camera_info;    ///< depth images before any usable CameraInfo (within rejected)
  Counter camera_info;       ///< CameraInfo messages taken
  Counter camera_info_bad;   ///< CameraInfo refused (camera_info_rejected_by says why)
  Counter scans_integrated;  ///< in the map (integrator thread)
};

/// @brief Everything the pipeline counts. Each group has one writer thread (named); any thread
/// reads. @rt writes are wait-free and allocate nothing.
struct PipelineStats {
  // ---- ingest thread ----
  Counter clouds_received;  ///< PointCloud2 and depth Image messages taken from DDS
  /// Datagrams the kernel dropped on raymapd's sockets because their receive buffer was full
  /// (platform::UdpDrops; set by the diagnostics thread once a report).
  Counter socket_drops;
  /// Monotonic time the last of them was taken (0: none yet). Health compares it with
  /// last_scan_integrated_ns: input that stopped and input that is not integrated read the
  /// same in counts over a window that still holds the last clouds.
  std::atomic<std::int64_t> last_cloud_received_ns{0};
  Counter clouds_malformed;      ///< rejected by the decoder (clouds_rejected_by says why)
  Counter clouds_too_large;      ///< more points than the sensor's max_points
  Counter clouds_unknown_frame;  ///< frame_id is not the configured sensors[].frame
  /// Clouds the decoder rejected, per reason (indexed by msgs::CloudError; too_many_points is
  /// clouds_too_large, the others add up to clouds_malformed).
  std::array<Counter, msgs::kCloudErrorCount> clouds_rejected_by;
  /// The first frame_id that matched no configured frame, and the sensor it came for (written
  /// once by the ingest thread, then wrong_frame_seen is set with release).
  /// Depth images and CameraInfo messages the decoders rejected, per reason (indexed by
  /// msgs::DepthImageError and msgs::CameraInfoError); images also count in clouds_malformed (or
  /// clouds_too_large for too_many_points).
  std::array<Counter, msgs::kDepthImageErrorCount> images_rejected_by;
  std::array<Counter, msgs::kCameraInfoErrorCount> camera_info_rejected_by;
  /// Per configured sensor, by its index in sensors[].
  std::array<SensorCounters, kMaxSensors> sensors;
  char wrong_frame[64] = {};
  std::uint32_t wrong_frame_sensor = 0;
  std::atomic<bool> wrong_frame_seen{false};
  Counter points_received;  ///< points in accepted clouds
  /// Depth blocks that gave no point because something in them is nearer than the sensor's
  /// min range (within the accepted images; the health rule counts them as offered rays).
  Counter points_too_near;
  Counter poses_received;   ///< odometry messages / TF transforms used
  Counter poses_malformed;  ///< rejected by the decoder
  Counter poses_dropped;    ///< pose queue full (the integrator is far behind)
  Counter tf_ignored;       ///< TF transforms between frames the service does not use
  /// /tf transforms of the base's moving edge that could not be composed up to world_frame (an
  /// edge above it has not come yet): no pose for that stamp.
  Counter tf_unresolved;
  /// Static TF edges kept (/tf_static, any order), and sensor extrinsic updates resolved from
  /// TF (static chains, and moving mounts on /tf).
  std::atomic<std::uint32_t> tf_static_edges{0};
  std::atomic<std::uint32_t> extrinsics_from_tf{0};
  // ---- integrator thread ----
  /// Scans handed to the map in a batch that put at least one ray in it.
  Counter scans_integrated;
  /// Scans handed to the map in batches that put no ray in it (every ray rejected, or none to
  /// begin with): they keep nothing fresh, so they do not count as integrated for staleness.
  Counter scans_empty;
  Counter scans_no_pose;     ///< dropped: no pose covered the scan in time
  Counter points_no_return;  ///< non-finite points (no direction: counted, not integrated)
  /// Points whose per-point time is not finite or further than sensors[].max_time_offset_s from
  /// the header stamp (a corrupt time field): the point is left out, not the scan.
  Counter points_bad_time;
  /// Load shedding (queues.max_latency_s): scans dropped whole because no map within the bound
  /// could contain them, scans cut short at their deadline (what went in is spread over the
  /// whole scan), and the points left out of subsampled or cut-short scans.
  Counter scans_shed;
  Counter scans_cut_short;
  Counter points_shed;
  /// Share of the last second the integrator spent working, percent (above 90 the latency bound
  /// treats the input as more than the backend integrates).
  std::atomic<std::int32_t> integrator_load_percent{0};
  /// The ray budget: every scan is subsampled by this factor (1 = whole) while the points
  /// arriving over the last second need more than the backend integrates.
  std::atomic<std::int32_t> subsample_stride{1};
  /// Monotonic time the last scan put a ray into the map (0: none yet); the staleness rule.
  std::atomic<std::int64_t> last_scan_integrated_ns{0};
  Counter rays_integrated;  ///< rays handed to the backend
  Counter rays_rejected;    ///< invalid, too short, out of bounds or outside the window
  /// Of rays_rejected, by reason (the ray preparer's counters).
  Counter rays_invalid;         ///< NaN or infinite coordinates
  Counter rays_too_short;       ///< shorter than the sensor's min range
  Counter rays_out_of_bounds;   ///< beyond the map's key range or longer than the longest ray
  Counter rays_outside_window;  ///< entirely outside the rolling window
  Counter batches;              ///< backend calls
  Counter integrate_errors;     ///< backend calls that failed
  Counter poses_out_of_order;   ///< pose stamps not after the previous one (ignored)
  /// Pose stamps more than pose.time_reset_s before the newest: the clock went back (a looped
  /// bag, a simulation reset); the pose history started over.
  Counter pose_time_resets;
  /// Poses further than pose.max_jump_m from the one before (relocalisation, odometry reset):
  /// the history started over; window_clears of them also emptied the rolling window.
  Counter pose_jumps;
  Counter window_clears;
  /// How far the last jump went (millimetres) and how far back the last reset went (ms).
  std::atomic<std::int64_t> last_pose_jump_mm{0};
  std::atomic<std::int64_t> last_time_reset_ms{0};
  // ---- publisher thread ----
  Counter maps_published;
  Counter costmaps_published;  ///< nav_msgs/OccupancyGrid written (dds.costmap_topic)
  Counter maps_withheld;       ///< cycles with no map published: the map was stale (health)
  Counter cycles_late;         ///< generation did not finish by the publish instant
  Counter heightmap_errors;    ///< generation failed (nothing published that cycle)
  /// header.stamp of the newest scan in the map (the pose source's clock; written by the
  /// integrator under the map lock, read by the publisher under it).
  std::atomic<std::int64_t> newest_scan_stamp_ns{0};
  DurationHistogram latency_us;          ///< cloud arrival -> first GridMap containing it
  DurationHistogram period_error_us;     ///< |publish period - nominal period|
  DurationHistogram generate_us;         ///< window move + height-map generation
  DurationHistogram integrate_batch_us;  ///< one batch, all its slices (written by the integrator)
  /// Each continuous hold of the map lock by the integrator (one or more slices of a batch).
  DurationHistogram map_lock_hold_us;
  /// How long the publisher waited for the map lock each cycle (written by the publisher).
  DurationHistogram map_lock_wait_us;
  /// How long the publisher held the map lock each cycle: the device synchronise, the window
  /// move and the height-map generation (written by the publisher).
  DurationHistogram heightmap_lock_hold_us;
  /// Bytes each cycle's synchronise() downloaded from the device (map regions; 0 on the CPU).
  /// The histogram counts bytes where its name says microseconds.
  DurationHistogram sync_copy_bytes;
  /// Bytes of the map's layers each cycle's height-map generation copied to the device (regions
  /// uploaded; 0 on the CPU, and on a device whose backend holds the window).
  DurationHistogram heightmap_copy_bytes;
  /// All bytes each cycle's generation moved between host and device: the map's layers plus the
  /// region tables and the height map read back (0 on the CPU).
  DurationHistogram heightmap_transfer_bytes;
  /// The publisher's lead before each publish instant, microseconds (adapts; publisher writes).
  std::atomic<std::int64_t> publish_lead_us{0};
  /// The next publish instant (monotonic ns; 0 before the first), for the integrator's latency
  /// bound (written by the publisher).
  std::atomic<std::int64_t> next_publish_ns{0};
};

}  // namespace raymap::pipeline
