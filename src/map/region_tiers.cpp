// SPDX-License-Identifier: BSD-3-Clause
// RegionTiers: staging, background zstd compression and the spill file (see region_tiers.hpp).
#include "src/map/region_tiers.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

#include <zstd.h>

#include "src/map/region_planes.hpp"
#include "src/map/region_store.hpp"

namespace raymap {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string mib(std::uint64_t bytes) {
  return std::to_string((bytes + (std::uint64_t{1} << 19)) >> 20) + " MiB";
}

}  // namespace

Result<std::unique_ptr<RegionTiers>> RegionTiers::create(const RegionTierConfig& config,
                                                         const LayerSchema& schema,
                                                         std::uint32_t voxels_per_region) {
  if (config.staging_regions == 0) {
    return fail(ErrorCode::kInvalidArgument, "the cold tiers need at least one staging region");
  }
  std::unique_ptr<RegionTiers> tiers(new RegionTiers(config, schema, voxels_per_region));
  if (!config.spill_dir.empty()) {
    auto spill = SpillFile::create(config.spill_dir);
    if (!spill) {
      return Unexpected(spill.error());
    }
    tiers->spill_ = std::move(spill).value();
  }
  tiers->worker_ = std::thread([t = tiers.get()] { t->run(); });
  return tiers;
}

RegionTiers::RegionTiers(const RegionTierConfig& config, const LayerSchema& schema,
                         std::uint32_t voxels_per_region)
    : config_(config), schema_(schema), voxels_(voxels_per_region) {
  for (int l = 0; l < schema_.size(); ++l) {
    layer_bytes_.push_back(std::size_t{schema_.at(l).bytes_per_voxel} * voxels_);
    region_bytes_ += layer_bytes_.back();
  }
  // Buffers are sized on first use: a map that never outgrows its pool pays nothing for them.
  staging_.resize(config_.staging_regions);
  for (std::uint32_t i = 0; i < config_.staging_regions; ++i) {
    free_staging_.push_back(config_.staging_regions - 1 - i);
  }
}

RegionTiers::~RegionTiers() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  work_.notify_all();
  if (worker_.joinable()) {
    worker_.join();
  }
}

Expected<void, Error> RegionTiers::evict(std::uint64_t key, const RegionStore& store,
                                         std::uint32_t slot, std::uint64_t last_use, bool dirty) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (failure_) {
    return Unexpected(*failure_);
  }
  ++stats_.evictions;
  if (auto it = entries_.find(key); it != entries_.end()) {
    if (!dirty && it->second.resident) {
      // Unchanged since it was read back: the cold copy is the region.
      ++stats_.clean_evictions;
      Entry& e = it->second;
      e.resident = false;
      if (e.state == State::kCompressed) {
        cold_order_.erase({e.last_use, key});
        cold_order_.insert({last_use, key});
      }
      e.last_use = last_use;
      return {};
    }
    eraseLocked(it);  // a stale copy of a region that changed since
  }
  if (free_staging_.empty()) {
    ++stats_.waits;
    const Clock::time_point start = Clock::now();
    space_.wait(lock, [&] { return !free_staging_.empty() || failure_.has_value(); });
    stats_.wait_seconds += secondsSince(start);
    if (failure_) {
      return Unexpected(*failure_);
    }
  }
  const std::uint32_t buffer = free_staging_.back();
  free_staging_.pop_back();
  lock.unlock();
  // The buffer is this thread's until it is queued: copy without holding the lock.
  if (staging_[buffer].empty()) {
    staging_[buffer].resize(region_bytes_);
  }
  std::byte* out = staging_[buffer].data();
  for (int l = 0; l < schema_.size(); ++l) {
    std::memcpy(out, store.layerBytes(slot, l), layer_bytes_[static_cast<std::size_t>(l)]);
    out += layer_bytes_[static_cast<std::size_t>(l)];
  }
  lock.lock();
  Entry entry;
  entry.state = State::kStaged;
  entry.staging = buffer;
  entry.generation = next_generation_++;
  entry.last_use = last_use;
  jobs_.push_back(Job{key, buffer, entry.generation});
  entries_[key] = std::move(entry);
  lock.unlock();
  work_.notify_one();
  return {};
}

