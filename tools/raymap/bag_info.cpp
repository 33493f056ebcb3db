// SPDX-License-Identifier: BSD-3-Clause
// `raymap info BAG`: a rosbag2 recording's topics, types, message counts and time span, as
// `ros2 bag info` shows them (read from the messages themselves, so a bag without a summary or
// with a wrong metadata.yaml is described as it is).
#include "tools/raymap/bag_info.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "src/bag/bag_reader.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/option_names.hpp"

namespace raymap::cli {
namespace {

struct TopicCount {
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
};

/// What `raymap info` says of a bag: per topic counts and the log-time span.
struct BagCounts {
  std::vector<TopicCount> topics;
  std::int64_t first = std::numeric_limits<std::int64_t>::max();
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  std::uint64_t total = 0;
  bool stated = false;  ///< from the file's summary (bytes unknown), not counted
  bag::BagPass read;    ///< the reading pass, when counted

  double durationSeconds() const {
    return total > 0 ? static_cast<double>(last - first) * 1e-9 : 0.0;
  }
};

/// The counts an indexed MCAP file states (no need to read gigabytes), else (or with `full`)
/// counted from the messages.
Result<BagCounts> countMessages(bag::BagReader& reader, bool full) {
  BagCounts c;
  c.topics.resize(reader.topics().size());
  const std::optional<bag::BagStatistics> stated = full ? std::nullopt : reader.statistics();
  if (stated) {
    c.stated = true;
    c.total = stated->messages;
    c.first = stated->start_ns;
    c.last = stated->end_ns;
    for (std::size_t i = 0; i < c.topics.size(); ++i) {
      c.topics[i].messages = stated->topic_messages[i];
    }
    return c;
  }
  auto pass = reader.forEach([&](const bag::BagMessage& m) {
    if (m.topic >= c.topics.size()) {
      c.topics.resize(m.topic + 1);
    }
    ++c.topics[m.topic].messages;
    c.topics[m.topic].bytes += m.data.size();
    c.first = std::min(c.first, m.log_time_ns);
    c.last = std::max(c.last, m.log_time_ns);
    return true;
  });
  if (!pass) {
    return Unexpected(pass.error());
  }
  c.read = pass.value();
  c.total = c.read.messages;
  return c;
}

void printBagJson(const std::string& path, const bag::BagReader& reader, const BagCounts& c) {
  const std::vector<bag::BagTopic>& topics = reader.topics();
  Json list = Json::array();
  for (std::size_t i = 0; i < topics.size(); ++i) {
    Json t = {
        {"name", topics[i].name},
        {"type", topics[i].type},
        {"serialization_format", topics[i].serialization_format},
        {"messages", c.topics[i].messages},
    };
    if (!c.stated) {
      t["bytes"] = c.topics[i].bytes;
    }
    list.push_back(std::move(t));
  }
  const Json j = {
      {"path", path},
      {"storage", reader.storage()},
      {"messages", c.total},
      {"start_ns", c.total > 0 ? c.first : std::int64_t{0}},
      {"end_ns", c.total > 0 ? c.last : std::int64_t{0}},
      {"duration_s", c.durationSeconds()},
      {"counted_from", c.stated ? "summary" : "messages"},
      {"truncated", c.read.truncated},
      {"topics", list},
  };
  std::printf("%s\n", dumpJson(j).c_str());
}

void printBagText(const std::string& path, const bag::BagReader& reader, const BagCounts& c) {
  const std::vector<bag::BagTopic>& topics = reader.topics();
  std::printf("bag            %s (%s)\n", path.c_str(), reader.storage());
  std::printf("messages       %" PRIu64 " over %.3f s", c.total, c.durationSeconds());
  if (c.total > 0) {
    std::printf(" (log time %" PRId64 ".%09" PRId64 " to %" PRId64 ".%09" PRId64 " s)",
                c.first / 1000000000, c.first % 1000000000, c.last / 1000000000,
                c.last % 1000000000);
  }
  std::printf("%s\ntopics         %zu\n", c.stated ? " (from the file's summary)" : "",
              topics.size());
  for (std::size_t i = 0; i < topics.size(); ++i) {
    char bytes[32] = "";
    if (!c.stated) {
      std::snprintf(bytes, sizeof(bytes), "  %.3f MB",
                    static_cast<double>(c.topics[i].bytes) / 1e6);
    }
    std::printf("  %-28s %-32s %8" PRIu64 " messages%s  %s\n", topics[i].name.c_str(),
                topics[i].type.c_str(), c.topics[i].messages, bytes,
                topics[i].serialization_format.c_str());
  }
}

}  // namespace

int runBagInfo(const std::string& path, bool json, bool full) {
  // A description reads what a damaged bag holds and says what is damaged (stderr).
  bag::BagReadOptions options;
  options.skip_damaged = true;
  auto bag = bag::openBag(path, options);
  if (!bag) {
    printError("info", bag.error().message);
    return kExitFailure;
  }
  bag::BagReader& reader = *bag.value();
  auto counts = countMessages(reader, full);
  if (!counts) {
    printError("info", counts.error().message);
    return kExitFailure;
  }
  if (json) {
    printBagJson(path, reader, *counts);
  } else {
    printBagText(path, reader, *counts);
  }
  for (const std::string& warning : reader.openWarnings()) {
    std::fprintf(stderr, "raymap info: warning: %s\n", withCliFlags(warning).c_str());
  }
  for (const std::string& damage : counts->read.damage) {
    std::fprintf(stderr, "raymap info: warning: %s\n", withCliFlags(damage).c_str());
  }
  return 0;
}

}  // namespace raymap::cli
