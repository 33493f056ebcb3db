// SPDX-License-Identifier: BSD-3-Clause
// The MCAP reader: one sequential pass over the data section per forEach(), chunks decompressed
// (zstd, lz4) into one reused buffer and checked against their CRC; the summary section, when
// the file has one, to know the topics up front and where the data and its chunks are, so that
// a damaged record in a complete file is reported as damage (and, when asked, skipped to the next
// indexed chunk), never as a file cut off.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lz4frame.h>
#include <zstd.h>

#include "src/bag/bag_reader.hpp"
#include "src/bag/mcap_records.hpp"
#include "src/bag/mcap_summary.hpp"
#include "src/core/crc32.hpp"
#include "src/io/byte_reader.hpp"

namespace raymap::bag {
namespace {

using mcap::Cursor;
using mcap::Op;

/// A chunk may not claim more than this uncompressed: a corrupt size must not exhaust memory.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

std::string offsetText(std::uint64_t offset) {
  char text[48];
  std::snprintf(text, sizeof(text), "offset %" PRIu64, offset);
  return text;
}

class McapBagReader final : public BagReader {
 public:
  McapBagReader(std::string path, const BagReadOptions& options)
      : path_(std::move(path)), options_(options) {}

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

  std::vector<std::string> openWarnings() const override { return open_warnings_; }

  /// Checks the magic and the header, then learns the topics from the summary section (or, in a
  /// file without one, from a pass over the data).
  Expected<void, Error> open() {
    if (auto first = rewind(); !first) {
      return first;
    }
    end_ = mcap::readFileEnd(path_, reader_->fileBytes());
    if (end_.state == mcap::FileEnd::State::kSummary && !readSummary()) {
      end_.state = mcap::FileEnd::State::kDamaged;
      end_.problem = "its summary section (offset " + std::to_string(end_.summary_start) +
                     ") holds a malformed record";
      end_.chunks.clear();
    }
    if (end_.state == mcap::FileEnd::State::kDamaged) {
      // Nothing is lost yet: the data section says everything. A file cut off inside it fails
      // (or is reported) when the scan reaches the cut.
      open_warnings_.push_back(path_ + ": " + end_.problem +
                               "; its summary is not used and its records are read in order");
      schemas_.clear();
      channel_topic_.clear();
      topics_.clear();
      statistics_.reset();
    }
    if (end_.state == mcap::FileEnd::State::kSummary && !topics_.empty()) {
      return rewind();
    }
    // No summary, or one without channels: the topics are learnt from a pass over the data.
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
    next_chunk_ = 0;
    skipped_bytes_ = false;
    pass_finished_ = false;
    return startPass();
  }

  Result<bool> next(BagMessage& out) override {
    while (!done_) {
      if (in_chunk_) {
        auto got = nextInChunk(out);
        if (!got || got.value()) {
          return got;
        }
        continue;  // the chunk is done (or skipped)
      }
      finishRecord();
      auto got = nextRecord(out);
      if (!got || got.value()) {
        return got;
      }
    }
    finishPass();
    return false;
  }

 private:
  /// Reads the record at the reader's position. @return true when it was a message, now in
  /// `out`.
  Result<bool> nextRecord(BagMessage& out) {
    const std::uint64_t offset = reader_->position();
    if (end_.data_end != 0 && offset >= end_.data_end) {
      done_ = true;  // the summary or the footer: the data section is over
      return false;
    }
    auto prefix = reader_->ensure(mcap::kRecordPrefixBytes);
    if (!prefix) {
      return Unexpected(prefix.error());
    }
    if (prefix.value().size() < mcap::kRecordPrefixBytes) {
      return cutOff(offset, prefix.value().empty() ? "where the next record would begin"
                                                   : "inside a record's opcode and length");
    }
    Cursor head(prefix.value());
    const auto op = static_cast<Op>(head.u8());
    const std::uint64_t length = head.u64();
    auto placed = checkPlace(op, length, offset);
    if (!placed || !placed.value()) {
      return placed;  // the error, or false: the pass moved on
    }
    auto record = reader_->ensure(mcap::kRecordPrefixBytes + static_cast<std::size_t>(length));
    if (!record) {
      return Unexpected(record.error());
    }
    if (record.value().size() < mcap::kRecordPrefixBytes + length) {
      return cutOff(offset, "inside a record");
    }
    pending_ = record.value().first(mcap::kRecordPrefixBytes + length);
    const std::span<const std::byte> content = pending_.subspan(mcap::kRecordPrefixBytes);
    if (op == Op::kDataEnd) {
      Cursor c(content);
      const std::uint32_t stored = c.u32();
      // Bytes skipped as damaged are not in the running CRC: a mismatch then says nothing new.
      if (stored != 0 && stored != data_crc_ && !skipped_bytes_) {
        const std::string what = "the data section's CRC does not match (" + offsetText(offset) +
                                 "): a record outside the chunks was changed";
        if (!options_.skip_damaged) {
          return fail(ErrorCode::kCorrupt, path_ + ": " + what + ": the file is corrupt");
        }
        pass_.damage.push_back(path_ + ": " + what + " (every chunk passed its checks)");
      }
      done_ = true;
    } else if (op == Op::kFooter) {
      done_ = true;  // a file without a DataEnd record
    } else if (op == Op::kChunk) {
      if (auto ok = chunk(content, offset); !ok) {
        if (ok.error().code == ErrorCode::kUnsupported) {
          return Unexpected(ok.error());  // not damage: every chunk would fail alike
        }
        // The chunk's length was checked above: the next record starts right after it.
        if (auto skipped = damaged(offset, withoutPath(ok.error()), offset + pending_.size());
            !skipped) {
          return Unexpected(skipped.error());
        }
      }
    } else {
      return handle(op, content, offset, out);
    }
    return false;
  }

