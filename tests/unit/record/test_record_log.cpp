// SPDX-License-Identifier: BSD-3-Clause
// Record logs: exact round trips, crash behaviour (.partial, SIGKILL, cut-off files) and clean
// errors for damaged, foreign and newer files. The file bytes are checked against the layout of
// docs/record-format.md with a byte walker written out here and the CRC-32 of
// tests/support/file_bytes, not the library's.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include "src/record/record_log.hpp"
#include "src/record/record_log_reader.hpp"
#include "src/record/record_log_writer.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::record {
namespace {

using test::appendLe;
using test::Bytes;
using test::crc32;
using test::getLe;
using test::putLe;
using test::readFileBytes;
using test::TempDir;
using test::writeFileBytes;

// ---- file bytes, independent of the library (docs/record-format.md) ----

constexpr std::size_t kHeader = 32;      // file header
constexpr std::size_t kRecordHead = 12;  // kind, length, crc
constexpr std::size_t kPrefix = 28;      // MESSAGE: topic id and three timestamps
constexpr std::uint32_t kTopic = 1;
constexpr std::uint32_t kMessage = 2;
constexpr std::uint32_t kEnd = 3;

struct RecordAt {
  std::size_t offset;
  std::uint32_t kind;
  std::uint32_t length;
};

/// Every complete record of a well-formed file, in order.
std::vector<RecordAt> records(const Bytes& bytes) {
  std::vector<RecordAt> out;
  std::size_t at = kHeader;
  while (at + kRecordHead <= bytes.size()) {
    const auto kind = static_cast<std::uint32_t>(getLe(bytes, at, 4));
    const auto length = static_cast<std::uint32_t>(getLe(bytes, at + 4, 4));
    if (at + kRecordHead + length > bytes.size()) {
      break;
    }
    out.push_back({at, kind, length});
    at += kRecordHead + length;
  }
  return out;
}

/// Recomputes the CRC of the record at `at` after its bytes were edited.
void fixRecordCrc(Bytes& bytes, std::size_t at) {
  const auto length = static_cast<std::size_t>(getLe(bytes, at + 4, 4));
  Bytes covered(bytes.begin() + static_cast<std::ptrdiff_t>(at),
                bytes.begin() + static_cast<std::ptrdiff_t>(at + 8));
  covered.insert(covered.end(), bytes.begin() + static_cast<std::ptrdiff_t>(at + kRecordHead),
                 bytes.begin() + static_cast<std::ptrdiff_t>(at + kRecordHead + length));
  putLe(bytes, at + 8, crc32(covered.data(), covered.size()), 4);
}

/// A record with a correct checksum.
Bytes forgeRecord(std::uint32_t kind, const Bytes& payload) {
  Bytes record;
  appendLe(record, kind, 4);
  appendLe(record, payload.size(), 4);
  appendLe(record, 0, 4);
  record.insert(record.end(), payload.begin(), payload.end());
  fixRecordCrc(record, 0);
  return record;
}

void insertAt(Bytes& bytes, std::size_t at, const Bytes& what) {
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), what.begin(), what.end());
}

// ---- messages ----

std::vector<std::byte> randomBytes(std::size_t size, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::byte> out(size);
  for (auto& b : out) {
    b = static_cast<std::byte>(rng() & 0xFFu);
  }
  return out;
}

struct Sample {
  std::uint32_t topic_id = 0;
  std::int64_t receive_unix_ns = 0;
  std::int64_t receive_monotonic_ns = 0;
  std::int64_t source_timestamp_ns = 0;
  std::vector<std::byte> cdr;
  bool operator==(const Sample&) const = default;
};

Sample sample(std::uint32_t topic, std::int64_t i, std::size_t size) {
  return Sample{topic, 1'700'000'000'000'000'000 + i * 1000, 5'000'000 + i * 7, -3 + i * 11,
                randomBytes(size, static_cast<unsigned>(i) + 1)};
}

void writeSamples(RecordLogWriter& writer, const std::vector<Sample>& samples) {
  for (const Sample& s : samples) {
    auto written = writer.write(s.topic_id, s.receive_unix_ns, s.receive_monotonic_ns,
                                s.source_timestamp_ns, s.cdr);
    ASSERT_TRUE(written) << written.error().message;
  }
}

/// Reads messages until the end; an error fails the test and stops.
std::vector<Sample> readAll(RecordLogReader& reader) {
  std::vector<Sample> out;
  for (;;) {
    auto next = reader.next();
    if (!next) {
      ADD_FAILURE() << next.error().message;
      return out;
    }
    if (!*next) {
      return out;
    }
    const LogMessage& m = **next;
    out.push_back(Sample{m.topic_id, m.receive_unix_ns, m.receive_monotonic_ns,
                         m.source_timestamp_ns,
                         std::vector<std::byte>(m.cdr.begin(), m.cdr.end())});
  }
}

/// Reads until an error and returns it (fails the test when the log reads cleanly).
Error firstError(RecordLogReader& reader, std::uint64_t* messages_before = nullptr) {
  std::uint64_t read = 0;
  for (;;) {
    auto next = reader.next();
    if (!next) {
      if (messages_before != nullptr) {
        *messages_before = read;
      }
      return next.error();
    }
    if (!*next) {
      ADD_FAILURE() << "the log read to its end without an error";
      return Error{};
    }
    ++read;
  }
}