Result<bool> RegionTiers::restore(std::uint64_t key, RegionStore& store, std::uint32_t slot,
                                  bool keep_copy) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (failure_) {
    return Unexpected(*failure_);
  }
  auto it = entries_.find(key);
  if (it == entries_.end() || it->second.resident) {
    return false;
  }
  const Clock::time_point start = Clock::now();
  Entry& e = it->second;
  switch (e.state) {
    case State::kStaged: {
      // Still waiting for (or in) the compressor, which only reads the buffer and frees it
      // when it finds the entry gone.
      const std::byte* in = staging_[e.staging].data();
      for (int l = 0; l < schema_.size(); ++l) {
        std::memcpy(store.layerBytes(slot, l), in, layer_bytes_[static_cast<std::size_t>(l)]);
        in += layer_bytes_[static_cast<std::size_t>(l)];
      }
      eraseLocked(it);
      break;
    }
    case State::kCompressed: {
      if (auto ok = decodeInto(e.packed, store, slot, key); !ok) {
        failure_ = ok.error();
        return Unexpected(ok.error());
      }
      if (keep_copy) {
        e.resident = true;
      } else {
        eraseLocked(it);
      }
      break;
    }
    case State::kSpilled: {
      if (auto ok =
              spill_.read(e.spill, key, static_cast<std::uint32_t>(region_bytes_), restore_packed_);
          !ok) {
        failure_ = ok.error();
        return Unexpected(ok.error());
      }
      ++stats_.spill_reads;
      stats_.spill_bytes_read += SpillFile::kHeaderBytes + restore_packed_.size();
      if (auto ok = decodeInto(restore_packed_, store, slot, key); !ok) {
        failure_ = Error{ok.error().code, spill_.description() + ": " + ok.error().message};
        return Unexpected(*failure_);
      }
      if (keep_copy) {
        e.resident = true;
      } else {
        eraseLocked(it);
      }
      break;
    }
  }
  ++stats_.restores;
  stats_.restore_seconds += secondsSince(start);
  return true;
}

void RegionTiers::dropCopy(std::uint64_t key) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = entries_.find(key); it != entries_.end() && it->second.resident) {
    eraseLocked(it);
  }
}

bool RegionTiers::holdsCold(std::uint64_t key) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = entries_.find(key);
  return it != entries_.end() && !it->second.resident;
}

std::vector<std::uint64_t> RegionTiers::coldKeys() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::uint64_t> keys;
  keys.reserve(entries_.size());
  for (const auto& [key, e] : entries_) {
    if (!e.resident) {
      keys.push_back(key);
    }
  }
  return keys;
}

std::uint64_t RegionTiers::coldCount() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::uint64_t n = 0;
  for (const auto& [key, e] : entries_) {
    n += e.resident ? 0u : 1u;
  }
  return n;
}

RegionTierStats RegionTiers::stats() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  RegionTierStats s = stats_;
  for (const auto& [key, e] : entries_) {
    if (e.resident) {
      continue;
    }
    switch (e.state) {
      case State::kStaged:
        ++s.regions_staged;
        break;
      case State::kCompressed:
        ++s.regions_compressed;
        break;
      case State::kSpilled:
        ++s.regions_spilled;
        break;
    }
  }
  s.spill_file_bytes = spill_.sizeBytes();
  s.spill_garbage_bytes = spill_.garbageBytes();
  return s;
}

std::optional<Error> RegionTiers::failure() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return failure_;
}

Expected<void, Error> RegionTiers::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  space_.wait(lock, [&] { return (jobs_.empty() && busy_ == 0) || failure_.has_value(); });
  if (failure_) {
    return Unexpected(*failure_);
  }
  return {};
}

int RegionTiers::spillDescriptorForTests() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return spill_.descriptorForTests();
}

void RegionTiers::ZstdDeleter::operator()(ZSTD_CCtx_s* c) const noexcept { ZSTD_freeCCtx(c); }
void RegionTiers::ZstdDeleter::operator()(ZSTD_DCtx_s* d) const noexcept { ZSTD_freeDCtx(d); }

