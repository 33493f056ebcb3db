// SPDX-License-Identifier: BSD-3-Clause
// Batch planning for device backends.
#include "src/device/staging/batch_plan.hpp"

#include <algorithm>
#include <optional>

#include "raymap/assert.hpp"

#include "kernels/common/span_walk.h"

namespace raymap::gpu {

BatchPlanner::BatchPlanner(VoxelMap& map, DeviceRegionCache* cache, RegionTransfer& transfer,
                           const BatchLimits& limits)
    : map_(&map),
      cache_(cache),
      transfer_(&transfer),
      limits_(limits),
      region_voxels_(map.store().regionVoxels()),
      voxels_per_region_(map.store().voxelsPerRegion()),
      host_uninitialised_(map.store().capacity(), 0),
      seen_recycled_(map.regionsRecycled()) {
  RAYMAP_EXPECTS(limits.max_rays > 0 && limits.max_rays < (std::size_t{1} << 32));
  RAYMAP_EXPECTS(limits.max_spans > 0);
}

void BatchPlanner::reserve(BatchArrays& out) const {
  out.rays.reserve(limits_.max_rays);
  out.spans.reserve(limits_.max_spans);
  out.groups.reserve(limits_.max_rays);
  out.hit_rays.reserve(limits_.max_rays);
  out.hit_keys.reserve(limits_.max_rays);
}

void BatchPlanner::revalidate() noexcept {
  if (cache_ == nullptr || map_->regionsRecycled() == seen_recycled_) {
    return;
  }
  seen_recycled_ = map_->regionsRecycled();
  const RegionStore& store = map_->store();
  for (std::uint32_t slot = 0; slot < cache_->capacity(); ++slot) {
    const DeviceRegionCache::Entry& e = cache_->entry(slot);
    if (e.used && store.find(e.region) != e.host_slot) {
      cache_->drop(slot);
    }
  }
}

Expected<std::uint32_t, StoreError> BatchPlanner::acquireHostRegion(Vec3i region) noexcept {
  bool created = false;
  auto host = map_->acquireRegionUncleared(region, &created);
  if (host && created) {
    host_uninitialised_[*host] = 1;
  }
  return host;
}

Expected<std::uint32_t, IntegrateError> BatchPlanner::sharedRegion(
    std::uint32_t host_slot) noexcept {
  if (host_uninitialised_[host_slot] != 0) {
    // The device works in the host pool: a slot no region held before is still zero pages, and
    // filling its zero layers (the 40-byte NDT Gaussians) would make every page resident.
    auto ok = transfer_->fillClear(host_slot, map_->store().onZeroPages(host_slot));
    if (!ok) {
      return Unexpected(ok.error());
    }
    host_uninitialised_[host_slot] = 0;
    ++stats_.region_misses;
  } else {
    ++stats_.region_hits;
  }
  return host_slot;
}

Expected<std::uint32_t, IntegrateError> BatchPlanner::placeRegion(Vec3i region,
                                                                  std::uint32_t host_slot,
                                                                  bool* full, bool write) noexcept {
  *full = false;
  // A region the host never wrote is cleared on the device: its device copy is the only one.
  write = write || host_uninitialised_[host_slot] != 0;
  auto placement = cache_->place(region, host_slot, write);
  if (!placement) {
    // A region created for this ray must not stay uninitialised on the host: it is not on the
    // device yet, and a later batch will upload it from here. Its host slot may be one a window
    // move recycled while the download of its former region was still running: wait for it.
    if (host_uninitialised_[host_slot] != 0) {
      if (auto idle = transfer_->waitForDevice(); !idle) {
        return Unexpected(idle.error());
      }
      map_->store().clearRegion(host_slot);
      host_uninitialised_[host_slot] = 0;
    }
    *full = true;
    return DeviceRegionCache::kNoSlot;
  }
  if (placement->evicted && placement->evicted_entry.dirty) {
    auto ok = transfer_->download(placement->slot, placement->evicted_entry.host_slot,
                                  placement->evicted_entry.samples_dirty, /*drained=*/false);
    if (!ok) {
      return Unexpected(ok.error());
    }
    host_uninitialised_[placement->evicted_entry.host_slot] = 0;
  }
  if (host_uninitialised_[host_slot] != 0) {
    cache_->markSamplesWritten(placement->slot);  // the device copy is the only one
  }
  if (!placement->resident) {
    if (host_uninitialised_[host_slot] != 0) {
      auto ok = transfer_->fillClear(placement->slot, /*zero_layers_clear=*/false);
      if (!ok) {
        return Unexpected(ok.error());
      }
    } else {
      auto ok = transfer_->upload(placement->slot, host_slot);
      if (!ok) {
        return Unexpected(ok.error());
      }
    }
  }
  return placement->slot;
}

namespace {

/// The batch's error for a store error that ends it, or nullopt for one that only skips the
/// region (outside a rolling window or the index's range).
std::optional<IntegrateError> batchError(StoreError error) noexcept {
  if (error == StoreError::kFull) {
    return IntegrateError::kStoreFull;
  }
  if (error == StoreError::kTierFailed) {
    return IntegrateError::kTierFailed;
  }
  return std::nullopt;
}

rm_span_record spanRecord(const RaySpan& span, std::uint32_t ray, std::uint32_t slot) noexcept {
  rm_span_record record;
  record.ray = ray;
  record.slot = slot;
  record.flags = (span.first ? RM_SPAN_FIRST : 0u) | (span.last ? RM_SPAN_LAST : 0u);
  record.t0 = span.t0;
  record.t1 = span.t1;
  record.box_lo = span.box_lo;
  return record;
}

}  // namespace

Expected<bool, IntegrateError> BatchPlanner::planSpans(RayRegionWalk& walk, std::uint32_t ray_index,
                                                       BatchArrays& out) noexcept {
  RaySpan span;
  bool full = false;
  while (walk.next(&span)) {
    if (out.spans.size() == limits_.max_spans) {
      full = true;
      break;
    }
    const std::uint64_t key = RegionStore::packCoord(span.region);
    if (const std::uint32_t* cached = batch_regions_.find(key)) {
      if (*cached == DeviceRegionCache::kNoSlot) {
        ++stats_.spans_outside_window;
        continue;
      }
      if (cache_ != nullptr) {
        cache_->noteHit();
      } else {
        ++stats_.region_hits;
      }
      out.spans.push_back(spanRecord(span, ray_index, *cached));
      continue;
    }
    auto host = acquireHostRegion(span.region);
    if (!host) {
      if (const auto error = batchError(host.error())) {
        return Unexpected(*error);
      }
      ++stats_.spans_outside_window;  // outside a rolling window (or the index's range)
      batch_regions_.remember(DeviceRegionCache::kNoSlot);
      continue;
    }
    auto slot = cache_ != nullptr ? placeRegion(span.region, *host, &full) : sharedRegion(*host);
    if (!slot) {
      return Unexpected(slot.error());
    }
    if (full) {
      break;
    }
    batch_regions_.remember(*slot);
    out.spans.push_back(spanRecord(span, ray_index, *slot));
  }
  return full;
}

void BatchPlanner::planHit(const RayRegionWalk& walk, std::uint32_t ray_index,
                           BatchArrays& out) noexcept {
  const auto [region, index] = walk.sampleCell();
  const std::uint32_t* cached = batch_regions_.find(RegionStore::packCoord(region));
  std::uint32_t slot = DeviceRegionCache::kNoSlot;
  if (cached != nullptr) {
    slot = *cached;
  } else if (cache_ != nullptr) {
    slot = cache_->find(region);
  } else {
    // RegionStore::kNoSlot == DeviceRegionCache::kNoSlot. A tiered map brings a cold region
    // back (the device writes the hit into it).
    auto found = map_->findForWrite(region);
    slot = found ? *found : RegionStore::kNoSlot;
  }
  if (slot != DeviceRegionCache::kNoSlot) {
    if (cache_ != nullptr) {
      cache_->markSamplesWritten(slot);  // the hit writes its sample layers
    }
    const std::uint64_t voxel = std::uint64_t{slot} * voxels_per_region_ + index;
    out.hit_keys.push_back((voxel << 32) | ray_index);
  }
}

Expected<std::size_t, IntegrateError> BatchPlanner::plan(std::span<const PreparedRay> rays,
                                                         BatchArrays& out) noexcept {
  out.clear();
  if (cache_ != nullptr) {
    cache_->beginBatch();
  }
  batch_regions_.reset();
  std::size_t consumed = 0;
  for (; consumed < rays.size() && out.rays.size() < limits_.max_rays; ++consumed) {
    const PreparedRay& ray = rays[consumed];
    const auto ray_index = static_cast<std::uint32_t>(out.rays.size());
    const std::size_t spans_before = out.spans.size();
    const std::uint64_t outside_before = stats_.spans_outside_window;
    RayRegionWalk walk(ray, region_voxels_);
    // A ray that might not fit the batch's span records (by the regions it crosses, in a window
    // or not) starts the next batch before any of its regions is placed; the device planner cuts
    // its batches at the same ray (kernels/device/plan.h).
    if (spans_before + walk.regionCount() > limits_.max_spans) {
      if (out.rays.empty()) {
        ++stats_.rays_too_long;  // not even an empty batch holds it
        continue;
      }
      break;
    }
    auto planned = planSpans(walk, ray_index, out);
    if (!planned) {
      return Unexpected(planned.error());
    }
    const bool full = *planned;
    if (full) {
      out.spans.resize(spans_before);
      // The ray is planned again (next batch) or skipped: its spans are counted then, or never.
      stats_.spans_outside_window = outside_before;
      if (out.rays.empty()) {
        // Even an empty batch cannot hold this ray's regions: skip it, counted.
        ++stats_.rays_too_long;
        if (cache_ != nullptr) {
          cache_->beginBatch();
        }
        batch_regions_.reset();
        continue;
      }
      break;  // the next batch starts with this ray
    }
    if ((ray.flags & RM_RAY_END_HIT) != 0u) {
      planHit(walk, ray_index, out);
    }
    out.rays.push_back(ray);
  }
  buildHitGroups(out);
  return consumed;
}

void BatchPlanner::beginDevicePlanned() noexcept {
  if (cache_ != nullptr) {
    cache_->beginBatch();
  }
  batch_regions_.reset();
}

Expected<std::uint32_t, IntegrateError> BatchPlanner::placeDevicePlanned(
    Vec3i region, std::uint32_t spans, std::uint32_t samples) noexcept {
  RAYMAP_DEBUG_ASSERT(spans > 0);
  auto host = acquireHostRegion(region);
  if (!host) {
    // Outside the range or the window cannot happen: a precondition (DevicePlanner checks).
    return Unexpected(batchError(host.error()).value_or(IntegrateError::kDeviceFailure));
  }
  if (cache_ == nullptr) {
    auto slot = sharedRegion(*host);
    stats_.region_hits += spans - 1u;  // plan(): each further span in the region is a hit
    return slot;
  }
  bool full = false;
  auto slot = placeRegion(region, *host, &full);
  if (!slot) {
    return slot;
  }
  if (full) {
    return Unexpected(IntegrateError::kDeviceFailure);  // more regions than slots: a precondition
  }
  cache_->noteHits(spans - 1u);
  if (samples > 0) {
    cache_->markSamplesWritten(*slot);
  }
  return slot;
}

void BatchPlanner::buildHitGroups(BatchArrays& out) const {
  // Sorting (voxel, ray) keys groups the samples of each voxel, in ray order within a group.
  std::sort(out.hit_keys.begin(), out.hit_keys.end());
  for (std::size_t i = 0; i < out.hit_keys.size();) {
    const std::uint64_t voxel = out.hit_keys[i] >> 32;
    rm_hit_group group;
    group.slot = static_cast<std::uint32_t>(voxel / voxels_per_region_);
    group.index = static_cast<std::uint32_t>(voxel % voxels_per_region_);
    group.first = static_cast<std::uint32_t>(out.hit_rays.size());
    for (; i < out.hit_keys.size() && (out.hit_keys[i] >> 32) == voxel; ++i) {
      out.hit_rays.push_back(static_cast<std::uint32_t>(out.hit_keys[i] & 0xFFFFFFFFu));
    }
    group.count = static_cast<std::uint32_t>(out.hit_rays.size()) - group.first;
    out.groups.push_back(group);
  }
}

Expected<void, IntegrateError> BatchPlanner::downloadAll() noexcept {
  if (cache_ == nullptr) {
    return {};  // shared mode: the device worked on the host store itself
  }
  for (std::uint32_t slot = 0; slot < cache_->capacity(); ++slot) {
    const DeviceRegionCache::Entry& e = cache_->entry(slot);
    if (e.used && e.dirty) {
      auto ok = transfer_->download(slot, e.host_slot, e.samples_dirty, /*drained=*/true);
      if (!ok) {
        return Unexpected(ok.error());
      }
      host_uninitialised_[e.host_slot] = 0;
      cache_->markClean(slot);
    }
  }
  return {};
}

Expected<void, IntegrateError> BatchPlanner::writeBack(
    std::span<const std::uint32_t> host_slots) noexcept {
  if (cache_ == nullptr) {
    return {};
  }
  const RegionStore& store = map_->store();
  for (const std::uint32_t host_slot : host_slots) {
    const std::uint32_t slot = cache_->find(store.coordOf(host_slot));
    if (slot == DeviceRegionCache::kNoSlot || cache_->entry(slot).host_slot != host_slot) {
      continue;
    }
    if (cache_->entry(slot).dirty) {
      if (auto ok = transfer_->download(slot, host_slot, cache_->entry(slot).samples_dirty,
                                        /*drained=*/true);
          !ok) {
        return ok;
      }
      host_uninitialised_[host_slot] = 0;
    }
    cache_->drop(slot);
  }
  return transfer_->waitForDevice();
}

Expected<bool, IntegrateError> BatchPlanner::placeForRead(
    std::span<const std::uint32_t> host_slots, std::span<std::uint32_t> device_slots) noexcept {
  RAYMAP_EXPECTS(host_slots.size() == device_slots.size());
  if (cache_ == nullptr) {
    std::copy(host_slots.begin(), host_slots.end(), device_slots.begin());
    return true;
  }
  cache_->beginBatch();
  const RegionStore& store = map_->store();
  for (std::size_t r = 0; r < host_slots.size(); ++r) {
    bool full = false;
    auto slot = placeRegion(store.coordOf(host_slots[r]), host_slots[r], &full, /*write=*/false);
    if (!slot) {
      return Unexpected(slot.error());
    }
    if (full) {
      return false;
    }
    device_slots[r] = *slot;
  }
  return true;
}

}  // namespace raymap::gpu