std::unique_ptr<RecordLogReader> openOrFail(const std::string& path) {
  auto reader = RecordLogReader::open(path);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return nullptr;
  }
  return std::move(*reader);
}

const LogTopic kPoints{0, "rt/points", "sensor_msgs::msg::dds_::PointCloud2_",
                       LogReliability::kBestEffort, LogDurability::kVolatile};
const LogTopic kTfStatic{1, "rt/tf_static", "tf2_msgs::msg::dds_::TFMessage_",
                         LogReliability::kReliable, LogDurability::kTransientLocal};

/// Writes kPoints and kTfStatic and `samples`; closes the log when `close` is set, else leaves
/// the .partial file (returns its path).
std::string recordLog(const std::string& path, const std::vector<Sample>& samples, bool close) {
  auto writer = RecordLogWriter::create(path);
  EXPECT_TRUE(writer) << writer.error().message;
  if (!writer) {
    return path;
  }
  for (const LogTopic& t : {kPoints, kTfStatic}) {
    auto id = (*writer)->addTopic(t.name, t.type, t.reliability, t.durability);
    EXPECT_TRUE(id && *id == t.id);
  }
  writeSamples(**writer, samples);
  if (!close) {
    return (*writer)->partialPath();
  }
  auto closed = (*writer)->close();
  EXPECT_TRUE(closed) << closed.error().message;
  return path;
}

std::vector<Sample> smallSamples(std::size_t count) {
  std::vector<Sample> out;
  for (std::size_t i = 0; i < count; ++i) {
    out.push_back(sample(static_cast<std::uint32_t>(i % 2), static_cast<std::int64_t>(i), 40 + i));
  }
  return out;
}

std::string recordAt(std::size_t index, std::size_t offset) {
  return "record " + std::to_string(index) + " at byte offset " + std::to_string(offset);
}

// ---- round trips ----

TEST(RecordLog, RoundTripKeepsTopicsMessagesAndTimestampsExactly) {
  TempDir dir;
  const std::string path = dir.file("run.rmlog");
  std::vector<Sample> samples = {
      sample(0, 0, 0),                     // empty payload
      sample(1, 1, 1),                     // one byte
      sample(0, 2, std::size_t{5} << 20),  // 5 MiB
      sample(1, 3, 17),
      Sample{0, INT64_MIN, INT64_MAX, -1, randomBytes(3, 9)},  // extreme timestamps
  };
  const auto before = std::chrono::system_clock::now().time_since_epoch();

  auto writer = RecordLogWriter::create(path);
  ASSERT_TRUE(writer) << writer.error().message;
  auto points =
      (*writer)->addTopic(kPoints.name, kPoints.type, kPoints.reliability, kPoints.durability);
  auto tf = (*writer)->addTopic(kTfStatic.name, kTfStatic.type, kTfStatic.reliability,
                                kTfStatic.durability);
  ASSERT_TRUE(points && tf);
  EXPECT_EQ(*points, 0u);
  EXPECT_EQ(*tf, 1u);
  writeSamples(**writer, samples);
  EXPECT_EQ((*writer)->messages(), samples.size());
  ASSERT_TRUE((*writer)->close());
  const auto after = std::chrono::system_clock::now().time_since_epoch();

  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  EXPECT_DOUBLE_EQ(reader->progress(), static_cast<double>(kHeader) /
                                           static_cast<double>(std::filesystem::file_size(path)));
  EXPECT_EQ(readAll(*reader), samples);
  EXPECT_EQ(reader->topics(), (std::vector<LogTopic>{kPoints, kTfStatic}));
  ASSERT_NE(reader->topic(1), nullptr);
  EXPECT_EQ(reader->topic(1)->name, "rt/tf_static");
  EXPECT_EQ(reader->topic(2), nullptr);
  EXPECT_TRUE(reader->complete());
  EXPECT_FALSE(reader->truncation());
  EXPECT_EQ(reader->messagesRead(), samples.size());
  EXPECT_DOUBLE_EQ(reader->progress(), 1.0);
  EXPECT_GE(reader->createdUnixNs(),
            std::chrono::duration_cast<std::chrono::nanoseconds>(before).count());
  EXPECT_LE(reader->createdUnixNs(),
            std::chrono::duration_cast<std::chrono::nanoseconds>(after).count());
  auto again = reader->next();  // stays at the end
  ASSERT_TRUE(again);
  EXPECT_FALSE(*again);
}

