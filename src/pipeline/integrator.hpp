// SPDX-License-Identifier: BSD-3-Clause
// The integrator (the pipeline's scheduler): takes decoded scans, deskews them into world-frame
// rays with interpolated poses, forms batches by size or deadline and feeds the backend.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "platform/clock.hpp"
#include "platform/pi_mutex.hpp"
#include "src/map/backend.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_history.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "src/pipeline/scan_order.hpp"

namespace raymap::pipeline {

/// @brief Fixed settings of the integrator (from the configuration).
struct IntegratorSettings {
  std::uint32_t batch_rays = 16384;          ///< rays per backend call
  std::int64_t batch_deadline_ns = 5000000;  ///< a partial batch waits at most this long
  std::int64_t pose_wait_ns = 200000000;     ///< a scan waits this long for poses
  std::int64_t pose_hold_ns = 20000000;      ///< newest pose used this far beyond it
  std::uint32_t pose_history = 4096;
  /// The integrator gives the map lock up after this long (between slices of a batch) so that a
  /// waiting publisher takes it (the PI mutex hands it to the waiter). Per-scan semantics cannot
  /// split a scan: there a hold is one whole scan.
  std::int64_t max_lock_hold_ns = 5000000;
  /// Latency bound (load shedding): a scan is taken whole, subsampled or dropped so that the
  /// first map containing it is published within this long of its arrival (0 = no bound).
  std::int64_t max_latency_ns = 250000000;
  std::int64_t publish_period_ns = 200000000;  ///< the publisher's period (for the bound)
  /// Subsample by at most this factor; a scan that would need more is dropped. 1 = never
  /// subsample: whole scans are dropped (queues.shed: drop).
  std::uint32_t max_stride = 8;
  /// Planning ahead (subsampling or dropping a scan that is predicted to miss the bound) applies
  /// always, not only while the integrator is saturated (queues.shed_when). The deadline itself
  /// holds either way.
  bool shed_always = false;
  /// A pose stamped this much before the newest is a clock that went back (a bag played in a
  /// loop, simulation time reset), not a late pose: the pose history and the deskewing start
  /// over from it (pose.time_reset_s). Later-than-this late poses are ignored as out of order.
  std::int64_t time_reset_ns = 1000000000;
  /// A pose further than this (metres) from the one before is a jump (relocalisation, an
  /// odometry reset): counted, the pose history starts over from it, and with clear_on_jump the
  /// rolling window is emptied (pose.max_jump_m, pose.on_jump). 0 = off.
  double max_pose_jump_m = 0.0;
  bool clear_on_jump = false;
  /// The clock (monotonic ns) the integrator reads; tests give it one whose time they control.
  std::int64_t (*clock_ns)() noexcept = &platform::monotonicNowNs;
};

/// @brief Per-sensor settings: extrinsic (until tf_static replaces it) and ray limits.
struct SensorSettings {
  io::Pose extrinsic;  ///< sensor in the base frame
  RayFilter filter;    ///< min/max range
  /// A point whose time is further than this from the header stamp (or not finite) is left out
  /// and counted (points_bad_time): one corrupt time must not make the scan wait for poses that
  /// never come, and so cost the whole scan.
  float max_time_offset_s = 1.0f;
};

/// @brief Moves scans from the mailbox into the map.
///
/// Design: runs on one thread (the integrator). Poses arrive through `poses` (SPSC, from the
/// ingest thread) into a PoseHistory it owns. A scan is taken from the mailbox once poses cover
/// its last point (or dropped after pose_wait_ns), converted point by point into world-frame rays
/// (the pose interpolated at each distinct point time: deskewing), and the rays go into a batch.
/// A batch is integrated when full, at the end of a scan under per-scan semantics, or when no
/// scan waits and its oldest ray is batch_deadline_ns old. A batch goes in as slices, each
/// prepared and integrated under `map_mutex` (shared with the publisher, which moves the window
/// and reads the map); the lock is given up once it has been held max_lock_hold_ns, so the
/// publisher waits at most about that long (plus one slice), whatever the batch size. Slices are
/// sized from the measured time per ray to fit the hold. Before a scan is converted, the latency
/// bound (load_shedding.hpp) decides whether it goes in whole, subsampled or not at all, and
/// points whose time is corrupt are left out. Its points are then visited coarse to fine
/// (ScanOrder) until the scan's deadline, the generation of the last map within the bound: a
/// scan that would miss it is cut short there, and what went in is still spread over the whole
/// scan. Batches are sized so that rays of a scan whose deadline is near go in before it. Arrival
/// times of scans whose last ray went into the map go to `integrated` (for the latency measure).
///
/// Thread-safety: one thread. @rt step(): allocates: no; blocks: on map_mutex only.
class Integrator {
 public:
  /// Allocates the batch buffers (start-up). @pre every argument outlives the integrator.
  Integrator(VoxelMap& map, Backend& backend, platform::PiMutex& map_mutex, ScanMailbox& mailbox,
             PoseQueue& poses, ArrivalQueue& integrated, LatestPosition& latest,
             const IntegratorSettings& settings, std::vector<SensorSettings> sensors,
             PipelineStats& stats);

