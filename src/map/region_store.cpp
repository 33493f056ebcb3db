// SPDX-License-Identifier: BSD-3-Clause
// Region pool and index.
#include "src/map/region_store.hpp"

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

namespace raymap {

const char* toString(StoreError error) noexcept {
  switch (error) {
    case StoreError::kFull:
      return "region store full";
    case StoreError::kOutOfRange:
      return "region coordinate out of range";
    case StoreError::kOutsideWindow:
      return "region outside the rolling window";
    case StoreError::kTierFailed:
      return "the map's cold tiers failed";
  }
  return "unknown store error";
}

Result<RegionStore> RegionStore::create(const Config& config) {
  if (config.capacity == 0) {
    return fail(ErrorCode::kInvalidArgument, "region store capacity must be at least one region");
  }
  if (config.schema.size() == 0) {
    return fail(ErrorCode::kInvalidArgument, "a map needs at least one layer");
  }
  RegionStore store;
  store.schema_ = config.schema;
  store.region_voxels_ = config.region_voxels;
  const auto n = static_cast<std::uint32_t>(config.region_voxels);
  store.voxels_per_region_ = n * n * n;
  store.capacity_ = config.capacity;

  std::size_t total = 0;
  for (int l = 0; l < config.schema.size(); ++l) {
    const std::size_t region_bytes =
        std::size_t{config.schema.at(l).bytes_per_voxel} * store.voxels_per_region_;
    store.layer_offset_.push_back(total);
    store.layer_region_bytes_.push_back(region_bytes);
    total += region_bytes * config.capacity;
  }
  auto pool = platform::PageBlock::create(total);
  if (!pool) {
    return fail(pool.error().code, "region store of " + std::to_string(config.capacity) +
                                       " regions: " + pool.error().message);
  }
  store.pool_ = std::move(pool).value();
  for (int l = 0; l < config.schema.size(); ++l) {
    if (config.schema.at(l).dense) {
      const auto u = static_cast<std::size_t>(l);
      store.pool_.adviseHugePages(store.layer_offset_[u],
                                  store.layer_region_bytes_[u] * config.capacity);
    }
  }
  if (config.prefault) {
    store.pool_.prefault();
  }
  store.coords_.assign(config.capacity, Vec3i{});
  store.used_.assign(config.capacity, 0);
  store.fresh_.assign(config.capacity, 1);  // prefault() writes zeros: still zero pages
  store.sparse_zero_.assign(config.capacity, 0);
  store.free_slots_.reserve(config.capacity);
  for (std::uint32_t s = config.capacity; s > 0; --s) {
    store.free_slots_.push_back(s - 1);  // slot 0 is handed out first
  }
  store.index_ = RegionIndex(config.capacity);
  return store;
}

std::uint32_t RegionStore::find(Vec3i region) const noexcept {
  if (!inRange(region)) {
    return kNoSlot;
  }
  return findPacked(packCoord(region));
}

std::uint32_t RegionStore::findPacked(std::uint64_t key) const noexcept {
  static_assert(RegionIndex::kNone == kNoSlot);
  return index_.find(key);
}

Expected<std::uint32_t, StoreError> RegionStore::findOrCreate(Vec3i region) noexcept {
  bool created = false;
  auto slot = findOrCreateUncleared(region, &created);
  if (slot && created) {
    clearRegion(*slot);
  }
  return slot;
}

Expected<std::uint32_t, StoreError> RegionStore::findOrCreateUncleared(Vec3i region,
                                                                       bool* created) noexcept {
  *created = false;
  if (!inRange(region)) {
    return Unexpected(StoreError::kOutOfRange);
  }
  const std::uint64_t key = packCoord(region);
  if (const std::uint32_t existing = index_.find(key); existing != kNoSlot) {
    return existing;
  }
  if (free_slots_.empty()) {
    return Unexpected(StoreError::kFull);
  }
  const std::uint32_t slot = free_slots_.back();
  free_slots_.pop_back();
  index_.insert(key, slot);
  coords_[slot] = region;
  used_[slot] = 1;
  ++size_;
  *created = true;
  return slot;
}

void RegionStore::clearRegion(std::uint32_t slot) noexcept {
  for (int l = 0; l < schema_.size(); ++l) {
    // A slot's first use finds the OS's zero pages: zero-valued layers need no writes, and pages
    // that are never written (voxel means away from surfaces) never become resident. The same
    // holds for sparse layers whose pages discardSparseLayers() gave back.
    const LayerSpec& spec = schema_.at(l);
    const bool zero_pages = fresh_[slot] != 0 || (sparse_zero_[slot] != 0 && !spec.dense);
    if (!(spec.clearsToZero() && zero_pages)) {
      clearLayer(slot, l);
    }
  }
  fresh_[slot] = 0;
  sparse_zero_[slot] = 0;
}

void RegionStore::discardSparseLayers(std::uint32_t slot) noexcept {
  bool all = true;
  for (int l = 0; l < schema_.size(); ++l) {
    const LayerSpec& spec = schema_.at(l);
    if (spec.dense || !spec.clearsToZero()) {
      continue;
    }
    const auto u = static_cast<std::size_t>(l);
    all = pool_.discard(layer_offset_[u] + std::size_t{slot} * layer_region_bytes_[u],
                        layer_region_bytes_[u]) &&
          all;
  }
  sparse_zero_[slot] = all ? 1 : 0;
}

void RegionStore::clearLayer(std::uint32_t slot, int layer) noexcept {
  const LayerSpec& spec = schema_.at(layer);
  std::byte* bytes = layerBytes(slot, layer);
  const std::size_t words = spec.bytes_per_voxel / 4u;
  if (spec.clearsToZero()) {
    std::memset(bytes, 0, layerRegionBytes(layer));
    return;
  }
  auto* out = reinterpret_cast<std::uint32_t*>(bytes);  // pool is page-aligned
  if (words == 1) {
    std::fill_n(out, voxels_per_region_, spec.clear_words[0]);
    return;
  }
  for (std::uint32_t v = 0; v < voxels_per_region_; ++v) {
    for (std::size_t w = 0; w < words; ++w) {
      out[std::size_t{v} * words + w] = spec.clear_words[w];
    }
  }
}

void RegionStore::release(std::uint32_t slot) noexcept {
  RAYMAP_EXPECTS(slot < capacity_ && used_[slot] != 0);
  index_.erase(packCoord(coords_[slot]));
  used_[slot] = 0;
  fresh_[slot] = 0;  // whoever held it (host or a device sharing the pool) may have written it
  free_slots_.push_back(slot);
  --size_;
}

void RegionStore::clear() noexcept {
  for (std::uint32_t slot = 0; slot < capacity_; ++slot) {
    if (used_[slot] != 0) {
      release(slot);
    }
  }
}

}  // namespace raymap
