// SPDX-License-Identifier: BSD-3-Clause
// The last tier of a global map past its memory budgets: compressed regions in a scratch file.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"

namespace raymap {

/// @brief Where one region's record lies in a SpillFile.
struct SpillRecord {
  std::uint64_t offset = 0;        ///< of the record header, bytes from the start of the file
  std::uint32_t packed_bytes = 0;  ///< compressed payload after the header
};

/// @brief An append-only scratch file of compressed regions, unlinked from its folder as soon as
/// it is created: it has no name, so nothing is left behind whatever way the process ends
/// (SIGKILL and power loss included), and the space returns to the file system when it closes.
///
/// Each record is a 28-byte header (tag "RSPL", region key, raw and packed sizes, CRC-32 of the
/// payload, CRC-32 of the header) and the payload. A record whose header or payload does not
/// match is reported with the file's folder, the region and the offset, never decoded.
/// Records are never rewritten: a region read back leaves garbage behind (counted in
/// garbageBytes()); the file only grows, by at most the compressed size of each eviction.
///
/// Thread-safety: not thread-safe (RegionTiers serialises all calls). Real-time: no (file I/O).
class SpillFile {
 public:
  static constexpr std::size_t kHeaderBytes = 28;

  SpillFile() = default;
  /// @brief Creates the file in `folder` (O_TMPFILE; where the file system lacks it, a named
  /// file removed at once). Fails naming the folder and the reason (missing, not writable...).
  static Result<SpillFile> create(const std::string& folder);
  SpillFile(SpillFile&& other) noexcept;
  SpillFile& operator=(SpillFile&& other) noexcept;
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;
  ~SpillFile();

  bool isOpen() const noexcept { return fd_ >= 0; }
  /// @brief "the spill file in FOLDER": how errors name it (it has no name of its own).
  const std::string& description() const noexcept { return description_; }

  /// @brief Appends a record of region `key` holding `packed` (which decodes to `raw_bytes`).
  /// A failed or short write (full disk) is an error naming the file; the file's end does not
  /// move, so earlier records stay readable.
  Result<SpillRecord> append(std::uint64_t key, std::uint32_t raw_bytes,
                             std::span<const std::byte> packed);
  /// @brief Reads the record at `record` into `packed` after checking that it is region `key`'s,
  /// of `raw_bytes` raw bytes, and that both checksums match.
  Expected<void, Error> read(const SpillRecord& record, std::uint64_t key, std::uint32_t raw_bytes,
                             std::vector<std::byte>& packed) const;
  /// @brief Marks a record's bytes as no longer needed (for the statistics).
  void release(const SpillRecord& record) noexcept {
    garbage_bytes_ += kHeaderBytes + record.packed_bytes;
  }

  std::uint64_t sizeBytes() const noexcept { return end_; }
  std::uint64_t garbageBytes() const noexcept { return garbage_bytes_; }
  /// @brief The descriptor, for tests that damage the file on purpose.
  int descriptorForTests() const noexcept { return fd_; }

 private:
  int fd_ = -1;
  std::uint64_t end_ = 0;
  std::uint64_t garbage_bytes_ = 0;
  std::string description_;
};

}  // namespace raymap