TEST(RecordLog, FileBytesFollowTheDocumentedLayout) {
  TempDir dir;
  const std::string path = dir.file("layout.rmlog");
  const Sample s = sample(1, 4, 5);
  recordLog(path, {s}, true);
  const Bytes bytes = readFileBytes(path);

  ASSERT_GE(bytes.size(), kHeader);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), std::string("RMLOG\r\n\x1a", 8));
  EXPECT_EQ(getLe(bytes, 8, 4), 1u);    // version
  EXPECT_EQ(getLe(bytes, 12, 4), 32u);  // header size
  EXPECT_EQ(getLe(bytes, 24, 4), 0u);   // flags
  EXPECT_EQ(getLe(bytes, 28, 4), crc32(bytes.data(), 28));
  const auto all = records(bytes);
  ASSERT_EQ(all.size(), 4u);  // TOPIC, TOPIC, MESSAGE, END
  EXPECT_EQ(all[0].kind, kTopic);
  EXPECT_EQ(all[1].kind, kTopic);
  EXPECT_EQ(all[2].kind, kMessage);
  EXPECT_EQ(all[3].kind, kEnd);
  EXPECT_EQ(all[3].offset + kRecordHead + all[3].length, bytes.size());
  // TOPIC 1: id, reliable, transient-local, reserved, then the two strings.
  const std::size_t t = all[1].offset + kRecordHead;
  EXPECT_EQ(getLe(bytes, t, 4), 1u);
  EXPECT_EQ(bytes[t + 4], 1u);
  EXPECT_EQ(bytes[t + 5], 1u);
  EXPECT_EQ(getLe(bytes, t + 6, 2), 0u);
  EXPECT_EQ(getLe(bytes, t + 8, 2), kTfStatic.name.size());
  EXPECT_EQ(all[1].length, 8 + 2 + kTfStatic.name.size() + 2 + kTfStatic.type.size());
  // MESSAGE: topic id, three i64 timestamps, the CDR bytes; the CRC covers kind+length+payload.
  const std::size_t m = all[2].offset;
  EXPECT_EQ(all[2].length, kPrefix + s.cdr.size());
  EXPECT_EQ(getLe(bytes, m + 12, 4), 1u);
  EXPECT_EQ(static_cast<std::int64_t>(getLe(bytes, m + 16, 8)), s.receive_unix_ns);
  EXPECT_EQ(static_cast<std::int64_t>(getLe(bytes, m + 24, 8)), s.receive_monotonic_ns);
  EXPECT_EQ(static_cast<std::int64_t>(getLe(bytes, m + 32, 8)), s.source_timestamp_ns);
  Bytes covered(bytes.begin() + static_cast<std::ptrdiff_t>(m),
                bytes.begin() + static_cast<std::ptrdiff_t>(m + 8));
  covered.insert(covered.end(), bytes.begin() + static_cast<std::ptrdiff_t>(m + kRecordHead),
                 bytes.begin() + static_cast<std::ptrdiff_t>(m + kRecordHead + all[2].length));
  EXPECT_EQ(getLe(bytes, m + 8, 4), crc32(covered.data(), covered.size()));
  // END: message count and a wall-clock time.
  EXPECT_EQ(all[3].length, 16u);
  EXPECT_EQ(getLe(bytes, all[3].offset + kRecordHead, 8), 1u);
}

// ---- crash behaviour ----

TEST(RecordLog, PartialFileExistsWhileRecordingAndIsRenamedOnClose) {
  TempDir dir;
  const std::string path = dir.file("run.rmlog");
  auto writer = RecordLogWriter::create(path);
  ASSERT_TRUE(writer) << writer.error().message;
  EXPECT_EQ((*writer)->partialPath(), path + ".partial");
  EXPECT_TRUE(std::filesystem::exists(path + ".partial"));
  EXPECT_FALSE(std::filesystem::exists(path));
  ASSERT_TRUE(
      (*writer)->addTopic("rt/points", "T", LogReliability::kBestEffort, LogDurability::kVolatile));
  writeSamples(**writer, {sample(0, 0, 10)});
  EXPECT_EQ((*writer)->bytes(), std::filesystem::file_size(path + ".partial"));

  ASSERT_TRUE((*writer)->close());
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  EXPECT_EQ((*writer)->bytes(), std::filesystem::file_size(path));
}

TEST(RecordLog, EveryWrittenRecordIsInTheFileBeforeClose) {
  TempDir dir;
  const std::string path = dir.file("live.rmlog");
  auto writer = RecordLogWriter::create(path);
  ASSERT_TRUE(writer);
  ASSERT_TRUE(
      (*writer)->addTopic("rt/points", "T", LogReliability::kBestEffort, LogDurability::kVolatile));
  std::vector<Sample> written;
  for (int i = 0; i < 5; ++i) {
    written.push_back(sample(0, i, 100));
    writeSamples(**writer, {written.back()});
    // No user-space buffer: another reader sees the record as soon as write() returns.
    auto reader = openOrFail((*writer)->partialPath());
    ASSERT_NE(reader, nullptr);
    EXPECT_EQ(readAll(*reader), written);
    EXPECT_FALSE(reader->truncation());
  }
}

TEST(RecordLog, WriterDestroyedWithoutCloseLeavesAReadablePartialFile) {
  TempDir dir;
  const std::string path = dir.file("crash.rmlog");
  const auto samples = smallSamples(7);
  const std::string partial = recordLog(path, samples, /*close=*/false);
  ASSERT_EQ(partial, path + ".partial");
  EXPECT_TRUE(std::filesystem::exists(partial));
  EXPECT_FALSE(std::filesystem::exists(path));

  auto reader = openOrFail(partial);
  ASSERT_NE(reader, nullptr);
  EXPECT_EQ(readAll(*reader), samples);
  EXPECT_FALSE(reader->complete());
  EXPECT_FALSE(reader->truncation());
  EXPECT_EQ(reader->topics().size(), 2u);
}

