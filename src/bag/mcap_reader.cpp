// SPDX-License-Identifier: BSD-3-Clause
// The MCAP reader: one sequential pass over the data section per forEach(), chunks decompressed
// (zstd, lz4) into one reused buffer and checked against their CRC; the summary section, when
// the file has one, only to know the topics up front.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "src/bag/bag_reader.hpp"
#include "src/bag/mcap_records.hpp"
#include "src/io/byte_reader.hpp"

namespace raymap::bag {
namespace {

using mcap::Cursor;
using mcap::Op;

/// A chunk may not claim more than this uncompressed: a corrupt size must not exhaust memory.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

std::uint32_t crc32Update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

std::string offsetText(std::uint64_t offset) {
  char text[48];
  std::snprintf(text, sizeof(text), "offset %" PRIu64, offset);
  return text;
}

class McapBagReader final : public BagReader {
 public:
  explicit McapBagReader(std::string path) : path_(std::move(path)) {}

  const std::string& path() const noexcept override { return path_; }
  const char* storage() const noexcept override { return "mcap"; }
  const std::vector<BagTopic>& topics() const noexcept override { return topics_; }
  double progress() const noexcept override { return reader_ ? reader_->progress() : 0.0; }

  const BagPass& pass() const noexcept override { return pass_; }

  std::optional<BagStatistics> statistics() const override {
    if (!statistics_) {
      return std::nullopt;
    }
    BagStatistics stats = *statistics_;
    stats.topic_messages.assign(topics_.size(), 0);
    std::uint64_t sum = 0;
    for (const auto& [channel, count] : statistics_pending_) {
      const auto topic = channel_topic_.find(channel);
      if (topic == channel_topic_.end()) {
        return std::nullopt;  // counts for a channel the summary does not define
      }
      stats.topic_messages[topic->second] += count;
      sum += count;
    }
    if (sum != stats.messages) {
      return std::nullopt;  // per-channel counts missing or inconsistent: count by reading
    }
    return stats;
  }

  /// Checks the magic and the header, then learns the topics from the summary section (or, in a
  /// file without one, from a pass over the data).
  Expected<void, Error> open() {
    if (auto first = rewind(); !first) {
      return first;
    }
    if (readSummary()) {
      return rewind();
    }
    BagMessage unused;
    for (;;) {
      auto more = next(unused);
      if (!more) {
        return Unexpected(more.error());
      }
      if (!more.value()) {
        break;
      }
    }
    return rewind();
  }

  Expected<void, Error> rewind() override {
    pass_ = BagPass{};
    message_index_ = 0;
    pending_ = {};
    in_chunk_.reset();
    done_ = false;
    return startPass();
  }

  Result<bool> next(BagMessage& out) override {
    while (!done_) {
      if (in_chunk_) {
        auto got = nextInChunk(out);
        if (!got || got.value()) {
          return got;
        }
        continue;  // the chunk is done
      }
      finishRecord();
      const std::uint64_t offset = reader_->position();
      auto prefix = reader_->ensure(mcap::kRecordPrefixBytes);
      if (!prefix) {
        return Unexpected(prefix.error());
      }
      if (prefix.value().size() < mcap::kRecordPrefixBytes) {
        markTruncated(offset, prefix.value().empty() ? "where the next record would begin"
                                                     : "inside a record's opcode and length");
        break;
      }
      Cursor head(prefix.value());
      const auto op = static_cast<Op>(head.u8());
      const std::uint64_t length = head.u64();
      const std::uint64_t file_left =
          reader_->fileBytes() - std::min(reader_->fileBytes(), offset + mcap::kRecordPrefixBytes);
      if (length > file_left) {
        markTruncated(offset, "inside a record that declares " + std::to_string(length) + " bytes");
        break;
      }
      auto record = reader_->ensure(mcap::kRecordPrefixBytes + static_cast<std::size_t>(length));
      if (!record) {
        return Unexpected(record.error());
      }
      if (record.value().size() < mcap::kRecordPrefixBytes + length) {
        markTruncated(offset, "inside a record");
        break;
      }
      pending_ = record.value().first(mcap::kRecordPrefixBytes + length);
      const std::span<const std::byte> content = pending_.subspan(mcap::kRecordPrefixBytes);
      if (op == Op::kDataEnd) {
        Cursor c(content);
        const std::uint32_t stored = c.u32();
        if (stored != 0 && stored != data_crc_) {
          return fail(ErrorCode::kCorrupt, path_ + ": the data section's CRC does not match (" +
                                               offsetText(offset) + "): the file is corrupt");
        }
        done_ = true;
      } else if (op == Op::kFooter) {
        done_ = true;  // a file without a DataEnd record
      } else if (op == Op::kChunk) {
        if (auto ok = chunk(content, offset); !ok) {
          return Unexpected(ok.error());
        }
      } else {
        auto got = handle(op, content, offset, out);
        if (!got || got.value()) {
          return got;
        }
      }
    }
    pass_.messages = message_index_;
    return false;
  }

