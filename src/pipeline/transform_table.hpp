// SPDX-License-Identifier: BSD-3-Clause
// The latest transform of each edge of a TF tree, kept whatever order they arrive in, so that a
// sensor's extrinsic or the base's pose can be resolved through a chain of frames.
#pragma once

#include <array>
#include <cstdint>

#include "src/io/trajectory.hpp"

namespace raymap::pipeline {

/// @brief A fixed table of TF edges (child frame -> its parent and the child's latest pose in
/// it): /tf_static's edges in one, /tf's latest in another. A TF tree gives each frame one
/// parent, so a later transform for the same child replaces the earlier one (tf2 does the same).
///
/// Thread-safety: one thread (the ingest thread). @rt allocates: no; O(kMaxEdges) per call.
class TransformTable {
 public:
  static constexpr std::uint32_t kMaxEdges = 256;
  static constexpr std::uint32_t kMaxChain = 32;  ///< longer chains are taken for loops
  static constexpr std::uint32_t kFrameChars = 64;

  /// @brief Records `child`'s pose in `parent`. @return false when the table is full (the edge
  /// is not kept; the caller counts it) or a frame name does not fit.
  bool set(const char* parent, const char* child, const io::Pose& child_in_parent) noexcept;

  /// @brief The pose of `frame` in `ancestor`, composed along the chain of parents from `frame`
  /// up to `ancestor`, each edge taken from this table or else from `other` (may be null).
  /// @return false when `frame` is not below `ancestor` in the tree. `frame` == `ancestor` gives
  /// the identity.
  bool resolve(const char* ancestor, const char* frame, io::Pose* frame_in_ancestor,
               const TransformTable* other = nullptr) const noexcept;
  /// @brief The parent of `child` in this table, or nullptr.
  const char* parentOf(const char* child) const noexcept;

  std::uint32_t size() const noexcept { return size_; }

 private:
  struct Edge {
    char parent[kFrameChars] = {};
    char child[kFrameChars] = {};
    io::Pose child_in_parent;
  };
  /// Index of the edge whose child is `child`, or size_.
  std::uint32_t indexOf(const char* child) const noexcept;

  std::array<Edge, kMaxEdges> edges_{};
  std::uint32_t size_ = 0;
};

}  // namespace raymap::pipeline
