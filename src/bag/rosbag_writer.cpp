// SPDX-License-Identifier: BSD-3-Clause
// RosbagWriter: MCAP records built in memory per chunk and appended to the file; the summary
// (schemas, channels, statistics, chunk indexes) and the footer at close().
#include "src/bag/rosbag_writer.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <vector>

#include <lz4frame.h>
#include <unistd.h>
#include <zstd.h>

#include "platform/errno_text.hpp"
#include "src/bag/mcap_records.hpp"
#include "src/bag/ros2_definitions.hpp"
#include "src/core/crc32.hpp"

namespace raymap::bag {
namespace {

namespace fs = std::filesystem;
using mcap::Builder;
using mcap::Op;

constexpr int kZstdLevel = 1;  // fast enough to keep up with a lidar on one core

struct Topic {
  std::string name;
  std::string type;
  std::string qos;
  std::string definition;  // the ros2msg schema text
  std::uint64_t messages = 0;
};

struct ChunkIndex {
  std::uint64_t start_time = 0;
  std::uint64_t end_time = 0;
  std::uint64_t offset = 0;                              // of the chunk record in the file
  std::uint64_t length = 0;                              // of the chunk record
  std::map<std::uint16_t, std::uint64_t> index_offsets;  // channel -> its MessageIndex record
  std::uint64_t index_length = 0;
  std::uint64_t compressed = 0;
  std::uint64_t uncompressed = 0;
};

class McapRosbagWriter final : public RosbagWriter {
 public:
  McapRosbagWriter(std::string dir, std::string partial, const RosbagWriterOptions& options)
      : dir_(std::move(dir)), partial_(std::move(partial)), options_(options) {}
  ~McapRosbagWriter() override {
    if (file_ != nullptr) {
      std::fclose(file_);
    }
  }

  Expected<void, Error> open() {
    std::error_code ec;
    if (!fs::create_directory(partial_, ec)) {
      return fail(ErrorCode::kIo, partial_ + ": cannot create the directory: " +
                                      (ec ? ec.message() : "it exists (another recording?)"));
    }
    file_name_ = fs::path(dir_).filename().string() + "_0.mcap";
    file_path_ = (fs::path(partial_) / file_name_).string();
    file_ = std::fopen(file_path_.c_str(), "wb");
    if (file_ == nullptr) {
      return fail(ErrorCode::kIo, file_path_ + ": cannot create: " + platform::errnoText(errno));
    }
    Builder b;
    b.raw(mcap::kMagic);
    const std::size_t header = b.beginRecord(Op::kHeader);
    b.string("ros2");
    b.string("raymap");
    b.endRecord(header);
    return append(b.bytes(), true);
  }

  Result<std::uint32_t> addTopic(const std::string& topic, const std::string& type,
                                 const std::string& qos) override {
    std::string definition = ros2MessageDefinition(type);
    if (definition.empty()) {
      return fail(ErrorCode::kUnsupported, topic + ": raymap has no message definition for " +
                                               type + ", so it cannot write it to a bag");
    }
    const auto id = static_cast<std::uint16_t>(topics_.size() + 1);  // 0 means "no schema"
    topics_.push_back(Topic{topic, type, qos, std::move(definition), 0});
    Builder b;
    schemaRecord(b, id);
    channelRecord(b, id);
    if (auto ok = append(b.bytes(), true); !ok) {
      return Unexpected(ok.error());
    }
    return std::uint32_t{id};
  }

  Expected<void, Error> write(std::uint32_t topic, std::int64_t log_time_ns,
                              std::int64_t publish_time_ns,
                              std::span<const std::byte> cdr) override {
    if (topic == 0 || topic > topics_.size()) {
      return fail(ErrorCode::kInvalidArgument, "bag write: no topic " + std::to_string(topic));
    }
    const auto channel = static_cast<std::uint16_t>(topic);
    const auto log_time = static_cast<std::uint64_t>(log_time_ns);
    if (chunk_messages_ == 0) {
      chunk_start_ = log_time;
      chunk_end_ = log_time;
    }
    chunk_start_ = std::min(chunk_start_, log_time);
    chunk_end_ = std::max(chunk_end_, log_time);
    message_index_[channel].emplace_back(log_time, chunk_.size());
    const std::size_t record = chunk_.beginRecord(Op::kMessage);
    chunk_.u16(channel);
    chunk_.u32(static_cast<std::uint32_t>(topics_[topic - 1].messages));
    chunk_.u64(log_time);
    chunk_.u64(static_cast<std::uint64_t>(publish_time_ns));
    chunk_.raw(cdr);
    chunk_.endRecord(record);
    ++chunk_messages_;
    ++topics_[topic - 1].messages;
    ++messages_;
    bytes_ += cdr.size();
    if (messages_ == 1 || log_time < start_time_) {
      start_time_ = log_time;
    }
    end_time_ = std::max(end_time_, log_time);
    if (chunk_.size() >= options_.chunk_bytes) {
      return flushChunk();
    }
    return {};
  }