 private:
  Expected<void, Error> startPass() {
    auto reader = io::ByteReader::open(path_);
    if (!reader) {
      return Unexpected(reader.error());
    }
    if (reader.value().compressed()) {
      return fail(ErrorCode::kUnsupported,
                  path_ +
                      ": a gzip-compressed MCAP file; decompress it first (MCAP compresses "
                      "its chunks itself)");
    }
    reader_.emplace(std::move(reader).value());
    auto magic = reader_->ensure(mcap::kMagic.size() + mcap::kRecordPrefixBytes);
    if (!magic) {
      return Unexpected(magic.error());
    }
    const std::span<const std::byte> start = magic.value();
    if (start.size() < mcap::kMagic.size() ||
        !std::equal(mcap::kMagic.begin(), mcap::kMagic.end(), start.begin())) {
      return fail(ErrorCode::kFormat, path_ + ": not an MCAP file (no MCAP magic at its start)");
    }
    if (start.size() < mcap::kMagic.size() + 1 ||
        static_cast<Op>(start[mcap::kMagic.size()]) != Op::kHeader) {
      return fail(ErrorCode::kFormat, path_ + ": the MCAP magic is not followed by a header");
    }
    data_crc_ = crc32Update(0, start.first(mcap::kMagic.size()));
    reader_->consume(mcap::kMagic.size());
    return {};
  }

  void markTruncated(std::uint64_t offset, const std::string& where) {
    pass_.truncated = true;
    pass_.warning = path_ + ": the file is truncated (it ends at " + offsetText(offset) + ", " +
                    where + "); read the " + std::to_string(message_index_) + " messages before it";
  }

  /// Marks the record last read as used (its bytes go into the data section's CRC).
  void finishRecord() noexcept {
    if (!pending_.empty()) {
      data_crc_ = crc32Update(data_crc_, pending_);
      reader_->consume(pending_.size());
      pending_ = {};
    }
  }

  Unexpected<Error> malformed(const char* what, std::uint64_t offset) const {
    return fail(ErrorCode::kFormat,
                path_ + ": a malformed " + std::string(what) + " record at " + offsetText(offset));
  }

  /// One schema, channel or message record. @return true when it was a message, now in `out`.
  Result<bool> handle(Op op, std::span<const std::byte> content, std::uint64_t offset,
                      BagMessage& out) {
    switch (op) {
      case Op::kSchema:
        if (auto ok = schema(content, offset); !ok) {
          return Unexpected(ok.error());
        }
        return false;
      case Op::kChannel:
        if (auto ok = channel(content, offset); !ok) {
          return Unexpected(ok.error());
        }
        return false;
      case Op::kMessage:
        if (auto ok = message(content, offset, out); !ok) {
          return Unexpected(ok.error());
        }
        return true;
      default:
        return false;  // header, indexes, attachments, metadata, statistics: not needed
    }
  }

  Expected<void, Error> schema(std::span<const std::byte> content, std::uint64_t offset) {
    Cursor c(content);
    const std::uint16_t id = c.u16();
    const std::string_view name = c.string();
    (void)c.string();  // encoding: rosbag2 writes ros2msg; the type name is what raymap uses
    const std::span<const std::byte> data = c.bytes32();
    if (!c.ok() || id == 0) {
      return malformed("schema", offset);
    }
    Schema& s = schemas_[id];
    s.name = name;
    s.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
    return {};
  }

