// SPDX-License-Identifier: BSD-3-Clause
// An MCAP file's end: the footer and magic, and the summary section they point to (schemas,
// channels, statistics, chunk indexes). What the reader believes about where the data section
// ends and where its chunks are comes from here, so that damage in the middle of a complete file
// is told apart from a file that was cut off.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace raymap::bag::mcap {

/// @brief One chunk as the summary's chunk index records it.
struct IndexedChunk {
  std::uint64_t offset = 0;  ///< where the chunk record starts
  std::uint64_t length = 0;  ///< the whole record: opcode, length and content
};

/// @brief What the end of an MCAP file says.
struct FileEnd {
  enum class State : std::uint8_t {
    kSummary,    ///< footer, magic and a summary whose CRC checks
    kNoSummary,  ///< footer and magic, and the footer says there is no summary
    kDamaged,    ///< no footer and magic at the end, or a summary that fails its checks
  };
  State state = State::kDamaged;
  /// kDamaged: what is wrong, for a warning (without the path).
  std::string problem;
  /// Where the data section ends at the latest: the summary's start, else the footer's; 0 when
  /// the file has no footer (then only the file's size bounds it, and a record past it means
  /// the file was cut off).
  std::uint64_t data_end = 0;
  std::uint64_t summary_start = 0;   ///< kSummary: where the summary section starts
  std::vector<std::byte> summary;    ///< kSummary: the summary section's records
  std::vector<IndexedChunk> chunks;  ///< kSummary: the chunk indexes, by offset
};

/// @brief Reads the footer and the summary of the MCAP file `path` of `file_bytes` bytes. Never
/// fails: a file whose end cannot be read or checked is kDamaged with the reason.
FileEnd readFileEnd(const std::string& path, std::uint64_t file_bytes);

}  // namespace raymap::bag::mcap