  /// An error's message without the leading "PATH: " (damaged() adds it again).
  std::string withoutPath(const Error& error) const {
    const std::string prefix = path_ + ": ";
    return error.message.rfind(prefix, 0) == 0 ? error.message.substr(prefix.size())
                                               : error.message;
  }

  /// Checks that the record at `offset` fits the file: inside the data section of a complete
  /// file (a record running past it is damage, not a cut), over no chunk the summary indexes,
  /// and, for a chunk, where and as long as its index says. @return false when the pass moved
  /// on (damage skipped, or the file cut off and read up to there).
  Result<bool> checkPlace(Op op, std::uint64_t length, std::uint64_t offset) {
    const std::uint64_t begin = offset + mcap::kRecordPrefixBytes;
    const std::uint64_t bound = end_.data_end != 0 ? end_.data_end : reader_->fileBytes();
    const std::string record = "the record at " + offsetText(offset) + " (opcode " +
                               std::to_string(static_cast<unsigned>(op)) + ")";
    if (length > bound - std::min(bound, begin)) {
      if (end_.data_end == 0) {
        return cutOff(offset, "inside a record that declares " + std::to_string(length) + " bytes");
      }
      return damagedHere(offset, record + " declares " + std::to_string(length) +
                                     " bytes, past the end of the data section at " +
                                     offsetText(end_.data_end) +
                                     ": its length is corrupt (the file itself is complete)");
    }
    const std::vector<mcap::IndexedChunk>& chunks = end_.chunks;
    while (next_chunk_ < chunks.size() && chunks[next_chunk_].offset < offset) {
      ++next_chunk_;  // passed by a skip
    }
    if (next_chunk_ == chunks.size()) {
      if (op != Op::kChunk || chunks.empty()) {
        return true;
      }
      return damagedHere(offset, record + " is a chunk the summary's chunk index does not list");
    }
    const mcap::IndexedChunk& indexed = chunks[next_chunk_];
    const std::uint64_t whole = mcap::kRecordPrefixBytes + length;
    if (op == Op::kChunk && indexed.offset == offset && indexed.length == whole) {
      ++next_chunk_;
      return true;
    }
    if (op != Op::kChunk && indexed.offset >= offset + whole) {
      return true;
    }
    return damagedHere(offset, record + " declares " + std::to_string(length) +
                                   " bytes, but the summary's chunk index has a chunk of " +
                                   std::to_string(indexed.length) + " bytes at " +
                                   offsetText(indexed.offset) + ": its length is corrupt");
  }

  /// Damage at the record at `offset` whose own length cannot be trusted: resumes at the next
  /// indexed chunk. @return false (moved on) or the error.
  Result<bool> damagedHere(std::uint64_t offset, const std::string& what) {
    if (auto ok = damaged(offset, what, 0); !ok) {
      return Unexpected(ok.error());
    }
    return false;
  }