  /// @brief Does the work that is due at `now_ns` (monotonic).
  /// @return the monotonic time at which it wants to run again even without a new scan (a batch
  /// deadline or a pose wait), or INT64_MAX when only a new scan or pose can give it work.
  std::int64_t step(std::int64_t now_ns) noexcept;
  /// @brief Integrates whatever the batch holds (shutdown).
  void flush(std::int64_t now_ns) noexcept;

  /// @brief The pose history (integrator thread only; other threads read LatestPosition).
  const PoseHistory& poses() const noexcept { return history_; }

 private:
  std::int64_t step_(std::int64_t now_ns) noexcept;  // step() without the load accounting
  // The steps of step_() for one scan, in order.
  /// Takes the next scan from the mailbox and finds the span of its point times. False: none.
  bool takeScan() noexcept;
  /// Gives the current scan back, counted in `reason`.
  void dropScan(Counter& reason) noexcept;
  enum class PoseCheck : std::uint8_t { kCovered, kDropped, kWaiting };
  /// Whether poses cover the scan; kWaiting sets `*wake_ns` (and may integrate earlier scans'
  /// batch meanwhile), kDropped gave the scan back (no pose in time).
  PoseCheck checkPoses(std::int64_t now_ns, std::int64_t* wake_ns) noexcept;
  /// The latency bound's decision: the stride and the deadline of the scan's rays. False: the
  /// scan was shed whole (given back).
  bool planIntake(std::int64_t now_ns, std::int64_t* deadline, std::uint32_t* stride) noexcept;
  /// Converts the scan into the batch, integrating full or due batches on the way. @return true
  /// when the scan was cut short (its deadline, or one backend call per scan)
  bool convertBefore(std::int64_t now_ns, std::int64_t deadline) noexcept;
  /// Counts the scan's outcome, gives it back and integrates the batch when it is due.
  void finishScan(std::int64_t now_ns, std::int64_t deadline, bool cut_short,
                  std::int64_t scan_started) noexcept;
  void drainPoses() noexcept;
  /// A base pose that went back in time or jumped: the history starts over (and with
  /// clear_on_jump the window is emptied). @return whether `update` began a new history.
  bool startsOver(const PoseUpdate& update) noexcept;
  /// Converts points of the current scan into the batch until it is done, the batch is full or
  /// `max_visits` points have been visited. @return true when the scan is finished.
  bool convertScan(std::uint64_t max_visits) noexcept;
  void integrateBatch(std::int64_t now_ns) noexcept;
  /// Counts the scans the batch finished as integrated (with `rays_in` and the rays of their
  /// earlier batches) or empty (none), and stamps the staleness rule's time.
  void countCompletedScans(std::uint64_t rays_in) noexcept;
  /// Adds the preparer's rejections between two readings to the pipeline's counters.
  void countRejections(const RayCounters& before, const RayCounters& now) noexcept;
  /// How many more points can be converted (and, with the batch, integrated) before `deadline`
  /// at the measured cost; UINT64_MAX for kNoDeadline.
  std::uint64_t visitsBefore(std::int64_t deadline) const noexcept;
  /// When the partial batch must go in: at once when a scan in it has a deadline, else
  /// batch_deadline_ns after its first scan arrived.
  std::int64_t batchDue(std::int64_t now_ns) const noexcept;
  /// At the end of each load window (`load`: its busy share): the stride the points offered
  /// over it need (the ray budget).
  void updateRayBudget(double load) noexcept;
  /// Adds the time since busy_since_ns_ to the load window, and closes the window once it is a
  /// second long (load, overload flag, ray budget).
  void accountLoad(std::int64_t now_ns) noexcept;

