// SPDX-License-Identifier: BSD-3-Clause
// The footer, the magic after it and the summary section, read from the end of an MCAP file.
#include "src/bag/mcap_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <span>

#include "src/bag/mcap_records.hpp"
#include "src/core/crc32.hpp"

namespace raymap::bag::mcap {
namespace {

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

bool readAt(std::FILE* file, std::uint64_t offset, std::span<std::byte> out) {
  return std::fseek(file, static_cast<long>(offset), SEEK_SET) == 0 &&
         std::fread(out.data(), 1, out.size(), file) == out.size();
}

FileEnd damaged(std::string problem, std::uint64_t data_end = 0) {
  FileEnd end;
  end.state = FileEnd::State::kDamaged;
  end.problem = std::move(problem);
  end.data_end = data_end;
  return end;
}

/// The chunk indexes of a summary that checked; false when one is malformed.
bool readChunkIndexes(FileEnd& end) {
  Cursor records(end.summary);
  while (records.left() > 0) {
    const auto op = static_cast<Op>(records.u8());
    Cursor record(records.bytes64());
    if (!records.ok()) {
      return false;
    }
    if (op != Op::kChunkIndex) {
      continue;
    }
    (void)record.u64();  // message start time
    (void)record.u64();  // message end time
    IndexedChunk chunk;
    chunk.offset = record.u64();
    chunk.length = record.u64();
    if (!record.ok() || chunk.length < kRecordPrefixBytes || chunk.offset > end.data_end ||
        chunk.length > end.data_end - chunk.offset) {
      return false;
    }
    end.chunks.push_back(chunk);
  }
  std::sort(end.chunks.begin(), end.chunks.end(),
            [](const IndexedChunk& a, const IndexedChunk& b) { return a.offset < b.offset; });
  return true;
}

}  // namespace

FileEnd readFileEnd(const std::string& path, std::uint64_t file_bytes) {
  const File file(std::fopen(path.c_str(), "rb"), &std::fclose);
  const std::uint64_t tail = kFooterRecordBytes + kMagic.size();
  if (!file) {
    return damaged("its end cannot be read");
  }
  if (file_bytes < kMagic.size() + tail) {
    return damaged("it is too short to end with an MCAP footer and magic");
  }
  const std::uint64_t footer_at = file_bytes - tail;
  std::vector<std::byte> footer(tail);
  if (!readAt(file.get(), footer_at, footer) ||
      !std::equal(kMagic.begin(), kMagic.end(), footer.end() - kMagic.size())) {
    return damaged("it does not end with the MCAP magic (its end is cut off or overwritten)");
  }
  Cursor f(std::span<const std::byte>(footer).subspan(1));
  if (static_cast<Op>(footer[0]) != Op::kFooter || f.u64() != kFooterContentBytes) {
    return damaged("no footer record before the magic at its end (offset " +
                   std::to_string(footer_at) + ")");
  }
  const std::uint64_t summary_start = f.u64();
  (void)f.u64();  // summary offset start
  const std::uint32_t summary_crc = f.u32();
  if (summary_start == 0) {
    FileEnd end;
    end.state = FileEnd::State::kNoSummary;
    end.data_end = footer_at;
    return end;
  }
  if (summary_start >= footer_at || summary_start < kMagic.size()) {
    return damaged("the footer's summary offset " + std::to_string(summary_start) +
                       " lies outside the file's records",
                   footer_at);
  }
  FileEnd end;
  end.summary.resize(static_cast<std::size_t>(footer_at - summary_start));
  if (!readAt(file.get(), summary_start, end.summary)) {
    return damaged("its summary section cannot be read", footer_at);
  }
  // The CRC covers the summary (and summary offset) sections and the footer up to the CRC.
  if (summary_crc != 0 &&
      crc32(crc32(0, end.summary),
            std::span<const std::byte>(footer).first(kFooterRecordBytes - 4)) != summary_crc) {
    return damaged(
        "its summary section (offset " + std::to_string(summary_start) + ") fails its CRC check",
        footer_at);
  }
  end.state = FileEnd::State::kSummary;
  end.summary_start = summary_start;
  end.data_end = summary_start;
  if (!readChunkIndexes(end)) {
    return damaged("its summary section (offset " + std::to_string(summary_start) +
                       ") holds a malformed chunk index",
                   footer_at);
  }
  return end;
}

}  // namespace raymap::bag::mcap