  Expected<void, Error> close() override {
    if (auto ok = flushChunk(); !ok) {
      return ok;
    }
    Builder b;
    const std::size_t data_end = b.beginRecord(Op::kDataEnd);
    b.u32(data_crc_);
    b.endRecord(data_end);
    if (auto ok = append(b.bytes(), false); !ok) {
      return ok;
    }
    const std::uint64_t summary_start = offset_;
    Builder s;
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      schemaRecord(s, static_cast<std::uint16_t>(i + 1));
    }
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      channelRecord(s, static_cast<std::uint16_t>(i + 1));
    }
    statisticsRecord(s);
    for (const ChunkIndex& c : chunks_) {
      chunkIndexRecord(s, c);
    }
    // The summary CRC covers the summary and the footer up to the CRC itself (its opcode and
    // length included), so the footer's length is written before, not patched after.
    s.u8(static_cast<std::uint8_t>(Op::kFooter));
    s.u64(mcap::kFooterContentBytes);
    s.u64(summary_start);
    s.u64(0);  // no summary offset section
    s.u32(crc32(0, s.bytes()));
    s.raw(mcap::kMagic);
    if (auto ok = append(s.bytes(), false); !ok) {
      return ok;
    }
    if (std::fflush(file_) != 0 || ::fsync(fileno(file_)) != 0 || std::fclose(file_) != 0) {
      file_ = nullptr;
      return fail(ErrorCode::kIo, file_path_ + ": cannot write: " + platform::errnoText(errno));
    }
    file_ = nullptr;
    if (auto ok = writeMetadata(); !ok) {
      return ok;
    }
    std::error_code ec;
    if (fs::exists(dir_, ec)) {
      return fail(ErrorCode::kIo,
                  dir_ + " appeared while recording: the bag is left in " + partial_);
    }
    fs::rename(partial_, dir_, ec);
    if (ec) {
      return fail(ErrorCode::kIo,
                  "cannot rename " + partial_ + " to " + dir_ + ": " + ec.message());
    }
    return {};
  }

  const std::string& partialPath() const noexcept override { return partial_; }
  std::uint64_t messages() const noexcept override { return messages_; }
  std::uint64_t bytes() const noexcept override { return bytes_; }