void RegionTiers::run() {
  std::vector<std::byte> planes;  // sized by the first job
  std::vector<std::byte> packed;
  const std::unique_ptr<ZSTD_CCtx_s, ZstdDeleter> context(ZSTD_createCCtx());
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    work_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
    if (stop_) {
      return;
    }
    const Job job = jobs_.front();
    jobs_.pop_front();
    ++busy_;
    const auto live = [&] {
      const auto it = entries_.find(job.key);
      return it != entries_.end() && it->second.state == State::kStaged &&
             it->second.generation == job.generation;
    };
    if (live() && !failure_) {
      lock.unlock();
      const Clock::time_point start = Clock::now();
      compressJob(job, context.get(), planes, packed, lock);
      stats_.compress_seconds += secondsSince(start);
    }
    free_staging_.push_back(job.staging);
    --busy_;
    space_.notify_all();
  }
}

void RegionTiers::compressJob(const Job& job, ZSTD_CCtx_s* context, std::vector<std::byte>& planes,
                              std::vector<std::byte>& packed, std::unique_lock<std::mutex>& lock) {
  // Called without the lock (the staging buffer stays this job's until it is pushed back free);
  // returns with it.
  if (planes.empty()) {
    planes.resize(region_bytes_);
    packed.resize(ZSTD_compressBound(region_bytes_));
  }
  const std::byte* in = staging_[job.staging].data();
  std::byte* out = planes.data();
  for (int l = 0; l < schema_.size(); ++l) {
    encodeBytePlanes(in, voxels_, schema_.at(l).bytes_per_voxel / 4u, out);
    in += layer_bytes_[static_cast<std::size_t>(l)];
    out += layer_bytes_[static_cast<std::size_t>(l)];
  }
  // Level 1: twice LZ4's ratio on map regions at 0.8 of its speed (docs/large-maps.md); the
  // speed matters less here, off the map's thread, than how many regions the budget holds.
  const std::size_t n = context == nullptr
                            ? 0
                            : ZSTD_compressCCtx(context, packed.data(), packed.size(),
                                                planes.data(), region_bytes_, kZstdLevel);
  lock.lock();
  if (context == nullptr || ZSTD_isError(n) != 0u) {
    failure_ = Error{ErrorCode::kIo, std::string("compressing a region for the compressed tier "
                                                 "failed: ") +
                                         (context == nullptr ? "no memory for zstd's context"
                                                             : ZSTD_getErrorName(n))};
    return;
  }
  const auto it = entries_.find(job.key);
  if (it != entries_.end() && it->second.state == State::kStaged &&
      it->second.generation == job.generation) {
    Entry& e = it->second;
    e.state = State::kCompressed;
    e.packed.assign(packed.begin(), packed.begin() + static_cast<std::ptrdiff_t>(n));
    cold_order_.insert({e.last_use, job.key});
    ++stats_.compressions;
    stats_.raw_bytes_compressed += region_bytes_;
    stats_.packed_bytes += n;
    stats_.compressed_bytes += n;
    stats_.compressed_peak_bytes = std::max(stats_.compressed_peak_bytes, stats_.compressed_bytes);
  }
  while (stats_.compressed_bytes > config_.compressed_bytes && !failure_) {
    if (auto ok = spillColdest(lock); !ok) {
      failure_ = ok.error();
    }
  }
}

Expected<void, Error> RegionTiers::spillColdest(std::unique_lock<std::mutex>& lock) {
  (void)lock;  // held: the spill file and the entries are guarded by it
  const auto coldest = cold_order_.begin();
  const std::uint64_t key = coldest->second;
  const auto it = entries_.find(key);
  Entry& e = it->second;
  if (e.resident) {
    // A clean copy of a region in the pool: dropping it costs nothing now (its next eviction
    // compresses it again).
    eraseLocked(it);
    return {};
  }
  if (!spill_.isOpen()) {
    return fail(ErrorCode::kCapacity,
                "the compressed tier is full (" + mib(config_.compressed_bytes) +
                    ", map.compressed_memory) and there is no spill folder (map.spill_dir)");
  }
  auto record = spill_.append(key, static_cast<std::uint32_t>(region_bytes_), e.packed);
  if (!record) {
    return Unexpected(record.error());
  }
  ++stats_.spill_writes;
  stats_.spill_bytes_written += SpillFile::kHeaderBytes + e.packed.size();
  stats_.compressed_bytes -= e.packed.size();
  cold_order_.erase(coldest);
  std::vector<std::byte>().swap(e.packed);
  e.state = State::kSpilled;
  e.spill = *record;
  return compactSpillLocked();
}

