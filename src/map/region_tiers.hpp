// SPDX-License-Identifier: BSD-3-Clause
// The cold tiers of a global map: regions evicted from the pool, compressed in memory on a
// background thread and, past that budget, spilled to a scratch file (docs/large-maps.md).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "raymap/error.hpp"

#include "src/map/layer_schema.hpp"
#include "src/map/spill_file.hpp"

struct ZSTD_CCtx_s;
struct ZSTD_DCtx_s;

namespace raymap {

class RegionStore;

/// @brief Budgets of the cold tiers. Aggregate with defaults.
struct RegionTierConfig {
  static constexpr std::uint64_t kDefaultCompressedBytes = std::uint64_t{1} << 30;  // 1 GiB

  /// Off: a full pool fails integration (the fixed-memory behaviour raymapd relies on).
  bool enabled = false;
  /// Bytes of compressed regions held in memory before the coldest go to the spill file.
  std::uint64_t compressed_bytes = kDefaultCompressedBytes;
  /// Folder of the spill file; empty: no spill file (a full compressed tier is an error).
  std::string spill_dir;
  /// Regions copied out of the pool and waiting for the compressor: the most eviction gets ahead
  /// of compression before the map waits (memory: this many regions, uncompressed).
  std::uint32_t staging_regions = 32;
  /// The spill file is rewritten with only its live records once its garbage (records of
  /// regions read back for good) reaches this many bytes and half the file (0: at any garbage
  /// over half; the tests).
  std::uint64_t spill_compact_bytes = std::uint64_t{64} << 20;
};

/// @brief What the tiers hold and what moving regions through them cost. Value type; counters
/// are totals since the map was created.
struct RegionTierStats {
  std::uint64_t regions_staged = 0;      ///< copied out of the pool, not yet compressed
  std::uint64_t regions_compressed = 0;  ///< held compressed in memory (not in the pool)
  std::uint64_t regions_spilled = 0;     ///< held in the spill file only
  std::uint64_t compressed_bytes = 0;    ///< memory the compressed tier holds now
  std::uint64_t compressed_peak_bytes = 0;
  std::uint64_t evictions = 0;        ///< regions moved out of the pool (clean ones included)
  std::uint64_t clean_evictions = 0;  ///< of those, unchanged since a read: nothing to compress
  std::uint64_t restores = 0;         ///< regions brought back into the pool
  std::uint64_t compressions = 0;     ///< regions compressed
  std::uint64_t raw_bytes_compressed = 0;
  std::uint64_t packed_bytes = 0;  ///< what those compressed to (ratio = raw / packed)
  std::uint64_t spill_writes = 0;
  std::uint64_t spill_bytes_written = 0;
  std::uint64_t spill_reads = 0;
  std::uint64_t spill_bytes_read = 0;
  std::uint64_t spill_file_bytes = 0;       ///< the spill file's size now
  std::uint64_t spill_garbage_bytes = 0;    ///< of which no longer needed (read back)
  std::uint64_t spill_compactions = 0;      ///< rewrites of the file with its live records only
  std::uint64_t spill_bytes_reclaimed = 0;  ///< file bytes the compactions gave back
  std::uint64_t waits = 0;                  ///< evictions that waited for the compressor
  double wait_seconds = 0;                  ///< time the map's thread waited for it
  double compress_seconds = 0;              ///< background thread: compressing and spilling
  double restore_seconds = 0;               ///< map's thread: decompressing and reading back

  double compressionRatio() const noexcept {
    return packed_bytes == 0
               ? 0.0
               : static_cast<double>(raw_bytes_compressed) / static_cast<double>(packed_bytes);
  }
};

/// @brief The compressed and spilled tiers of one map's regions, keyed by packed region
/// coordinate (RegionStore::packCoord).
///
/// Design: the map's thread evicts a region by copying it (every layer, scan marks included, so a
/// region evicted between two batches of one scan keeps its marks) into one of a few staging
/// buffers and releasing its slot at once; a background thread turns staged regions into byte
/// planes (src/map/region_planes) compressed with zstd, and moves the coldest compressed regions
/// to the SpillFile when the compressed tier passes its budget. Bringing a region back copies it
/// from wherever it is (a staging buffer, memory or the file). A region brought back only to be
/// read keeps its cold copy, so evicting it again costs nothing (a "clean" eviction).
/// An I/O failure (full disk, damaged spill file) is sticky: every later call returns it.
///
/// Thread-safety: one map thread calls every member; the background thread is internal.
/// Real-time: no (allocates, locks, file I/O): only global maps, never raymapd's rolling window.
class RegionTiers {
 public:
  /// @brief Starts the background thread and, with a spill folder, creates the spill file (so an
  /// unwritable folder fails here, before any work).
  static Result<std::unique_ptr<RegionTiers>> create(const RegionTierConfig& config,
                                                     const LayerSchema& schema,
                                                     std::uint32_t voxels_per_region);
  ~RegionTiers();
  RegionTiers(const RegionTiers&) = delete;
  RegionTiers& operator=(const RegionTiers&) = delete;
  RegionTiers(RegionTiers&&) = delete;
  RegionTiers& operator=(RegionTiers&&) = delete;