  /// Damage at the record at `offset` (the reader's position): an error naming the file and
  /// what is wrong, or, with skip_damaged, a note and a jump to `resume_at` (0: the next chunk
  /// the summary indexes after `offset`; none: the end of the pass).
  Expected<void, Error> damaged(std::uint64_t offset, const std::string& what,
                                std::uint64_t resume_at) {
    if (!options_.skip_damaged) {
      return fail(ErrorCode::kCorrupt, path_ + ": " + what);
    }
    if (resume_at == 0) {
      for (const mcap::IndexedChunk& c : end_.chunks) {
        if (c.offset > offset) {
          resume_at = c.offset;
          break;
        }
      }
    }
    pending_ = {};
    in_chunk_.reset();
    skipped_bytes_ = true;
    const std::uint64_t end = end_.data_end != 0 ? end_.data_end : reader_->fileBytes();
    if (resume_at == 0 || resume_at > end) {
      pass_.damage.push_back(path_ + ": " + what + "; skipped the rest of the data, " +
                             std::to_string(end - std::min(end, offset)) + " bytes from " +
                             offsetText(offset));
      done_ = true;
      return {};
    }
    pass_.damage.push_back(path_ + ": " + what + "; skipped " + std::to_string(resume_at - offset) +
                           " bytes from " + offsetText(offset) + " to " + offsetText(resume_at));
    auto skipped = reader_->skip(resume_at - reader_->position());
    if (!skipped) {
      return Unexpected(skipped.error());
    }
    return {};
  }

  /// The file ends at `offset`, `where`: an error, or with skip_damaged the end of the pass.
  Result<bool> cutOff(std::uint64_t offset, const std::string& where) {
    const std::string what = "the file is cut off (truncated): it ends " + where + " at " +
                             offsetText(offset) + ", after " + std::to_string(message_index_) +
                             " messages";
    if (!options_.skip_damaged) {
      return fail(ErrorCode::kTruncated, path_ + ": " + what);
    }
    pass_.truncated = true;
    pass_.damage.push_back(path_ + ": " + what + "; the rest is missing");
    done_ = true;
    return false;
  }

  /// Once per pass, after its last message: what a skip cost, when the summary counted it.
  void finishPass() {
    pass_.messages = message_index_;
    if (pass_finished_) {
      return;
    }
    pass_finished_ = true;
    if (!pass_.damage.empty() && statistics_ && statistics_->messages > message_index_) {
      pass_.damage.push_back(path_ + ": " + std::to_string(message_index_) + " of the " +
                             std::to_string(statistics_->messages) +
                             " messages its summary counts were read");
    }
  }

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
    data_crc_ = crc32(0, start.first(mcap::kMagic.size()));
    reader_->consume(mcap::kMagic.size());
    return {};
  }

  /// Marks the record last read as used (its bytes go into the data section's CRC).
  void finishRecord() noexcept {
    if (!pending_.empty()) {
      data_crc_ = crc32(data_crc_, pending_);
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
    if (uncompressed_crc != 0 && crc32(0, records) != uncompressed_crc) {
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
        if (auto skipped = damaged(chunk_offset_,
                                   "the chunk at " + offsetText(chunk_offset_) +
                                       " holds a record cut short: the file is corrupt",
                                   chunk_offset_ + pending_.size());
            !skipped) {
          return Unexpected(skipped.error());
        }
        return false;
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

  /// The topics (schemas and channels) and statistics from the summary section that
  /// readFileEnd() checked. @return false when a record in it is malformed.
  bool readSummary() {
    Cursor records(end_.summary);
    BagMessage unused;
    while (records.left() > 0) {
      const auto op = static_cast<Op>(records.u8());
      const std::span<const std::byte> record = records.bytes64();
      if (!records.ok()) {
        return false;
      }
      if (op == Op::kSchema || op == Op::kChannel) {
        if (auto ok = handle(op, record, end_.summary_start, unused); !ok) {
          return false;
        }
      } else if (op == Op::kStatistics) {
        readStatistics(record);
      }
    }
    return true;
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
  BagReadOptions options_;
  mcap::FileEnd end_;                       // the footer and summary, as checked at open
  std::vector<std::string> open_warnings_;  // a damaged end or summary (read in order instead)
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
  std::size_t next_chunk_ = 0;  // the first chunk of end_.chunks not yet reached
  bool skipped_bytes_ = false;  // damage skipped: the data section's CRC cannot match
  bool pass_finished_ = false;
  std::optional<BagStatistics> statistics_;                    // from the summary, if any
  std::map<std::uint16_t, std::uint64_t> statistics_pending_;  // its messages per channel
};

}  // namespace

Result<std::unique_ptr<BagReader>> openMcap(const std::string& path,
                                            const BagReadOptions& options) {
  auto reader = std::make_unique<McapBagReader>(path, options);
  if (auto ok = reader->open(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace raymap::bag