Expected<void, Error> RegionTiers::compactSpillLocked() {
  const std::uint64_t garbage = spill_.garbageBytes();
  if (garbage == 0 || garbage < config_.spill_compact_bytes || 2 * garbage < spill_.sizeBytes()) {
    return {};
  }
  auto fresh = SpillFile::create(config_.spill_dir);
  if (!fresh) {
    return {};  // no room for a second file now: the old one still serves
  }
  std::vector<std::byte> packed;
  std::vector<std::pair<Entry*, SpillRecord>> moved;
  for (auto& [key, e] : entries_) {
    if (e.state != State::kSpilled) {
      continue;
    }
    if (auto ok = spill_.read(e.spill, key, static_cast<std::uint32_t>(region_bytes_), packed);
        !ok) {
      failure_ = ok.error();
      return Unexpected(ok.error());
    }
    auto record = fresh->append(key, static_cast<std::uint32_t>(region_bytes_), packed);
    if (!record) {
      return {};  // the new file is dropped: every record stays where it was
    }
    moved.emplace_back(&e, *record);
  }
  for (auto& [entry, record] : moved) {
    entry->spill = record;
  }
  const std::uint64_t before = spill_.sizeBytes();
  spill_ = std::move(fresh).value();
  ++stats_.spill_compactions;
  stats_.spill_bytes_reclaimed += before - spill_.sizeBytes();
  return {};
}

void RegionTiers::eraseLocked(std::unordered_map<std::uint64_t, Entry>::iterator it) {
  Entry& e = it->second;
  if (e.state == State::kCompressed) {
    stats_.compressed_bytes -= e.packed.size();
    cold_order_.erase({e.last_use, it->first});
  } else if (e.state == State::kSpilled) {
    spill_.release(e.spill);
  }
  entries_.erase(it);  // a staged one's buffer is freed by its job
}

Expected<void, Error> RegionTiers::decodeInto(std::span<const std::byte> packed, RegionStore& store,
                                              std::uint32_t slot, std::uint64_t key) {
  if (restore_planes_.empty()) {
    restore_planes_.resize(region_bytes_);
  }
  if (!decompressor_) {
    decompressor_.reset(ZSTD_createDCtx());
  }
  const std::size_t n =
      decompressor_ == nullptr
          ? 0
          : ZSTD_decompressDCtx(decompressor_.get(), restore_planes_.data(), restore_planes_.size(),
                                packed.data(), packed.size());
  if (ZSTD_isError(n) != 0u || n != region_bytes_) {
    const Vec3i c = RegionStore::unpackCoord(key);
    return fail(ErrorCode::kCorrupt, "region (" + std::to_string(c.x) + ", " + std::to_string(c.y) +
                                         ", " + std::to_string(c.z) + ") does not decompress");
  }
  const std::byte* in = restore_planes_.data();
  for (int l = 0; l < schema_.size(); ++l) {
    // Sparse layers of a slot whose pages were given back: write only the non-zero words, so a
    // restored region is as resident as it was when it was built.
    const LayerSpec& spec = schema_.at(l);
    const bool zero = (store.onZeroPages(slot) || store.sparseLayersZero(slot)) && !spec.dense &&
                      spec.clearsToZero();
    decodeBytePlanes(in, voxels_, spec.bytes_per_voxel / 4u, store.layerBytes(slot, l), zero);
    in += layer_bytes_[static_cast<std::size_t>(l)];
  }
  return {};
}

}  // namespace raymap
