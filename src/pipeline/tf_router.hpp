// SPDX-License-Identifier: BSD-3-Clause
// TF as robots publish it, turned into the pipeline's pose updates: /tf_static edges kept in any
// order, chains composed, the base's pose from the lowest moving edge of world -> ... -> base,
// and each sensor's extrinsic from base -> ... -> sensor (static, or on a moving mount). Used by
// raymapd's ingest thread and by the offline readers of bags, so both build the same map.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "src/msgs/pose.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/transform_table.hpp"

namespace raymap::pipeline {

/// @brief The transform's pose (child in parent).
inline io::Pose poseOf(const msgs::StampedTransform& t) noexcept {
  // The wire struct stays plain (tx..qz); Eigen's quaternion takes (w, x, y, z).
  return io::Pose{{t.tx, t.ty, t.tz}, {t.qw, t.qx, t.qy, t.qz}};
}

/// @brief An Odometry message's pose as the base's pose in the world at its stamp.
inline PoseUpdate baseInWorld(const msgs::StampedTransform& odometry) noexcept {
  PoseUpdate update;
  update.stamp_ns = odometry.stamp_ns;
  update.pose = poseOf(odometry);
  update.kind = PoseUpdate::kBaseInWorld;
  return update;
}

/// @brief Where a TfRouter's pose updates go (raymapd: the SPSC queue to the integrator).
class PoseSink {
 public:
  /// @return false when the update could not be taken (counted as poses_dropped).
  virtual bool push(const PoseUpdate& update) noexcept = 0;

 protected:
  ~PoseSink() = default;
};

/// @brief Routes TF transforms and sensor frames to base poses and sensor extrinsics.
///
/// Counts into `stats`: poses_received (transforms used), poses_dropped (sink full), tf_ignored
/// (edges nothing uses, or a full table), tf_unresolved (an edge needed above has not come
/// yet), tf_static_edges and extrinsics_from_tf.
///
/// Thread-safety: one thread (raymapd's ingest thread). @rt allocates: no (after construction);
/// O(TransformTable::kMaxEdges × chain length) per transform.
class TfRouter {
 public:
  /// @param configured_frames per sensor: its configured frame, or "" to learn it from the
  /// sensor's first cloud.
  TfRouter(std::string world_frame, std::string base_frame,
           const std::vector<std::string>& configured_frames, PipelineStats& stats);

  /// @brief The frame sensor `s`'s clouds are in: configured, or learned from its first cloud
  /// ("" until then).
  const char* sensorFrame(std::uint32_t s) const noexcept;
  /// @brief Sensor `s`'s first cloud came in `frame` (its frame was not configured): remembered,
  /// and /tf_static heard before now applies. Later calls do nothing.
  void learnSensorFrame(std::uint32_t s, const char* frame, PoseSink& sink) noexcept;
  /// @brief The transforms of one TFMessage from /tf (`is_static` false) or /tf_static.
  void onTransforms(std::span<const msgs::StampedTransform> transforms, bool is_static,
                    PoseSink& sink) noexcept;

 private:
  /// Pushes the extrinsic of every sensor whose frame is known and whose chain from base_frame
  /// now resolves to a pose it has not pushed yet.
  void resolveExtrinsics(PoseSink& sink) noexcept;
  /// Pushes sensor `s`'s extrinsic resolved from TF, and remembers it. @return false when the
  /// sink was full (counted).
  bool pushExtrinsic(std::uint32_t s, const io::Pose& pose, PoseSink& sink) noexcept;
  /// The parent of `frame` in /tf_static, else in /tf as last heard; nullptr when neither has it.
  const char* parentFrame(const char* frame) const noexcept;
  /// The frame whose /tf edge to its parent moves the base: base_frame, or the first frame above
  /// it with no static edge.
  const char* baseChainDriver() const noexcept;
  /// True when `frame` lies on the chain from base_frame up to world_frame (as far as known).
  bool isBaseAncestor(const char* frame) const noexcept;
  /// True when the edge whose child is `edge_child` lies on the chain from `sensor_frame` up to
  /// base_frame (as far as known): the sensor moves with it.
  bool isOnSensorChain(const char* edge_child, const char* sensor_frame) const noexcept;

  std::string world_frame_;
  std::string base_frame_;
  std::vector<std::string> configured_frames_;
  std::vector<char> learned_frames_;  // per sensor: frame seen first (kFrameChars each)
  PipelineStats& stats_;
  TransformTable static_tf_;                 // /tf_static as it arrived, in any order
  TransformTable tf_latest_;                 // /tf's latest edge per child
  std::vector<io::Pose> extrinsic_from_tf_;  // per sensor: the extrinsic last pushed
  std::vector<std::uint8_t> extrinsic_resolved_;
};

}  // namespace raymap::pipeline
