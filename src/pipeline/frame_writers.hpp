// SPDX-License-Identifier: BSD-3-Clause
// The writers that published one frame's transform recently: two of them for the robot's base
// are two pose sources, which /tf's many legitimate publishers would hide in a writer count.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace raymap::pipeline {

/// @brief Distinct writers (DDS publication handles) of one frame's transform seen within a
/// recent window. /tf has many writers by design (each node its own frames), so a second pose
/// source shows only per frame: two writers of base_link's transform within a second.
/// Thread-safety: seen() from one thread (ingest), writers() from any (diagnostics); relaxed
/// atomics: a count a report late or early is fine. @rt wait-free; allocates: no.
class FrameWriters {
 public:
  static constexpr std::size_t kSlots = 4;  ///< writers told apart (more count as 4)

  /// @brief `writer` (nonzero) published the frame at `now_ns` (monotonic).
  void seen(std::uint64_t writer, std::int64_t now_ns) noexcept;

  /// @brief Writers seen within `window_ns` before `now_ns`.
  std::uint32_t writers(std::int64_t now_ns, std::int64_t window_ns) const noexcept;

 private:
  struct Slot {
    std::atomic<std::uint64_t> writer{0};
    std::atomic<std::int64_t> last_ns{0};
  };
  std::array<Slot, kSlots> slots_{};
};

}  // namespace raymap::pipeline
