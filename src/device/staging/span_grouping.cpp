// SPDX-License-Identifier: BSD-3-Clause
// Counting sort of a batch's span records by device slot.
#include "src/device/staging/span_grouping.hpp"

#include <algorithm>
#include <numeric>

#include "raymap/assert.hpp"

namespace raymap::gpu {

RegionSpanGrouper::RegionSpanGrouper(std::uint32_t slots) : run_of_slot_(slots, 0) {}

void RegionSpanGrouper::reserve(BatchArrays& arrays, const BatchLimits& limits) {
  // A batch touches at most one region per span and never more regions than there are slots.
  const std::size_t runs = std::min<std::size_t>(limits.max_spans, run_of_slot_.size());
  arrays.region_spans.reserve(limits.max_spans);
  arrays.span_runs.reserve(runs);
  for (std::vector<std::uint32_t>* list : {&run_slot_, &run_count_, &order_, &cursor_}) {
    list->reserve(runs);
  }
}

void RegionSpanGrouper::group(BatchArrays& arrays) noexcept {
  run_slot_.clear();
  run_count_.clear();
  for (const rm_span_record& span : arrays.spans) {
    RAYMAP_DEBUG_ASSERT(span.slot < run_of_slot_.size());
    std::uint32_t& run = run_of_slot_[span.slot];
    if (run == 0) {
      run_slot_.push_back(span.slot);
      run_count_.push_back(0);
      run = static_cast<std::uint32_t>(run_slot_.size());
    }
    ++run_count_[run - 1];
  }
  const auto runs = static_cast<std::uint32_t>(run_slot_.size());
  order_.resize(runs);
  std::iota(order_.begin(), order_.end(), 0u);
  // Ties in first-appearance order: the same batch always gives the same launch.
  std::sort(order_.begin(), order_.end(), [this](std::uint32_t a, std::uint32_t b) {
    return run_count_[a] != run_count_[b] ? run_count_[a] > run_count_[b] : a < b;
  });
  arrays.span_runs.resize(runs);
  cursor_.resize(runs);
  std::uint32_t first = 0;
  for (std::uint32_t k = 0; k < runs; ++k) {
    const std::uint32_t r = order_[k];
    arrays.span_runs[k] = rm_span_run{first, run_count_[r]};
    cursor_[r] = first;
    first += run_count_[r];
  }
  arrays.region_spans.resize(arrays.spans.size());
  for (const rm_span_record& span : arrays.spans) {
    arrays.region_spans[cursor_[run_of_slot_[span.slot] - 1]++] = span;
  }
  for (const std::uint32_t slot : run_slot_) {
    run_of_slot_[slot] = 0;
  }
}

}  // namespace raymap::gpu