TEST(RecordLog, SigkilledRecorderLeavesEveryReturnedRecord) {
  TempDir dir;
  const std::string path = dir.file("killed.rmlog");
  const auto samples = smallSamples(50);
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The recorder: write everything, report, then wait to be killed. Never returns into gtest.
    ::close(ready[0]);
    auto writer = RecordLogWriter::create(path);
    if (!writer ||
        !(*writer)->addTopic("a", "A", LogReliability::kReliable, LogDurability::kVolatile) ||
        !(*writer)->addTopic("b", "B", LogReliability::kReliable, LogDurability::kVolatile)) {
      ::_exit(2);
    }
    for (const Sample& s : samples) {
      if (!(*writer)->write(s.topic_id, s.receive_unix_ns, s.receive_monotonic_ns,
                            s.source_timestamp_ns, s.cdr)) {
        ::_exit(3);
      }
    }
    const char done = 'x';
    if (::write(ready[1], &done, 1) != 1) {
      ::_exit(4);
    }
    for (;;) {
      ::pause();
    }
  }
  ::close(ready[1]);
  char done = 0;
  const ssize_t got = ::read(ready[0], &done, 1);
  ::close(ready[0]);
  ::kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_EQ(got, 1) << "the recorder exited early with status " << status;
  ASSERT_TRUE(WIFSIGNALED(status));

  auto reader = openOrFail(path + ".partial");
  ASSERT_NE(reader, nullptr);
  EXPECT_EQ(readAll(*reader), samples);
  EXPECT_FALSE(reader->complete());
  EXPECT_FALSE(reader->truncation());
}

TEST(RecordLog, CutAtEveryOffsetOfTheLastRecordReadsTheRestAndReportsTruncation) {
  TempDir dir;
  const auto samples = smallSamples(6);
  const Bytes full = readFileBytes(recordLog(dir.file("cut.rmlog"), samples, /*close=*/false));
  const auto all = records(full);
  ASSERT_EQ(all.back().kind, kMessage);
  const std::size_t last = all.back().offset;
  ASSERT_EQ(last + kRecordHead + all.back().length, full.size());
  const std::vector<Sample> before_last(samples.begin(), samples.end() - 1);
  const std::string path = dir.file("cut-copy.rmlog");

  for (std::size_t cut = last; cut < full.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    writeFileBytes(path, Bytes(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(cut)));
    auto reader = openOrFail(path);
    ASSERT_NE(reader, nullptr);
    EXPECT_EQ(readAll(*reader), before_last);
    EXPECT_FALSE(reader->complete());
    EXPECT_DOUBLE_EQ(reader->progress(), 1.0);
    if (cut == last) {
      EXPECT_FALSE(reader->truncation());  // ends between records: nothing is cut
      continue;
    }
    ASSERT_TRUE(reader->truncation());
    EXPECT_EQ(reader->truncation()->offset, last);
    EXPECT_EQ(reader->truncation()->complete_messages, before_last.size());
    EXPECT_NE(reader->truncation()->what.find(recordAt(all.size() - 1, last)), std::string::npos)
        << reader->truncation()->what;
  }
}

TEST(RecordLog, CutInsideTheEndRecordKeepsEveryMessage) {
  TempDir dir;
  const auto samples = smallSamples(3);
  const Bytes full = readFileBytes(recordLog(dir.file("end.rmlog"), samples, /*close=*/true));
  const RecordAt end = records(full).back();
  ASSERT_EQ(end.kind, kEnd);
  const std::string path = dir.file("end-cut.rmlog");
  for (std::size_t cut = end.offset + 1; cut < full.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    writeFileBytes(path, Bytes(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(cut)));
    auto reader = openOrFail(path);
    ASSERT_NE(reader, nullptr);
    EXPECT_EQ(readAll(*reader), samples);
    EXPECT_FALSE(reader->complete());
    ASSERT_TRUE(reader->truncation());
    EXPECT_EQ(reader->truncation()->complete_messages, samples.size());
    EXPECT_EQ(reader->truncation()->offset, end.offset);
  }
}

TEST(RecordLog, CutInsideTheFileHeaderIsAnErrorNotACrash) {
  TempDir dir;
  const Bytes full = readFileBytes(recordLog(dir.file("h.rmlog"), smallSamples(1), true));
  const std::string path = dir.file("h-cut.rmlog");
  for (std::size_t cut = 0; cut < kHeader; ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    writeFileBytes(path, Bytes(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(cut)));
    auto reader = RecordLogReader::open(path);
    ASSERT_FALSE(reader);
    EXPECT_NE(reader.error().message.find(path), std::string::npos);
    EXPECT_EQ(reader.error().code, cut == 0 ? ErrorCode::kFormat : ErrorCode::kTruncated)
        << reader.error().message;
  }
}

