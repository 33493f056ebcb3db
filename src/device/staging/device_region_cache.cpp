// SPDX-License-Identifier: BSD-3-Clause
// Device region cache bookkeeping.
#include "src/device/staging/device_region_cache.hpp"

#include "raymap/assert.hpp"

#include "src/map/region_store.hpp"

namespace raymap::gpu {

DeviceRegionCache::DeviceRegionCache(std::uint32_t capacity)
    : entries_(capacity), prev_(capacity, kNoSlot), next_(capacity, kNoSlot), index_(capacity) {
  RAYMAP_EXPECTS(capacity > 0);
  free_.reserve(capacity);
  for (std::uint32_t s = capacity; s > 0; --s) {
    free_.push_back(s - 1);  // slot 0 first
  }
}

void DeviceRegionCache::unlink(std::uint32_t slot) noexcept {
  const std::uint32_t p = prev_[slot];
  const std::uint32_t n = next_[slot];
  (p == kNoSlot ? head_ : next_[p]) = n;
  (n == kNoSlot ? tail_ : prev_[n]) = p;
  prev_[slot] = kNoSlot;
  next_[slot] = kNoSlot;
}

void DeviceRegionCache::pushBack(std::uint32_t slot) noexcept {
  prev_[slot] = tail_;
  next_[slot] = kNoSlot;
  (tail_ == kNoSlot ? head_ : next_[tail_]) = slot;
  tail_ = slot;
}

std::optional<DeviceRegionCache::Placement> DeviceRegionCache::place(Vec3i region,
                                                                     std::uint32_t host_slot,
                                                                     bool write) noexcept {
  const std::uint64_t key = RegionStore::packCoord(region);
  Placement placement;
  std::uint32_t slot = index_.find(key);
  if (slot != RegionIndex::kNone) {
    Entry& e = entries_[slot];
    RAYMAP_DEBUG_ASSERT(e.host_slot == host_slot);
    if (e.batch != batch_) {
      e.batch = batch_;
      unlink(slot);
      pushBack(slot);
    }
    e.dirty = e.dirty || write;
    ++hits_;
    placement.slot = slot;
    placement.resident = true;
    return placement;
  }
  if (!free_.empty()) {
    slot = free_.back();
    free_.pop_back();
    ++size_;
  } else {
    // Regions used by this batch sit at the most-recent end: if the least recent is one of them,
    // they all are.
    slot = head_;
    if (slot == kNoSlot || entries_[slot].batch == batch_) {
      return std::nullopt;
    }
    placement.evicted = true;
    placement.evicted_entry = entries_[slot];
    index_.erase(RegionStore::packCoord(entries_[slot].region));
    unlink(slot);
    ++evictions_;
  }
  ++misses_;
  entries_[slot] = Entry{region, host_slot, batch_, true, write, false};
  index_.insert(key, slot);
  pushBack(slot);
  placement.slot = slot;
  return placement;
}

std::uint32_t DeviceRegionCache::find(Vec3i region) const noexcept {
  const std::uint32_t slot = index_.find(RegionStore::packCoord(region));
  return slot == RegionIndex::kNone ? kNoSlot : slot;
}

void DeviceRegionCache::drop(std::uint32_t slot) noexcept {
  RAYMAP_EXPECTS(slot < capacity() && entries_[slot].used);
  index_.erase(RegionStore::packCoord(entries_[slot].region));
  unlink(slot);
  entries_[slot] = Entry{};
  free_.push_back(slot);
  --size_;
}

}  // namespace raymap::gpu