  Expected<void, Error> channel(std::span<const std::byte> content, std::uint64_t offset) {
    Cursor c(content);
    const std::uint16_t id = c.u16();
    const std::uint16_t schema_id = c.u16();
    const std::string_view topic = c.string();
    const std::string_view encoding = c.string();
    Cursor metadata(c.bytes32());
    std::string qos;
    while (c.ok() && metadata.ok() && metadata.left() > 0) {
      const std::string_view key = metadata.string();
      const std::string_view value = metadata.string();
      if (key == "offered_qos_profiles") {
        qos = value;
      }
    }
    if (!c.ok() || !metadata.ok()) {
      return malformed("channel", offset);
    }
    if (channel_topic_.count(id) != 0) {
      return {};  // repeated (chunks repeat channels; the summary lists them again)
    }
    BagTopic t;
    t.name = topic;
    t.serialization_format = encoding;
    t.offered_qos_profiles = std::move(qos);
    if (schema_id != 0) {
      const auto s = schemas_.find(schema_id);
      if (s == schemas_.end()) {
        return fail(ErrorCode::kFormat, path_ + ": channel " + std::to_string(id) + " ('" + t.name +
                                            "') at " + offsetText(offset) + " names schema " +
                                            std::to_string(schema_id) +
                                            ", which no schema record before it defines");
      }
      t.type = s->second.name;
      t.schema = s->second.data;
    }
    channel_topic_[id] = static_cast<std::uint32_t>(topics_.size());
    topics_.push_back(std::move(t));
    return {};
  }

  Expected<void, Error> message(std::span<const std::byte> content, std::uint64_t offset,
                                BagMessage& out) {
    Cursor c(content);
    const std::uint16_t channel_id = c.u16();
    (void)c.u32();  // sequence
    const std::uint64_t log_time = c.u64();
    (void)c.u64();  // publish time
    const std::span<const std::byte> data = c.rest();
    if (!c.ok()) {
      return fail(ErrorCode::kFormat, path_ + ": message " + std::to_string(message_index_) +
                                          " at " + offsetText(offset) + " is malformed");
    }
    const auto topic = channel_topic_.find(channel_id);
    if (topic == channel_topic_.end()) {
      return fail(ErrorCode::kFormat, path_ + ": message " + std::to_string(message_index_) +
                                          " at " + offsetText(offset) + " is on channel " +
                                          std::to_string(channel_id) +
                                          ", which no channel record before it defines");
    }
    out.topic = topic->second;
    out.log_time_ns = static_cast<std::int64_t>(log_time);
    out.index = message_index_++;
    out.data = data;
    pass_.messages = message_index_;
    return {};
  }

  /// Opens a chunk: decompressed and checked; its records are then read by nextInChunk().
  Expected<void, Error> chunk(std::span<const std::byte> content, std::uint64_t offset) {
    Cursor c(content);
    (void)c.u64();  // message start time
    (void)c.u64();  // message end time
    const std::uint64_t uncompressed_size = c.u64();
    const std::uint32_t uncompressed_crc = c.u32();
    const std::string compression(c.string());
    const std::span<const std::byte> compressed = c.bytes64();
    if (!c.ok()) {
      return malformed("chunk", offset);
    }
    const std::string where = "the chunk at " + offsetText(offset);
    if (uncompressed_size > kMaxChunkBytes) {
      return fail(ErrorCode::kFormat, path_ + ": " + where + " declares " +
                                          std::to_string(uncompressed_size) +
                                          " bytes uncompressed, more than the 1 GiB accepted");
    }
    std::span<const std::byte> records;
    if (compression.empty()) {
      if (compressed.size() != uncompressed_size) {
        return fail(ErrorCode::kCorrupt,
                    path_ + ": " + where + " is uncompressed but its sizes disagree");
      }
      records = compressed;
    } else {
      chunk_bytes_.resize(static_cast<std::size_t>(uncompressed_size));
      if (auto ok = decompress(compression, compressed, where); !ok) {
        return ok;
      }
      records = chunk_bytes_;
    }
    if (uncompressed_crc != 0 && crc32Update(0, records) != uncompressed_crc) {
      return fail(ErrorCode::kCorrupt,
                  path_ + ": " + where + " fails its CRC check: the file is corrupt");
    }
    in_chunk_.emplace(records);
    chunk_offset_ = offset;
    return {};
  }