TEST(RecordLog, ZeroFilledTailAfterPowerLossReadsAsTruncation) {
  TempDir dir;
  const auto samples = smallSamples(4);
  Bytes bytes = readFileBytes(recordLog(dir.file("z.rmlog"), samples, false));
  const std::size_t end_of_data = bytes.size();
  const std::size_t records_before = records(bytes).size();
  bytes.resize(bytes.size() + 5000, 0);
  const std::string path = dir.file("zeros.rmlog");
  writeFileBytes(path, bytes);

  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  EXPECT_EQ(readAll(*reader), samples);
  ASSERT_TRUE(reader->truncation());
  EXPECT_EQ(reader->truncation()->offset, end_of_data);
  EXPECT_EQ(reader->truncation()->complete_messages, samples.size());

  // Zeros followed by data are damage, not a lost tail.
  bytes.back() = 1;
  writeFileBytes(path, bytes);
  reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  const Error error = firstError(*reader);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find(recordAt(records_before, end_of_data)), std::string::npos)
      << error.message;
}

// ---- damage ----

TEST(RecordLog, FlippedPayloadByteIsAChecksumErrorNamingFileRecordAndOffset) {
  TempDir dir;
  const auto samples = smallSamples(5);
  const Bytes good = readFileBytes(recordLog(dir.file("p.rmlog"), samples, true));
  const auto all = records(good);
  const std::size_t index = 4;  // TOPIC, TOPIC, MESSAGE 0, MESSAGE 1, MESSAGE 2 <-
  ASSERT_EQ(all[index].kind, kMessage);
  const std::string path = dir.file("p-bad.rmlog");
  // A byte of the timestamps and a byte of the CDR bytes.
  for (std::size_t in_payload : {std::size_t{5}, kPrefix + 3}) {
    Bytes bad = good;
    bad[all[index].offset + kRecordHead + in_payload] ^= 0x10;
    writeFileBytes(path, bad);
    auto reader = openOrFail(path);
    ASSERT_NE(reader, nullptr);
    std::uint64_t read = 0;
    const Error error = firstError(*reader, &read);
    EXPECT_EQ(read, 2u);  // the messages before it are fine
    EXPECT_EQ(error.code, ErrorCode::kCorrupt);
    EXPECT_NE(error.message.find(path), std::string::npos) << error.message;
    EXPECT_NE(error.message.find(recordAt(index, all[index].offset)), std::string::npos)
        << error.message;
    EXPECT_NE(error.message.find("checksum"), std::string::npos) << error.message;
    auto again = reader->next();  // the error sticks
    ASSERT_FALSE(again);
    EXPECT_EQ(again.error().message, error.message);
  }
}