  /// @brief Takes region `key` from pool slot `slot` of `store`. `last_use`: the map's access
  /// epoch when the region was last used (older ones spill first). `dirty`: false when the region
  /// is unchanged since it was brought back with its cold copy kept; then nothing is copied.
  /// Waits (counted) while every staging buffer is in use.
  Expected<void, Error> evict(std::uint64_t key, const RegionStore& store, std::uint32_t slot,
                              std::uint64_t last_use, bool dirty);
  /// @brief Copies region `key` into pool slot `slot`; false when the tiers do not hold it.
  /// `keep_copy`: keep the cold copy (the caller only reads the region; see evict()'s `dirty`).
  Result<bool> restore(std::uint64_t key, RegionStore& store, std::uint32_t slot, bool keep_copy);
  /// @brief Forgets the cold copy of a region that is in the pool and about to change.
  void dropCopy(std::uint64_t key);

  /// @brief True when the tiers hold region `key` and it is not in the pool.
  bool holdsCold(std::uint64_t key) const;
  /// @brief Keys of the regions held cold (not in the pool), in no particular order.
  std::vector<std::uint64_t> coldKeys() const;
  std::uint64_t coldCount() const;
  RegionTierStats stats() const;
  /// @brief The first I/O failure, if any (sticky).
  std::optional<Error> failure() const;
  /// @brief Waits until the background thread has compressed (and spilled) everything staged.
  Expected<void, Error> drain();
  /// @brief The spill file's descriptor (-1 without one), for tests that damage it on purpose.
  int spillDescriptorForTests() const;

 private:
  enum class State : std::uint8_t { kStaged, kCompressed, kSpilled };
  struct Entry {
    State state = State::kStaged;
    std::uint32_t staging = 0;      // kStaged: the buffer holding it
    std::uint64_t generation = 0;   // matches the queued job that compresses it
    std::vector<std::byte> packed;  // kCompressed
    SpillRecord spill;              // kSpilled
    std::uint64_t last_use = 0;
    bool resident = false;  // a clean copy of a region that is also in the pool
  };
  struct Job {
    std::uint64_t key;
    std::uint32_t staging;
    std::uint64_t generation;
  };

  RegionTiers(const RegionTierConfig& config, const LayerSchema& schema,
              std::uint32_t voxels_per_region);
  void run();
  struct ZstdDeleter {
    void operator()(ZSTD_CCtx_s* c) const noexcept;
    void operator()(ZSTD_DCtx_s* d) const noexcept;
  };
  static constexpr int kZstdLevel = 1;

  void compressJob(const Job& job, ZSTD_CCtx_s* context, std::vector<std::byte>& planes,
                   std::vector<std::byte>& packed, std::unique_lock<std::mutex>& lock);
  Expected<void, Error> spillColdest(std::unique_lock<std::mutex>& lock);
  /// Rewrites the spill file with the live records only, when its garbage has passed
  /// spill_compact_bytes and half the file (mutex_ held). A new file that cannot be made or
  /// written leaves the old one in use: compaction saves space, it is never needed.
  Expected<void, Error> compactSpillLocked();
  void eraseLocked(std::unordered_map<std::uint64_t, Entry>::iterator it);
  Expected<void, Error> decodeInto(std::span<const std::byte> packed, RegionStore& store,
                                   std::uint32_t slot, std::uint64_t key);

  RegionTierConfig config_;
  LayerSchema schema_;
  std::uint32_t voxels_ = 0;
  std::vector<std::size_t> layer_bytes_;  // one region's bytes per layer
  std::size_t region_bytes_ = 0;          // all layers

  mutable std::mutex mutex_;
  std::condition_variable work_;   // to the background thread: a job, or stop
  std::condition_variable space_;  // to the map thread: a staging buffer is free, or drained
  std::unordered_map<std::uint64_t, Entry> entries_;
  std::set<std::pair<std::uint64_t, std::uint64_t>> cold_order_;  // (last_use, key), compressed
  std::deque<Job> jobs_;
  std::vector<std::vector<std::byte>> staging_;
  std::vector<std::uint32_t> free_staging_;
  std::uint64_t next_generation_ = 1;
  unsigned busy_ = 0;  // jobs taken by the background thread, not finished
  bool stop_ = false;
  std::optional<Error> failure_;
  SpillFile spill_;
  RegionTierStats stats_;
  std::vector<std::byte> restore_planes_;                   // map thread's scratch
  std::unique_ptr<ZSTD_DCtx_s, ZstdDeleter> decompressor_;  // map thread's
  std::vector<std::byte> restore_packed_;
  std::thread worker_;
};

}  // namespace raymap
