// SPDX-License-Identifier: BSD-3-Clause
// rosbag2's SQLite storage (the default before Iron): table `topics` (id, name, type,
// serialization_format, offered_qos_profiles) and table `messages` (id, topic_id, timestamp,
// data), read with Debian's libsqlite3, read-only.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <sqlite3.h>

#include "src/bag/bag_reader.hpp"

namespace raymap::bag {
namespace {

struct CloseDatabase {
  void operator()(sqlite3* db) const noexcept { sqlite3_close(db); }
};
struct FinalizeStatement {
  void operator()(sqlite3_stmt* s) const noexcept { sqlite3_finalize(s); }
};
using Statement = std::unique_ptr<sqlite3_stmt, FinalizeStatement>;

std::string columnText(sqlite3_stmt* s, int column) {
  const unsigned char* text = sqlite3_column_text(s, column);
  return text != nullptr ? reinterpret_cast<const char*>(text) : "";
}

class SqliteBagReader final : public BagReader {
 public:
  explicit SqliteBagReader(std::string path) : path_(std::move(path)) {}

  const std::string& path() const noexcept override { return path_; }
  const char* storage() const noexcept override { return "sqlite3"; }
  const std::vector<BagTopic>& topics() const noexcept override { return topics_; }
  double progress() const noexcept override {
    return total_ == 0 ? 0.0 : static_cast<double>(done_) / static_cast<double>(total_);
  }

  Expected<void, Error> open() {
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(path_.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
    db_.reset(db);
    if (rc != SQLITE_OK) {
      return error(ErrorCode::kIo, "cannot open it");
    }
    // Older bags (Foxy) have no offered_qos_profiles column.
    auto topics = prepare(
        "SELECT id, name, type, serialization_format, offered_qos_profiles FROM topics ORDER BY "
        "id");
    if (!topics) {
      topics = prepare("SELECT id, name, type, serialization_format, '' FROM topics ORDER BY id");
    }
    if (!topics) {
      return Unexpected(topics.error());
    }
    int rc_step = SQLITE_ROW;
    while ((rc_step = sqlite3_step(topics.value().get())) == SQLITE_ROW) {
      sqlite3_stmt* s = topics.value().get();
      BagTopic t;
      t.name = columnText(s, 1);
      t.type = columnText(s, 2);
      t.serialization_format = columnText(s, 3);
      t.offered_qos_profiles = columnText(s, 4);
      topic_index_[sqlite3_column_int64(s, 0)] = static_cast<std::uint32_t>(topics_.size());
      topics_.push_back(std::move(t));
    }
    if (rc_step != SQLITE_DONE) {
      return error(ErrorCode::kFormat, "cannot read table 'topics'");
    }
    auto count = prepare("SELECT COUNT(*) FROM messages");
    if (!count) {
      return Unexpected(count.error());
    }
    if (sqlite3_step(count.value().get()) != SQLITE_ROW) {
      return error(ErrorCode::kFormat, "cannot count table 'messages'");
    }
    total_ = static_cast<std::uint64_t>(sqlite3_column_int64(count.value().get(), 0));
    return {};
  }

  const BagPass& pass() const noexcept override { return pass_; }

  Expected<void, Error> rewind() override {
    // In time order, as `ros2 bag play` plays them (rosbag2 indexes timestamp); ties by id.
    auto rows = prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
    if (!rows) {
      return Unexpected(rows.error());
    }
    rows_ = std::move(rows).value();
    pass_ = BagPass{};
    done_ = 0;
    return {};
  }

  Result<bool> next(BagMessage& out) override {
    if (!rows_) {
      if (auto ok = rewind(); !ok) {
        return Unexpected(ok.error());
      }
    }
    sqlite3_stmt* s = rows_.get();
    const int rc = sqlite3_step(s);
    if (rc == SQLITE_DONE) {
      return false;
    }
    if (rc != SQLITE_ROW) {
      return error(ErrorCode::kCorrupt,
                   "cannot read table 'messages' after message " + std::to_string(done_));
    }
    const auto topic = topic_index_.find(sqlite3_column_int64(s, 0));
    if (topic == topic_index_.end()) {
      return fail(ErrorCode::kFormat, path_ + ": message " + std::to_string(done_) +
                                          " names topic id " +
                                          std::to_string(sqlite3_column_int64(s, 0)) +
                                          ", which table 'topics' does not have");
    }
    out.topic = topic->second;
    out.log_time_ns = sqlite3_column_int64(s, 1);
    out.index = done_++;
    const void* blob = sqlite3_column_blob(s, 2);
    out.data = {static_cast<const std::byte*>(blob),
                static_cast<std::size_t>(sqlite3_column_bytes(s, 2))};
    pass_.messages = done_;
    return true;
  }

 private:
  Unexpected<Error> error(ErrorCode code, const std::string& what) const {
    return fail(code, path_ + ": " + what +
                          " (SQLite: " + (db_ ? sqlite3_errmsg(db_.get()) : "out of memory") + ")");
  }

  Result<Statement> prepare(const char* sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_.get(), sql, -1, &s, nullptr) != SQLITE_OK) {
      sqlite3_finalize(s);
      return error(ErrorCode::kFormat, "not a rosbag2 SQLite file");
    }
    return Statement(s);
  }

  std::string path_;
  std::unique_ptr<sqlite3, CloseDatabase> db_;
  std::vector<BagTopic> topics_;
  std::map<std::int64_t, std::uint32_t> topic_index_;  // topics.id -> index in topics_
  Statement rows_;                                     // the pass in progress
  BagPass pass_;
  std::uint64_t total_ = 0;
  std::uint64_t done_ = 0;
};

}  // namespace

Result<std::unique_ptr<BagReader>> openSqliteBag(const std::string& path) {
  auto reader = std::make_unique<SqliteBagReader>(path);
  if (auto ok = reader->open(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace raymap::bag
