// SPDX-License-Identifier: BSD-3-Clause
// The counters and histograms the pipeline threads keep, read by the diagnostics reporter.
#pragma once

#include <atomic>
#include <cstdint>

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

/// @brief Everything the pipeline counts. Each group has one writer thread (named); any thread
/// reads. @rt writes are wait-free and allocate nothing.
struct PipelineStats {
  // ---- ingest thread ----
  Counter clouds_received;       ///< PointCloud2 messages taken from DDS
  Counter clouds_malformed;      ///< rejected by the decoder (last_cloud_error says why)
  Counter clouds_too_large;      ///< more points than the sensor's max_points
  Counter clouds_unknown_frame;  ///< frame_id matches no configured sensor frame
  Counter points_received;       ///< points in accepted clouds
  std::atomic<std::uint32_t> last_cloud_error{0};  ///< dds::CloudError + 1; 0 = none yet
  Counter poses_received;                          ///< odometry messages / TF transforms used
  Counter poses_malformed;                         ///< rejected by the decoder
  Counter poses_dropped;  ///< pose queue full (the integrator is far behind)
  Counter tf_ignored;     ///< TF transforms between frames the service does not use
  // ---- integrator thread ----
  Counter scans_integrated;    ///< scans whose every ray went into the map
  Counter scans_no_pose;       ///< dropped: no pose covered the scan in time
  Counter points_no_return;    ///< non-finite points (no direction: counted, not integrated)
  Counter rays_integrated;     ///< rays handed to the backend
  Counter rays_rejected;       ///< invalid, too short, out of bounds or outside the window
  Counter batches;             ///< backend calls
  Counter integrate_errors;    ///< backend calls that failed
  Counter poses_out_of_order;  ///< pose stamps not after the previous one (ignored)
  // ---- publisher thread ----
  Counter maps_published;
  Counter cycles_late;       ///< generation did not finish by the publish instant
  Counter heightmap_errors;  ///< generation failed (nothing published that cycle)
  /// header.stamp of the newest scan in the map (the pose source's clock; written by the
  /// integrator under the map lock, read by the publisher under it).
  std::atomic<std::int64_t> newest_scan_stamp_ns{0};
  DurationHistogram latency_us;          ///< cloud arrival -> first GridMap containing it
  DurationHistogram period_error_us;     ///< |publish period - nominal period|
  DurationHistogram generate_us;         ///< window move + height-map generation
  DurationHistogram integrate_batch_us;  ///< one backend call (written by the integrator)
};

}  // namespace raymap::pipeline