 private:
  /// Writes `bytes` at the end of the file; `data` bytes count into the data section's CRC.
  Expected<void, Error> append(std::span<const std::byte> bytes, bool data) {
    if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
      return fail(ErrorCode::kIo, file_path_ + ": cannot write: " + platform::errnoText(errno));
    }
    if (data) {
      data_crc_ = crc32(data_crc_, bytes);
    }
    offset_ += bytes.size();
    return {};
  }

  void schemaRecord(Builder& b, std::uint16_t id) const {
    const Topic& t = topics_[id - 1u];
    const std::size_t r = b.beginRecord(Op::kSchema);
    b.u16(id);
    b.string(t.type);
    b.string("ros2msg");
    b.string(t.definition);  // bytes with a uint32 length, like a string
    b.endRecord(r);
  }

  void channelRecord(Builder& b, std::uint16_t id) const {
    const Topic& t = topics_[id - 1u];
    const std::size_t r = b.beginRecord(Op::kChannel);
    b.u16(id);
    b.u16(id);  // one schema per channel
    b.string(t.name);
    b.string("cdr");
    const std::size_t map_length = b.size();
    b.u32(0);
    b.string("offered_qos_profiles");
    b.string(t.qos);
    b.patch32(map_length, static_cast<std::uint32_t>(b.size() - map_length - 4));
    b.endRecord(r);
  }

  void statisticsRecord(Builder& b) const {
    const std::size_t r = b.beginRecord(Op::kStatistics);
    b.u64(messages_);
    b.u16(static_cast<std::uint16_t>(topics_.size()));
    b.u32(static_cast<std::uint32_t>(topics_.size()));
    b.u32(0);  // attachments
    b.u32(0);  // metadata
    b.u32(static_cast<std::uint32_t>(chunks_.size()));
    b.u64(messages_ > 0 ? start_time_ : 0);
    b.u64(messages_ > 0 ? end_time_ : 0);
    b.u32(static_cast<std::uint32_t>(topics_.size() * 10));
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      b.u16(static_cast<std::uint16_t>(i + 1));
      b.u64(topics_[i].messages);
    }
    b.endRecord(r);
  }

  void chunkIndexRecord(Builder& b, const ChunkIndex& c) const {
    const std::size_t r = b.beginRecord(Op::kChunkIndex);
    b.u64(c.start_time);
    b.u64(c.end_time);
    b.u64(c.offset);
    b.u64(c.length);
    b.u32(static_cast<std::uint32_t>(c.index_offsets.size() * 10));
    for (const auto& [channel, offset] : c.index_offsets) {
      b.u16(channel);
      b.u64(offset);
    }
    b.u64(c.index_length);
    b.string(compressionName());
    b.u64(c.compressed);
    b.u64(c.uncompressed);
    b.endRecord(r);
  }

  static const char* compressionName(ChunkCompression c) {
    return c == ChunkCompression::kZstd ? "zstd" : c == ChunkCompression::kLz4 ? "lz4" : "";
  }
  const char* compressionName() const { return compressionName(options_.compression); }

  Expected<void, Error> flushChunk() {
    if (chunk_messages_ == 0) {
      return {};
    }
    const std::span<const std::byte> records = chunk_.bytes();
    std::span<const std::byte> stored = records;
    if (options_.compression == ChunkCompression::kZstd) {
      compressed_.resize(ZSTD_compressBound(records.size()));
      const std::size_t n = ZSTD_compress(compressed_.data(), compressed_.size(), records.data(),
                                          records.size(), kZstdLevel);
      if (ZSTD_isError(n) != 0u) {
        return fail(ErrorCode::kIo, file_path_ + ": zstd: " + ZSTD_getErrorName(n));
      }
      stored = std::span<const std::byte>(compressed_).first(n);
    } else if (options_.compression == ChunkCompression::kLz4) {
      compressed_.resize(LZ4F_compressFrameBound(records.size(), nullptr));
      const std::size_t n = LZ4F_compressFrame(compressed_.data(), compressed_.size(),
                                               records.data(), records.size(), nullptr);
      if (LZ4F_isError(n) != 0u) {
        return fail(ErrorCode::kIo, file_path_ + ": lz4: " + LZ4F_getErrorName(n));
      }
      stored = std::span<const std::byte>(compressed_).first(n);
    }
    ChunkIndex index;
    index.start_time = chunk_start_;
    index.end_time = chunk_end_;
    index.offset = offset_;
    index.compressed = stored.size();
    index.uncompressed = records.size();
    Builder b;
    const std::size_t r = b.beginRecord(Op::kChunk);
    b.u64(chunk_start_);
    b.u64(chunk_end_);
    b.u64(records.size());
    b.u32(crc32(0, records));
    b.string(compressionName());
    b.u64(stored.size());
    b.raw(stored);
    b.endRecord(r);
    index.length = b.size();
    for (const auto& [channel, entries] : message_index_) {
      index.index_offsets[channel] = offset_ + b.size();
      const std::size_t m = b.beginRecord(Op::kMessageIndex);
      b.u16(channel);
      b.u32(static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [time, offset] : entries) {
        b.u64(time);
        b.u64(offset);
      }
      b.endRecord(m);
    }
    index.index_length = b.size() - index.length;
    if (auto ok = append(b.bytes(), true); !ok) {
      return ok;
    }
    chunks_.push_back(std::move(index));
    chunk_.clear();
    message_index_.clear();
    chunk_messages_ = 0;
    return {};
  }

  Expected<void, Error> writeMetadata() const {
    // The bag's span, and its one file's (the same).
    const std::string start = std::to_string(messages_ > 0 ? start_time_ : 0);
    const std::string duration = std::to_string(messages_ > 0 ? end_time_ - start_time_ : 0);
    std::string yaml = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n";
    yaml += "  duration:\n    nanoseconds: " + duration + "\n  starting_time:\n" +
            "    nanoseconds_since_epoch: " + start +
            "\n  message_count: " + std::to_string(messages_) + "\n";
    yaml += "  topics_with_message_count:\n";
    for (const Topic& t : topics_) {
      std::string qos = "\"";
      for (const char c : t.qos) {
        qos += c == '\n' ? std::string("\\n") : c == '"' ? std::string("\\\"") : std::string(1, c);
      }
      qos += "\"";
      yaml += "    - topic_metadata:\n        name: " + t.name + "\n        type: " + t.type +
              "\n        serialization_format: cdr\n        offered_qos_profiles: " + qos +
              "\n      message_count: " + std::to_string(t.messages) + "\n";
    }
    yaml += "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - " +
            file_name_ + "\n  files:\n    - path: " + file_name_ +
            "\n      starting_time:\n        nanoseconds_since_epoch: " + start +
            "\n      duration:\n        nanoseconds: " + duration +
            "\n      message_count: " + std::to_string(messages_) + "\n";
    const std::string path = (fs::path(partial_) / "metadata.yaml").string();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
      return fail(ErrorCode::kIo, path + ": cannot create: " + platform::errnoText(errno));
    }
    const bool written = std::fwrite(yaml.data(), 1, yaml.size(), f) == yaml.size();
    if (std::fclose(f) != 0 || !written) {
      return fail(ErrorCode::kIo, path + ": cannot write: " + platform::errnoText(errno));
    }
    return {};
  }

  std::string dir_;
  std::string partial_;
  RosbagWriterOptions options_;
  std::string file_name_;
  std::string file_path_;
  std::FILE* file_ = nullptr;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  std::vector<Topic> topics_;  // channel id = index + 1
  Builder chunk_;              // the open chunk's records, uncompressed
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> message_index_;
  std::uint64_t chunk_messages_ = 0;
  std::uint64_t chunk_start_ = 0;
  std::uint64_t chunk_end_ = 0;
  std::vector<std::byte> compressed_;
  std::vector<ChunkIndex> chunks_;
  std::uint64_t messages_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint64_t start_time_ = 0;
  std::uint64_t end_time_ = 0;
};

}  // namespace

