// SPDX-License-Identifier: BSD-3-Clause
// RayBatcher: see the header.
#include "src/map/ray_batcher.hpp"

#include <cstdio>
#include <string>

#include "raymap/assert.hpp"

namespace raymap {

RayBatcher::RayBatcher(const VoxelMap& map, Backend& backend, std::size_t batch_rays)
    : backend_(&backend), per_scan_(map.semantics() == Semantics::kPerScan) {
  RAYMAP_EXPECTS(batch_rays > 0);
  batch_.resize(batch_rays);
}

Expected<void, IntegrateError> RayBatcher::flush() noexcept {
  if (fill_ == 0) {
    return {};
  }
  const std::span<const PreparedRay> rays(batch_.data(), fill_);
  fill_ = 0;
  ++counters_.batches;
  auto ok = backend_->integrate(rays);
  if (!ok) {
    ++counters_.batches_failed;
    return ok;
  }
  counters_.rays_integrated += rays.size();
  return {};
}

Expected<void, IntegrateError> RayBatcher::add(RayPreparer& preparer,
                                               std::span<const Ray> rays) noexcept {
  Expected<void, IntegrateError> first_error;
  const auto keep_first = [&first_error](Expected<void, IntegrateError> ok) {
    if (!ok && first_error) {
      first_error = ok;
    }
  };
  std::size_t i = 0;
  while (i < rays.size()) {
    // A run of rays of one scan.
    std::size_t run_end = i + 1;
    while (run_end < rays.size() && rays[run_end].scan == rays[i].scan) {
      ++run_end;
    }
    if (!have_scan_ || rays[i].scan != scan_) {
      ++counters_.scans;
      if (per_scan_) {
        keep_first(flush());  // the previous scan is complete
      }
      have_scan_ = true;
      scan_split_ = false;
      scan_ = rays[i].scan;
    }
    while (i < run_end) {
      const RayPreparer::Progress p =
          preparer.prepare(rays.subspan(i, run_end - i),
                           std::span<PreparedRay>(batch_.data() + fill_, batch_.size() - fill_));
      fill_ += p.written;
      i += p.consumed;
      if (fill_ == batch_.size() || (p.consumed == 0 && i < run_end)) {
        // Full (or no room for the next ray's pieces): in it goes.
        if (per_scan_ && i < run_end && !scan_split_) {
          ++counters_.scans_split;
          scan_split_ = true;
        }
        if (fill_ == 0) {
          // Not one piece fits an empty batch (more pieces per ray than the batch holds): the
          // preparer made no progress, so give up on the rest rather than spin.
          i = run_end;
          break;
        }
        keep_first(flush());
      }
    }
  }
  return first_error;
}

Error integrateFailure(const VoxelMap& map, const Backend& backend, IntegrateError error,
                       std::string_view raise) {
  if (error == IntegrateError::kTierFailed) {
    const auto failure = map.tierFailure();
    return Error{failure ? failure->code : ErrorCode::kIo,
                 "moving regions between the map's memory tiers failed: " +
                     (failure ? failure->message : std::string("unknown reason"))};
  }
  if (error == IntegrateError::kStoreFull && map.tiered()) {
    return Error{ErrorCode::kCapacity, "one batch touches more regions than the pool's " +
                                           std::to_string(map.store().capacity()) +
                                           " hold at once; raise " + std::string(raise) +
                                           " or make batches smaller (--batch-rays)"};
  }
  if (error == IntegrateError::kStoreFull) {
    char gib[32];
    std::snprintf(gib, sizeof gib, "%g",
                  static_cast<double>(map.store().poolBytes()) / static_cast<double>(1u << 30));
    return Error{ErrorCode::kCapacity, "the map needs more than the " +
                                           std::to_string(map.store().capacity()) + " regions (" +
                                           gib + " GiB) its memory budget allows; raise " +
                                           std::string(raise)};
  }
  return Error{ErrorCode::kIo, std::string("integration failed on the ") + backend.name() +
                                   " backend: " + toString(error)};
}

}  // namespace raymap