TEST(RecordLog, FlippedRecordHeaderByteIsAnErrorNamingFileRecordAndOffset) {
  TempDir dir;
  std::vector<Sample> samples = smallSamples(4);
  samples.push_back(sample(0, 99, 200'000));  // enough bytes behind for a longer length to fit
  const Bytes good = readFileBytes(recordLog(dir.file("h.rmlog"), samples, true));
  const auto all = records(good);
  const std::size_t index = 3;
  ASSERT_EQ(all[index].kind, kMessage);
  const std::string path = dir.file("h-bad.rmlog");
  for (std::size_t byte = 0; byte < kRecordHead; ++byte) {
    SCOPED_TRACE("header byte " + std::to_string(byte));
    Bytes bad = good;
    // The top length byte with 0x80 makes the length impossible; every other flip leaves a
    // record whose checksum cannot match.
    bad[all[index].offset + byte] ^= byte == 7 ? 0x80 : 0x01;
    writeFileBytes(path, bad);
    auto reader = openOrFail(path);
    ASSERT_NE(reader, nullptr);
    const Error error = firstError(*reader);
    EXPECT_EQ(error.code, ErrorCode::kCorrupt);
    EXPECT_NE(error.message.find(path), std::string::npos) << error.message;
    EXPECT_NE(error.message.find(recordAt(index, all[index].offset)), std::string::npos)
        << error.message;
  }
}

TEST(RecordLog, FlippedFileHeaderByteIsAnErrorNamingTheFile) {
  TempDir dir;
  const Bytes good = readFileBytes(recordLog(dir.file("f.rmlog"), smallSamples(2), true));
  const std::string path = dir.file("f-bad.rmlog");
  for (std::size_t byte = 0; byte < kHeader; ++byte) {
    SCOPED_TRACE("file header byte " + std::to_string(byte));
    Bytes bad = good;
    bad[byte] ^= 0x01;
    writeFileBytes(path, bad);
    auto reader = RecordLogReader::open(path);
    ASSERT_FALSE(reader);
    EXPECT_NE(reader.error().message.find(path), std::string::npos) << reader.error().message;
    if (byte < 8) {
      EXPECT_NE(reader.error().message.find("not a raymap record log"), std::string::npos);
    } else if (byte >= 16) {  // time, flags, the checksum itself
      EXPECT_EQ(reader.error().code, ErrorCode::kCorrupt);
      EXPECT_NE(reader.error().message.find("checksum"), std::string::npos)
          << reader.error().message;
    }
  }
}

TEST(RecordLog, ForeignFilesAreNotRecordLogs) {
  TempDir dir;
  const std::string ply = dir.file("cloud.ply");
  const std::string text = dir.file("notes.txt");
  const std::string empty = dir.file("empty.rmlog");
  const std::string log = recordLog(dir.file("real.rmlog"), smallSamples(1), true);
  const std::string partial = recordLog(dir.file("open.rmlog"), smallSamples(1), false);
  const std::string ply_header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n";
  writeFileBytes(ply, Bytes(ply_header.begin(), ply_header.end()));
  std::mt19937 rng(7);
  std::string random_text;
  for (int i = 0; i < 500; ++i) {
    random_text.push_back(static_cast<char>('a' + rng() % 26));
  }
  writeFileBytes(text, Bytes(random_text.begin(), random_text.end()));
  writeFileBytes(empty, {});

  for (const std::string& path : {ply, text}) {
    SCOPED_TRACE(path);
    auto reader = RecordLogReader::open(path);
    ASSERT_FALSE(reader);
    EXPECT_EQ(reader.error().code, ErrorCode::kFormat);
    EXPECT_NE(reader.error().message.find(path + ": not a raymap record log"), std::string::npos)
        << reader.error().message;
    EXPECT_FALSE(looksLikeRecordLog(path));
  }
  auto empty_reader = RecordLogReader::open(empty);
  ASSERT_FALSE(empty_reader);
  EXPECT_EQ(empty_reader.error().code, ErrorCode::kFormat);
  EXPECT_EQ(empty_reader.error().message, empty + " is empty (0 bytes): not a raymap record log");
  EXPECT_FALSE(looksLikeRecordLog(empty));
  EXPECT_TRUE(looksLikeRecordLog(log));
  EXPECT_TRUE(looksLikeRecordLog(partial));
  EXPECT_FALSE(looksLikeRecordLog(dir.file("missing.rmlog")));
  EXPECT_FALSE(looksLikeRecordLog(dir.path().string()));

  auto missing = RecordLogReader::open(dir.file("missing.rmlog"));
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
  EXPECT_NE(missing.error().message.find(dir.file("missing.rmlog")), std::string::npos);
}

TEST(RecordLog, NewerVersionIsRefusedWithAClearMessage) {
  TempDir dir;
  Bytes bytes = readFileBytes(recordLog(dir.file("v.rmlog"), smallSamples(1), true));
  putLe(bytes, 8, 2, 4);
  putLe(bytes, 28, crc32(bytes.data(), 28), 4);  // a genuine version-2 header
  const std::string path = dir.file("v2.rmlog");
  writeFileBytes(path, bytes);

  auto reader = RecordLogReader::open(path);
  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(reader.error().message.find(path), std::string::npos);
  EXPECT_EQ(reader.error().message,
            path +
                ": record-log version 2 was written by a newer raymap; this one reads "
                "versions 1 to 1");
  EXPECT_TRUE(looksLikeRecordLog(path));
}

TEST(RecordLog, AFlippedVersionByteIsDamageNotANewerVersion) {
  // The version field reads 252 and the header checksum no longer matches: a damaged file, not
  // one from a raymap 251 versions ahead.
  TempDir dir;
  Bytes bytes = readFileBytes(recordLog(dir.file("v.rmlog"), smallSamples(1), true));
  bytes[8] ^= 0xFD;  // 1 -> 252
  const std::string path = dir.file("flipped.rmlog");
  writeFileBytes(path, bytes);

  auto reader = RecordLogReader::open(path);

  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, ErrorCode::kCorrupt);
  EXPECT_EQ(reader.error().message,
            path +
                ": damaged file header: its checksum does not match, and its version field "
                "reads 252 (this raymap reads record-log versions 1 to 1)");
}

TEST(RecordLog, AVersionFarAheadIsMoreLikelyDamageThanNew) {
  TempDir dir;
  Bytes bytes = readFileBytes(recordLog(dir.file("v.rmlog"), smallSamples(1), true));
  putLe(bytes, 8, 252, 4);
  putLe(bytes, 28, crc32(bytes.data(), 28), 4);  // the checksum agrees
  const std::string path = dir.file("far.rmlog");
  writeFileBytes(path, bytes);

  auto reader = RecordLogReader::open(path);

  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, ErrorCode::kUnsupported);
  EXPECT_EQ(reader.error().message,
            path +
                ": unsupported record-log version 252 (this raymap reads versions 1 to 1); a "
                "version this far ahead is more likely a damaged or foreign file than a "
                "newer raymap's");
}

// ---- structure ----

TEST(RecordLog, UnknownRecordKindWithAGoodChecksumIsSkipped) {
  TempDir dir;
  const auto samples = smallSamples(3);
  Bytes bytes = readFileBytes(recordLog(dir.file("u.rmlog"), samples, true));
  const auto all = records(bytes);
  ASSERT_EQ(all[3].kind, kMessage);
  // A kind from a newer writer between two messages, and an empty one right after the header.
  insertAt(bytes, all[3].offset, forgeRecord(77, {1, 2, 3, 4, 5}));
  insertAt(bytes, kHeader, forgeRecord(0xFFFFFFFFu, {}));
  const std::string path = dir.file("u-new.rmlog");
  writeFileBytes(path, bytes);

  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  EXPECT_EQ(readAll(*reader), samples);
  EXPECT_TRUE(reader->complete());
  EXPECT_EQ(reader->topics().size(), 2u);
}