  /// The next message of the open chunk. @return false when the chunk is done (closed).
  Result<bool> nextInChunk(BagMessage& out) {
    Cursor& inner = *in_chunk_;
    while (inner.left() > 0) {
      const auto op = static_cast<Op>(inner.u8());
      const std::span<const std::byte> record = inner.bytes64();
      if (!inner.ok()) {
        in_chunk_.reset();
        return fail(ErrorCode::kCorrupt, path_ + ": the chunk at " + offsetText(chunk_offset_) +
                                             " holds a record cut short: the file is corrupt");
      }
      auto got = handle(op, record, chunk_offset_, out);
      if (!got || got.value()) {
        return got;
      }
    }
    in_chunk_.reset();
    return false;
  }

  Expected<void, Error> decompress(const std::string& compression, std::span<const std::byte> in,
                                   const std::string& where) {
    if (compression == "zstd") {
      if (!zstd_) {
        zstd_.reset(ZSTD_createDCtx());
      }
      const std::size_t n = ZSTD_decompressDCtx(zstd_.get(), chunk_bytes_.data(),
                                                chunk_bytes_.size(), in.data(), in.size());
      if (ZSTD_isError(n) != 0u || n != chunk_bytes_.size()) {
        return fail(ErrorCode::kCorrupt,
                    path_ + ": " + where + " does not decompress (zstd: " +
                        (ZSTD_isError(n) != 0u ? ZSTD_getErrorName(n) : "wrong size") + ")");
      }
      return {};
    }
    if (compression == "lz4") {
      if (!lz4_) {
        LZ4F_dctx* context = nullptr;
        if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION)) != 0u) {
          return fail(ErrorCode::kIo, path_ + ": cannot create an LZ4 decompression context");
        }
        lz4_.reset(context);
      }
      LZ4F_resetDecompressionContext(lz4_.get());
      std::size_t in_at = 0;
      std::size_t out_at = 0;
      std::size_t status = 1;
      while (status != 0 && in_at < in.size()) {
        std::size_t out_size = chunk_bytes_.size() - out_at;
        std::size_t in_size = in.size() - in_at;
        status = LZ4F_decompress(lz4_.get(), chunk_bytes_.data() + out_at, &out_size,
                                 in.data() + in_at, &in_size, nullptr);
        if (LZ4F_isError(status) != 0u) {
          return fail(ErrorCode::kCorrupt, path_ + ": " + where + " does not decompress (lz4: " +
                                               LZ4F_getErrorName(status) + ")");
        }
        if (in_size == 0 && out_size == 0) {
          break;  // no progress: the output is full but the frame wants more
        }
        in_at += in_size;
        out_at += out_size;
      }
      if (status != 0 || out_at != chunk_bytes_.size()) {
        return fail(ErrorCode::kCorrupt, path_ + ": " + where +
                                             " does not decompress (lz4: the frame is cut short "
                                             "or its size disagrees with the chunk's)");
      }
      return {};
    }
    return fail(ErrorCode::kUnsupported, path_ + ": " + where + " uses compression '" +
                                             compression +
                                             "'; this raymap reads zstd, lz4 and uncompressed");
  }

  /// The topics from the summary section (schemas and channels). @return false when the file
  /// has no usable summary: then a pass over the data finds them.
  bool readSummary() {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path_.c_str(), "rb"),
                                                         &std::fclose);
    const std::uint64_t size = reader_->fileBytes();
    const std::uint64_t tail = mcap::kFooterRecordBytes + mcap::kMagic.size();
    if (!file || size < mcap::kMagic.size() + tail) {
      return false;
    }
    std::vector<std::byte> footer(tail);
    if (std::fseek(file.get(), static_cast<long>(size - tail), SEEK_SET) != 0 ||
        std::fread(footer.data(), 1, footer.size(), file.get()) != footer.size() ||
        static_cast<Op>(footer[0]) != Op::kFooter ||
        !std::equal(mcap::kMagic.begin(), mcap::kMagic.end(), footer.end() - 8)) {
      return false;
    }
    Cursor f(std::span<const std::byte>(footer).subspan(1));
    if (f.u64() != mcap::kFooterContentBytes) {
      return false;
    }
    const std::uint64_t summary_start = f.u64();
    (void)f.u64();  // summary offset start
    const std::uint32_t summary_crc = f.u32();
    const std::uint64_t footer_at = size - tail;
    if (summary_start == 0 || summary_start >= footer_at) {
      return false;
    }
    std::vector<std::byte> summary(static_cast<std::size_t>(footer_at - summary_start));
    if (std::fseek(file.get(), static_cast<long>(summary_start), SEEK_SET) != 0 ||
        std::fread(summary.data(), 1, summary.size(), file.get()) != summary.size()) {
      return false;
    }
    // The CRC covers the summary (and summary offset) sections and the footer up to the CRC.
    if (summary_crc != 0 &&
        crc32Update(crc32Update(0, summary), std::span<const std::byte>(footer).first(
                                                 mcap::kFooterRecordBytes - 4)) != summary_crc) {
      return false;
    }
    Cursor records(summary);
    BagMessage unused;
    while (records.left() > 0) {
      const auto op = static_cast<Op>(records.u8());
      const std::span<const std::byte> record = records.bytes64();
      if (!records.ok()) {
        return false;
      }
      if (op == Op::kSchema || op == Op::kChannel) {
        if (auto ok = handle(op, record, summary_start, unused); !ok) {
          return false;
        }
      } else if (op == Op::kStatistics) {
        readStatistics(record);
      }
    }
    return !topics_.empty();
  }

  /// The summary's Statistics record: message count, time span, messages per channel.
  void readStatistics(std::span<const std::byte> record) {
    Cursor c(record);
    BagStatistics stats;
    stats.messages = c.u64();
    (void)c.u16();  // schemas
    (void)c.u32();  // channels
    (void)c.u32();  // attachments
    (void)c.u32();  // metadata
    (void)c.u32();  // chunks
    stats.start_ns = static_cast<std::int64_t>(c.u64());
    stats.end_ns = static_cast<std::int64_t>(c.u64());
    Cursor counts(c.bytes32());
    std::map<std::uint16_t, std::uint64_t> per_channel;
    while (c.ok() && counts.ok() && counts.left() > 0) {
      const std::uint16_t channel = counts.u16();
      per_channel[channel] = counts.u64();
    }
    if (!c.ok() || !counts.ok()) {
      return;  // a malformed record: counted by reading instead
    }
    statistics_pending_ = std::move(per_channel);
    statistics_ = stats;
  }

  struct Schema {
    std::string name;
    std::string data;
  };
  struct ZstdFree {
    void operator()(ZSTD_DCtx* c) const noexcept { ZSTD_freeDCtx(c); }
  };
  struct Lz4Free {
    void operator()(LZ4F_dctx* c) const noexcept { LZ4F_freeDecompressionContext(c); }
  };

  std::string path_;
  std::optional<io::ByteReader> reader_;
  std::map<std::uint16_t, Schema> schemas_;
  std::map<std::uint16_t, std::uint32_t> channel_topic_;  // channel id -> index in topics_
  std::vector<BagTopic> topics_;
  std::vector<std::byte> chunk_bytes_;  // the current chunk, decompressed
  std::unique_ptr<ZSTD_DCtx, ZstdFree> zstd_;
  std::unique_ptr<LZ4F_dctx, Lz4Free> lz4_;
  std::uint32_t data_crc_ = 0;  // of every byte before the current record
  std::uint64_t message_index_ = 0;
  BagPass pass_;
  std::span<const std::byte> pending_;  // the record last read, still in reader_'s buffer
  std::optional<Cursor> in_chunk_;      // the open chunk's records
  std::uint64_t chunk_offset_ = 0;
  bool done_ = false;
  std::optional<BagStatistics> statistics_;                    // from the summary, if any
  std::map<std::uint16_t, std::uint64_t> statistics_pending_;  // its messages per channel
};

}  // namespace

Result<std::unique_ptr<BagReader>> openMcap(const std::string& path) {
  auto reader = std::make_unique<McapBagReader>(path);
  if (auto ok = reader->open(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace raymap::bag
