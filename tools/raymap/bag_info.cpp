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
  std::vector<TopicCount> counts(reader.topics().size());
  std::int64_t first = std::numeric_limits<std::int64_t>::max();
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  bag::BagPass read;
  std::uint64_t total = 0;
  // An indexed MCAP file states its counts: no need to read gigabytes (bytes then unknown).
  const std::optional<bag::BagStatistics> stated = full ? std::nullopt : reader.statistics();
  if (stated) {
    total = stated->messages;
    first = stated->start_ns;
    last = stated->end_ns;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      counts[i].messages = stated->topic_messages[i];
    }
  } else {
    auto pass = reader.forEach([&](const bag::BagMessage& m) {
      if (m.topic >= counts.size()) {
        counts.resize(m.topic + 1);
      }
      ++counts[m.topic].messages;
      counts[m.topic].bytes += m.data.size();
      first = std::min(first, m.log_time_ns);
      last = std::max(last, m.log_time_ns);
      return true;
    });
    if (!pass) {
      printError("info", pass.error().message);
      return kExitFailure;
    }
    read = pass.value();
    total = read.messages;
  }
  const double duration = total > 0 ? static_cast<double>(last - first) * 1e-9 : 0.0;
  const std::vector<bag::BagTopic>& topics = reader.topics();
  if (json) {
    Json list = Json::array();
    for (std::size_t i = 0; i < topics.size(); ++i) {
      Json t = {
          {"name", topics[i].name},
          {"type", topics[i].type},
          {"serialization_format", topics[i].serialization_format},
          {"messages", counts[i].messages},
      };
      if (!stated) {
        t["bytes"] = counts[i].bytes;
      }
      list.push_back(std::move(t));
    }
    const Json j = {
        {"path", path},
        {"storage", reader.storage()},
        {"messages", total},
        {"start_ns", total > 0 ? first : std::int64_t{0}},
        {"end_ns", total > 0 ? last : std::int64_t{0}},
        {"duration_s", duration},
        {"counted_from", stated ? "summary" : "messages"},
        {"truncated", read.truncated},
        {"topics", list},
    };
    std::printf("%s\n", dumpJson(j).c_str());
  } else {
    std::printf("bag            %s (%s)\n", path.c_str(), reader.storage());
    std::printf("messages       %" PRIu64 " over %.3f s", total, duration);
    if (total > 0) {
      std::printf(" (log time %" PRId64 ".%09" PRId64 " to %" PRId64 ".%09" PRId64 " s)",
                  first / 1000000000, first % 1000000000, last / 1000000000, last % 1000000000);
    }
    std::printf("%s\ntopics         %zu\n", stated ? " (from the file's summary)" : "",
                topics.size());
    for (std::size_t i = 0; i < topics.size(); ++i) {
      char bytes[32] = "";
      if (!stated) {
        std::snprintf(bytes, sizeof(bytes), "  %.3f MB",
                      static_cast<double>(counts[i].bytes) / 1e6);
      }
      std::printf("  %-28s %-32s %8" PRIu64 " messages%s  %s\n", topics[i].name.c_str(),
                  topics[i].type.c_str(), counts[i].messages, bytes,
                  topics[i].serialization_format.c_str());
    }
  }
  for (const std::string& warning : reader.openWarnings()) {
    std::fprintf(stderr, "raymap info: warning: %s\n", withCliFlags(warning).c_str());
  }
  for (const std::string& damage : read.damage) {
    std::fprintf(stderr, "raymap info: warning: %s\n", withCliFlags(damage).c_str());
  }
  return 0;
}

}  // namespace raymap::cli