TEST(RecordLog, MessageOnAnUndeclaredTopicIsAnError) {
  TempDir dir;
  Bytes bytes = readFileBytes(recordLog(dir.file("t.rmlog"), smallSamples(3), true));
  const auto all = records(bytes);
  const std::size_t index = 3;
  ASSERT_EQ(all[index].kind, kMessage);
  putLe(bytes, all[index].offset + kRecordHead, 7, 4);  // topic id 7: never declared
  fixRecordCrc(bytes, all[index].offset);
  const std::string path = dir.file("t-bad.rmlog");
  writeFileBytes(path, bytes);

  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  std::uint64_t read = 0;
  const Error error = firstError(*reader, &read);
  EXPECT_EQ(read, 1u);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find(path), std::string::npos);
  EXPECT_NE(error.message.find(recordAt(index, all[index].offset)), std::string::npos)
      << error.message;
  EXPECT_NE(error.message.find("topic id 7"), std::string::npos) << error.message;
}

TEST(RecordLog, MessageBeforeItsTopicRecordIsAnError) {
  TempDir dir;
  Bytes bytes = readFileBytes(recordLog(dir.file("o.rmlog"), smallSamples(1), false));
  const auto all = records(bytes);  // TOPIC 0, TOPIC 1, MESSAGE on topic 0
  ASSERT_EQ(all.size(), 3u);
  Bytes message(bytes.begin() + static_cast<std::ptrdiff_t>(all[2].offset), bytes.end());
  bytes.resize(all[2].offset);
  insertAt(bytes, kHeader, message);  // the message now comes first
  const std::string path = dir.file("o-bad.rmlog");
  writeFileBytes(path, bytes);

  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  const Error error = firstError(*reader);
  EXPECT_NE(error.message.find(recordAt(0, kHeader)), std::string::npos) << error.message;
}

