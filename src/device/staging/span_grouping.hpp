// SPDX-License-Identifier: BSD-3-Clause
// Span records grouped by region, for span kernels that give each region to one work-item
// (RM_REGION_OWNED, kernels/device/device.h).
#pragma once

#include <cstdint>
#include <vector>

#include "src/device/staging/batch_plan.hpp"

namespace raymap::gpu {

/// @brief Groups a planned batch's span records by region: a counting sort on the device slot,
/// stable, so each region's spans stay in ray order (the order the CPU backend updates a voxel
/// in). Writes BatchArrays::region_spans and one rm_span_run per region, the regions with the
/// most spans first: a device runs work-items roughly in launch order, so the longest runs start
/// first and the short ones fill in behind them.
///
/// Thread-safety: none (one per backend, used by the planning thread). Real-time: allocation-free
/// once reserve() has been called for the limits.
class RegionSpanGrouper {
 public:
  /// `slots`: device slots a span record may name (the layer buffers' regions).
  explicit RegionSpanGrouper(std::uint32_t slots);

  /// @brief Reserves `arrays`' grouped lists and this grouper's scratch for `limits`. Throws
  /// std::bad_alloc.
  void reserve(BatchArrays& arrays, const BatchLimits& limits);

  /// @brief Fills arrays.region_spans and arrays.span_runs from arrays.spans.
  void group(BatchArrays& arrays) noexcept;

 private:
  std::vector<std::uint32_t> run_of_slot_;  // per slot: 1 + its run while grouping, else 0
  std::vector<std::uint32_t> run_slot_;     // per run, in order of first appearance: its slot
  std::vector<std::uint32_t> run_count_;    // per run, same order: its spans
  std::vector<std::uint32_t> order_;        // runs by descending count
  std::vector<std::uint32_t> cursor_;       // per run (first-appearance order): next place
};

}  // namespace raymap::gpu