Result<ChunkCompression> parseChunkCompression(const std::string& text) {
  if (text == "none") {
    return ChunkCompression::kNone;
  }
  if (text == "zstd") {
    return ChunkCompression::kZstd;
  }
  if (text == "lz4") {
    return ChunkCompression::kLz4;
  }
  return fail(ErrorCode::kInvalidArgument,
              "compression '" + text + "': expected none, zstd or lz4");
}

Result<std::unique_ptr<RosbagWriter>> RosbagWriter::create(const std::string& dir,
                                                           const RosbagWriterOptions& options) {
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    return fail(ErrorCode::kInvalidArgument, dir + " exists: a bag is never overwritten");
  }
  std::string trimmed = dir;
  while (trimmed.size() > 1 && trimmed.back() == '/') {
    trimmed.pop_back();
  }
  auto writer = std::make_unique<McapRosbagWriter>(trimmed, trimmed + ".partial", options);
  if (auto ok = writer->open(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<RosbagWriter>(std::move(writer));
}

std::string offeredQosYaml(bool reliable, bool transient_local, int depth) {
  // rmw's enums: history 1 = keep last; reliability 1 = reliable, 2 = best effort; durability
  // 1 = transient local, 2 = volatile; liveliness 1 = automatic. Durations "infinite".
  const std::string infinite = "\n    sec: 2147483647\n    nsec: 4294967295";
  return "- history: 1\n  depth: " + std::to_string(depth) +
         "\n  reliability: " + (reliable ? "1" : "2") +
         "\n  durability: " + (transient_local ? "1" : "2") + "\n  deadline:" + infinite +
         "\n  lifespan:" + infinite + "\n  liveliness: 1\n  liveliness_lease_duration:" + infinite +
         "\n  avoid_ros_namespace_conventions: false\n";
}

}  // namespace raymap::bag