TEST(RecordLog, MalformedTopicAndEndRecordsAreErrors) {
  TempDir dir;
  const Bytes good = readFileBytes(recordLog(dir.file("m.rmlog"), smallSamples(2), true));
  const auto all = records(good);
  const std::string path = dir.file("m-bad.rmlog");
  struct Case {
    const char* name;
    std::size_t record;
    std::size_t payload_offset;
    std::uint64_t value;
    int bytes;
    const char* expected;
  };
  const Case cases[] = {
      {"name length past the payload", 0, 8, 0xFFFF, 2, "malformed TOPIC record"},
      {"reliability 9", 0, 4, 9, 1, "unknown reliability 9"},
      {"second topic id out of order", 1, 0, 5, 4, "declares id 5"},
      {"END counts too many", all.size() - 1, 0, 3, 8, "END record counts 3 messages"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Bytes bad = good;
    putLe(bad, all[c.record].offset + kRecordHead + c.payload_offset, c.value, c.bytes);
    fixRecordCrc(bad, all[c.record].offset);
    writeFileBytes(path, bad);
    auto reader = openOrFail(path);
    ASSERT_NE(reader, nullptr);
    const Error error = firstError(*reader);
    EXPECT_EQ(error.code, ErrorCode::kCorrupt);
    EXPECT_NE(error.message.find(recordAt(c.record, all[c.record].offset)), std::string::npos)
        << error.message;
    EXPECT_NE(error.message.find(c.expected), std::string::npos) << error.message;
  }

  Bytes trailing = good;  // bytes after END
  trailing.push_back(0x42);
  writeFileBytes(path, trailing);
  auto reader = openOrFail(path);
  ASSERT_NE(reader, nullptr);
  EXPECT_NE(firstError(*reader).message.find("followed by 1 more bytes"), std::string::npos);
}

// ---- replay helpers ----

TEST(RecordLog, RewindReadsTheSameMessagesAgain) {
  TempDir dir;
  const auto samples = smallSamples(9);
  auto reader = openOrFail(recordLog(dir.file("r.rmlog"), samples, true));
  ASSERT_NE(reader, nullptr);
  const auto first = readAll(*reader);
  ASSERT_TRUE(reader->complete());

  ASSERT_TRUE(reader->rewind());
  EXPECT_FALSE(reader->complete());
  EXPECT_EQ(reader->messagesRead(), 0u);
  EXPECT_EQ(reader->topics().size(), 2u);  // topics stay known
  EXPECT_DOUBLE_EQ(reader->progress(),
                   static_cast<double>(kHeader) /
                       static_cast<double>(std::filesystem::file_size(reader->path())));
  EXPECT_EQ(readAll(*reader), first);
  EXPECT_EQ(first, samples);
  EXPECT_TRUE(reader->complete());
  EXPECT_EQ(reader->topics().size(), 2u);
}

TEST(RecordLog, RewindOfAPartialFileReadsRecordsAddedSince) {
  TempDir dir;
  auto writer = RecordLogWriter::create(dir.file("grow.rmlog"));
  ASSERT_TRUE(writer);
  ASSERT_TRUE((*writer)->addTopic("x", "X", LogReliability::kBestEffort, LogDurability::kVolatile));
  writeSamples(**writer, {sample(0, 0, 3)});
  auto reader = openOrFail((*writer)->partialPath());
  ASSERT_NE(reader, nullptr);
  EXPECT_EQ(readAll(*reader).size(), 1u);
  writeSamples(**writer, {sample(0, 1, 4)});
  ASSERT_TRUE(reader->rewind());
  EXPECT_EQ(readAll(*reader).size(), 2u);
}

TEST(RecordLog, SummarizeCountsMessagesPerTopicAndTimes) {
  TempDir dir;
  const std::string path = dir.file("s.rmlog");
  auto writer = RecordLogWriter::create(path);
  ASSERT_TRUE(writer);
  for (const char* name : {"a", "b", "silent"}) {
    ASSERT_TRUE(
        (*writer)->addTopic(name, "T", LogReliability::kReliable, LogDurability::kVolatile));
  }
  const std::vector<std::uint32_t> topics = {0, 1, 1, 0, 1};
  for (std::size_t i = 0; i < topics.size(); ++i) {
    const auto t = static_cast<std::int64_t>(i);
    ASSERT_TRUE((*writer)->write(topics[i], 1000 + t * 10, t, 0, randomBytes(8, 1)));
  }
  ASSERT_TRUE((*writer)->close());

  auto summary = RecordLogReader::summarize(path);
  ASSERT_TRUE(summary) << summary.error().message;
  ASSERT_EQ(summary->topics.size(), 3u);
  EXPECT_EQ(summary->topics[2].name, "silent");
  EXPECT_EQ(summary->messages_per_topic, (std::vector<std::uint64_t>{2, 3, 0}));
  EXPECT_EQ(summary->first_receive_unix_ns, 1000);
  EXPECT_EQ(summary->last_receive_unix_ns, 1040);
  EXPECT_TRUE(summary->complete);
  EXPECT_FALSE(summary->truncation);

  // A cut-off copy: summarized up to the cut, with the truncation.
  Bytes bytes = readFileBytes(path);
  const auto all = records(bytes);
  bytes.resize(all[all.size() - 2].offset + 5);  // inside the last message
  const std::string cut = dir.file("s-cut.rmlog");
  writeFileBytes(cut, bytes);
  summary = RecordLogReader::summarize(cut);
  ASSERT_TRUE(summary) << summary.error().message;
  EXPECT_EQ(summary->messages_per_topic, (std::vector<std::uint64_t>{2, 2, 0}));
  EXPECT_EQ(summary->last_receive_unix_ns, 1030);
  EXPECT_FALSE(summary->complete);
  ASSERT_TRUE(summary->truncation);
  EXPECT_EQ(summary->truncation->complete_messages, 4u);

  auto missing = RecordLogReader::summarize(dir.file("none.rmlog"));
  EXPECT_FALSE(missing);
}

// ---- writer errors ----

TEST(RecordLog, UnwritableDirectoryIsAnErrorNamingThePath) {
  TempDir dir;
  const std::string not_a_dir = dir.file("plain-file");
  writeFileBytes(not_a_dir, {1});
  for (const std::string& path : {dir.file("missing-dir/run.rmlog"), not_a_dir + "/run.rmlog"}) {
    SCOPED_TRACE(path);
    auto writer = RecordLogWriter::create(path);
    ASSERT_FALSE(writer);
    EXPECT_EQ(writer.error().code, ErrorCode::kIo);
    EXPECT_NE(writer.error().message.find(path), std::string::npos) << writer.error().message;
  }
  EXPECT_FALSE(RecordLogWriter::create(""));
}

TEST(RecordLog, ExistingPartialFileIsNeverOverwritten) {
  TempDir dir;
  const std::string path = dir.file("twice.rmlog");
  const auto samples = smallSamples(2);
  recordLog(path, samples, /*close=*/false);
  const Bytes before = readFileBytes(path + ".partial");

  auto second = RecordLogWriter::create(path);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find(path + ".partial"), std::string::npos)
      << second.error().message;
  EXPECT_EQ(readFileBytes(path + ".partial"), before);
}

TEST(RecordLog, WriterRejectsMisuse) {
  TempDir dir;
  auto writer = RecordLogWriter::create(dir.file("misuse.rmlog"));
  ASSERT_TRUE(writer);
  RecordLogWriter& w = **writer;
  EXPECT_FALSE(w.addTopic("", "T", LogReliability::kReliable, LogDurability::kVolatile));
  EXPECT_FALSE(w.addTopic(std::string(70'000, 'n'), "T", LogReliability::kReliable,
                          LogDurability::kVolatile));
  EXPECT_FALSE(w.addTopic("x", "T", static_cast<LogReliability>(2), LogDurability::kVolatile));
  auto unknown = w.write(0, 0, 0, 0, {});
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(unknown.error().message.find("topic id 0"), std::string::npos);
  const std::uint64_t bytes = w.bytes();
  EXPECT_EQ(bytes, kHeader);  // nothing was written by the refused calls

  ASSERT_TRUE(w.addTopic("x", "T", LogReliability::kReliable, LogDurability::kVolatile));
  ASSERT_TRUE(w.close());
  EXPECT_FALSE(w.write(0, 0, 0, 0, {}));
  EXPECT_FALSE(w.addTopic("y", "T", LogReliability::kReliable, LogDurability::kVolatile));
  EXPECT_FALSE(w.close());
  auto reader = openOrFail(w.path());
  ASSERT_NE(reader, nullptr);
  EXPECT_TRUE(readAll(*reader).empty());
  EXPECT_TRUE(reader->complete());
}

}  // namespace
}  // namespace raymap::record
