// SPDX-License-Identifier: BSD-3-Clause
// TfRouter: TF edges to base poses and sensor extrinsics (see the header).
#include "src/pipeline/tf_router.hpp"

#include <cstring>

namespace raymap::pipeline {

TfRouter::TfRouter(std::string world_frame, std::string base_frame,
                   const std::vector<std::string>& configured_frames, PipelineStats& stats)
    : world_frame_(std::move(world_frame)),
      base_frame_(std::move(base_frame)),
      configured_frames_(configured_frames),
      learned_frames_(configured_frames.size() * TransformTable::kFrameChars, '\0'),
      stats_(stats),
      extrinsic_from_tf_(configured_frames.size()),
      extrinsic_resolved_(configured_frames.size(), 0) {}

const char* TfRouter::sensorFrame(std::uint32_t s) const noexcept {
  return configured_frames_[s].empty()
             ? &learned_frames_[std::size_t{s} * TransformTable::kFrameChars]
             : configured_frames_[s].c_str();
}

void TfRouter::learnSensorFrame(std::uint32_t s, const char* frame, PoseSink& sink) noexcept {
  char* learned = &learned_frames_[std::size_t{s} * TransformTable::kFrameChars];
  if (!configured_frames_[s].empty() || learned[0] != '\0') {
    return;
  }
  std::strncpy(learned, frame, TransformTable::kFrameChars - 1);
  // /tf_static latched before this first cloud now applies.
  resolveExtrinsics(sink);
}

void TfRouter::resolveExtrinsics(PoseSink& sink) noexcept {
  const char* base = base_frame_.c_str();
  for (std::uint32_t s = 0; s < configured_frames_.size(); ++s) {
    const char* frame = sensorFrame(s);
    io::Pose pose;
    // A cloud in the base frame itself keeps the configured extrinsic.
    if (frame[0] == '\0' || std::strcmp(frame, base) == 0 ||
        !static_tf_.resolve(base, frame, &pose, &tf_latest_)) {
      continue;
    }
    const io::Pose& last = extrinsic_from_tf_[s];
    if (extrinsic_resolved_[s] != 0 && last.position == pose.position &&
        last.orientation.coeffs() == pose.orientation.coeffs()) {
      continue;  // unchanged (tf_static is republished as a whole)
    }
    (void)pushExtrinsic(s, pose, sink);
  }
}

bool TfRouter::pushExtrinsic(std::uint32_t s, const io::Pose& pose, PoseSink& sink) noexcept {
  PoseUpdate update;
  update.pose = pose;
  update.kind = PoseUpdate::kSensorExtrinsic;
  update.sensor = s;
  if (!sink.push(update)) {
    stats_.poses_dropped.add();
    return false;
  }
  extrinsic_from_tf_[s] = pose;
  extrinsic_resolved_[s] = 1;
  stats_.extrinsics_from_tf.fetch_add(1, std::memory_order_relaxed);
  return true;
}

const char* TfRouter::parentFrame(const char* frame) const noexcept {
  const char* parent = static_tf_.parentOf(frame);
  return parent != nullptr ? parent : tf_latest_.parentOf(frame);
}

const char* TfRouter::baseChainDriver() const noexcept {
  const char* at = base_frame_.c_str();
  for (std::uint32_t depth = 0; depth < TransformTable::kMaxChain; ++depth) {
    const char* parent = static_tf_.parentOf(at);
    if (parent == nullptr) {
      break;
    }
    at = parent;
  }
  return at;
}

bool TfRouter::isOnSensorChain(const char* edge_child, const char* sensor_frame) const noexcept {
  const char* at = sensor_frame;
  for (std::uint32_t depth = 0; depth < TransformTable::kMaxChain; ++depth) {
    if (std::strcmp(at, base_frame_.c_str()) == 0) {
      return false;
    }
    if (std::strcmp(at, edge_child) == 0) {
      return true;
    }
    const char* parent = parentFrame(at);
    if (parent == nullptr) {
      return false;
    }
    at = parent;
  }
  return false;
}

bool TfRouter::isBaseAncestor(const char* frame) const noexcept {
  const char* at = base_frame_.c_str();
  for (std::uint32_t depth = 0; depth < TransformTable::kMaxChain; ++depth) {
    const char* parent = parentFrame(at);
    if (parent == nullptr || std::strcmp(at, world_frame_.c_str()) == 0) {
      return false;
    }
    if (std::strcmp(parent, frame) == 0) {
      return std::strcmp(frame, world_frame_.c_str()) != 0;
    }
    at = parent;
  }
  return false;
}

void TfRouter::onTransforms(std::span<const msgs::StampedTransform> transforms, bool is_static,
                            PoseSink& sink) noexcept {
  for (const msgs::StampedTransform& t : transforms) {
    const io::Pose pose = poseOf(t);
    if (is_static) {
      // Every static edge is kept, whatever order they come in and whether or not a sensor's
      // frame is known yet: chains are resolved below and again at each sensor's first cloud.
      if (!static_tf_.set(t.parent, t.child, pose)) {
        stats_.tf_ignored.add();  // table full
      }
      stats_.poses_received.add();
      continue;
    }
    PoseUpdate update;
    update.stamp_ns = t.stamp_ns;
    update.pose = pose;
    bool used = false;
    const bool kept = tf_latest_.set(t.parent, t.child, pose);
    if (kept && std::strcmp(t.child, baseChainDriver()) == 0) {
      // The lowest moving edge of the chain world_frame -> ... -> base_frame (odom -> base_link
      // under map -> odom, say): the base's pose at this stamp, the other edges as last heard.
      used = true;
      if (!static_tf_.resolve(world_frame_.c_str(), base_frame_.c_str(), &update.pose,
                              &tf_latest_)) {
        stats_.tf_unresolved.add();  // an edge above it has not come yet
        continue;
      }
      update.kind = PoseUpdate::kBaseInWorld;
    } else if (kept && isBaseAncestor(t.child)) {
      stats_.poses_received.add();  // an edge higher up the base's chain: used from now on
      continue;
    } else if (kept) {
      // A sensor on a moving mount (a pan unit, an arm): an edge of the chain from base_frame to
      // a sensor's frame came on /tf. The sensors below it take the composed extrinsic.
      for (std::uint32_t s = 0; s < configured_frames_.size(); ++s) {
        const char* frame = sensorFrame(s);
        if (frame[0] == '\0' || !isOnSensorChain(t.child, frame)) {
          continue;
        }
        used = true;
        io::Pose extrinsic;
        if (!static_tf_.resolve(base_frame_.c_str(), frame, &extrinsic, &tf_latest_)) {
          stats_.tf_unresolved.add();  // an edge between it and base_frame has not come yet
          continue;
        }
        if (pushExtrinsic(s, extrinsic, sink)) {
          stats_.poses_received.add();
        }
      }
      if (!used) {
        stats_.tf_ignored.add();
      }
      continue;
    }
    if (!used) {
      stats_.tf_ignored.add();
      continue;
    }
    if (!sink.push(update)) {
      stats_.poses_dropped.add();
      continue;
    }
    stats_.poses_received.add();
  }
  if (is_static) {
    stats_.tf_static_edges.store(static_tf_.size(), std::memory_order_relaxed);
    resolveExtrinsics(sink);
  }
}

}  // namespace raymap::pipeline