  VoxelMap& map_;
  platform::PiMutex& map_mutex_;
  ScanMailbox& mailbox_;
  PoseQueue& pose_queue_;
  ArrivalQueue& integrated_;
  LatestPosition& latest_;
  IntegratorSettings settings_;
  std::vector<SensorSettings> sensors_;
  std::vector<RayPreparer> preparers_;  // one per sensor (its range limits)
  PipelineStats& stats_;
  PoseHistory history_;
  bool per_scan_ = false;

  // The scan being converted (taken from the mailbox), and where it is.
  ScanSlot* scan_ = nullptr;
  std::int64_t scan_first_wait_ns_ = 0;  // when it first waited for poses
  std::int64_t scan_start_ns_ = 0;       // time of its earliest and latest point
  std::int64_t scan_end_ns_ = 0;
  ScanOrder order_;         // which points, in which order (stride set by the latency bound)
  PointDeskewer deskewer_;  // caches the sensor's pose at the last point time

  // The batch: rays of possibly several scans, all from one sensor (range limits differ), in
  // the batcher's staging room (RayBatcher::staging()): converted into it here without the map
  // lock, integrated from it in slices under the lock (RayBatcher::integrateStaged()), so the
  // rays are batched once. Set in the constructor, once batcher_ exists.
  std::span<Ray> rays_;
  // Or, where the backend deskews on the device (Backend::preparesOnDevice for the sensor's
  // filter), the batch's points as they came with the tables that deskew them
  // (kernels/common/deskew.h): a segment per conversion step, with the poses as they were then.
  bool points_mode_ = false;                  // this batch holds points_, not rays_
  std::vector<bool> sensor_on_device_;        // per sensor: its batches are points
  std::vector<rm_scan_point> points_;         // sized as rays_ where some sensor's are points
  std::vector<rm_pose_sample> pose_samples_;  // RM_DESKEW_MAX_POSE_SAMPLES
  std::size_t pose_samples_used_ = 0;
  std::vector<rm_deskew_segment> segments_;  // reserved for RM_DESKEW_MAX_SEGMENTS
  std::vector<std::uint64_t> segment_scans_;
  /// Starts a segment for the current scan's points converted next; false when the batch's
  /// tables are full.
  bool beginSegment() noexcept;
  /// Visits the current scan's points (convertScan()'s rules) and adds those `convert(point)`
  /// takes to the batch, up to `capacity`.
  template <class Convert>
  bool visitScan(std::uint32_t capacity, std::uint64_t max_visits, Convert&& convert) noexcept;
  /// Converts the current scan's points into points_ (see convertScan()).
  bool convertScanToPoints(std::uint64_t max_visits) noexcept;
  RayBatcher batcher_;  // prepares and integrates the batch (the one batching loop)
  std::uint32_t batch_size_ = 0;
  std::uint32_t batch_sensor_ = 0;
  std::int64_t batch_first_ns_ = 0;              // arrival of the first scan in the batch
  std::vector<std::int64_t> completed_;          // arrivals of scans whose last ray is in the batch
  std::vector<std::uint32_t> completed_sensor_;  // and their sensors (per-sensor counters)
  std::uint32_t completed_count_ = 0;
  /// Rays integrated since the last batch that finished a scan (decides whether the scans it
  /// finishes put anything in the map).
  std::uint64_t rays_since_scan_end_ = 0;
  std::int64_t scan_stamp_pending_ = 0;    // newest header stamp among the completed scans
  std::int64_t batch_due_ns_ = INT64_MAX;  // earliest deadline of the completed scans in the batch
  double ns_per_ray_ = 1000.0;             // measured (moving average): sizes the slices
  // How busy the integrator is (overload detection for the latency bound): time spent in step()
  // over windows of about a second.
  std::int64_t load_window_start_ns_ = 0;
  std::int64_t load_busy_ns_ = 0;
  std::int64_t busy_since_ns_ = 0;  // start of the busy time not yet accounted
  bool overloaded_ = false;
  // The ray budget: points offered over the load window (scans taken plus those the mailbox
  // dropped), and the stride every scan gets while they need more than the backend integrates.
  double window_points_taken_ = 0.0;
  double window_points_accepted_ = 0.0;  // of scans that went in (whole or in part)
  std::uint64_t window_scans_taken_ = 0;
  std::uint64_t window_dropped_before_ = 0;
  std::uint32_t budget_stride_ = 1;
  std::uint32_t scans_shed_in_a_row_ = 0;  // whole scans the latency bound dropped in a row
  double scan_ns_per_point_ = 0.0;         // measured per scan, conversion included (0: not yet)
};

}  // namespace raymap::pipeline
