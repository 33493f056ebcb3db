// SPDX-License-Identifier: BSD-3-Clause
// TransformTable: a small TF tree of static edges (see the header).
#include "src/pipeline/transform_table.hpp"

#include <cstring>

namespace raymap::pipeline {
namespace {

/// Copies a NUL-terminated name that fits (with its NUL) into `out`; false when it does not.
bool copyName(const char* name, char (&out)[TransformTable::kFrameChars]) noexcept {
  const std::size_t length = std::strlen(name);
  if (length >= TransformTable::kFrameChars) {
    return false;
  }
  std::memcpy(out, name, length + 1);
  return true;
}

}  // namespace

std::uint32_t TransformTable::indexOf(const char* child) const noexcept {
  for (std::uint32_t i = 0; i < size_; ++i) {
    if (std::strcmp(edges_[i].child, child) == 0) {
      return i;
    }
  }
  return size_;
}

bool TransformTable::set(const char* parent, const char* child,
                         const io::Pose& child_in_parent) noexcept {
  const std::uint32_t i = indexOf(child);
  if (i == size_ && size_ == kMaxEdges) {
    return false;
  }
  Edge candidate{};
  if (!copyName(parent, candidate.parent) || !copyName(child, candidate.child)) {
    return false;
  }
  candidate.child_in_parent = child_in_parent;
  edges_[i] = candidate;
  size_ += i == size_ ? 1u : 0u;
  return true;
}

const char* TransformTable::parentOf(const char* child) const noexcept {
  const std::uint32_t i = indexOf(child);
  return i == size_ ? nullptr : edges_[i].parent;
}

bool TransformTable::resolve(const char* ancestor, const char* frame, io::Pose* frame_in_ancestor,
                             const TransformTable* other) const noexcept {
  // Walk up from `frame`: pose = parent_k ∘ ... ∘ parent_1 ∘ edge(frame).
  io::Pose pose;  // identity
  const char* at = frame;
  for (std::uint32_t depth = 0; depth <= kMaxChain; ++depth) {
    if (std::strcmp(at, ancestor) == 0) {
      *frame_in_ancestor = pose;
      return true;
    }
    const TransformTable* table = this;
    std::uint32_t i = indexOf(at);
    if (i == size_ && other != nullptr) {
      table = other;
      i = other->indexOf(at);
    }
    if (i == table->size_) {
      return false;
    }
    pose = io::compose(table->edges_[i].child_in_parent, pose);
    at = table->edges_[i].parent;
  }
  return false;  // a loop, or a chain deeper than any robot's
}

}  // namespace raymap::pipeline
