// SPDX-License-Identifier: BSD-3-Clause
// `raymap info BAG`: a rosbag2 recording's topics, types, message counts and time span, as
// `ros2 bag info` shows them (bag::summariseBag reads them from the messages themselves, so a bag
// without a summary or with a wrong metadata.yaml is described as it is).
#include "tools/raymap/bag_info.hpp"

#include <cinttypes>
#include <cstdio>
#include <utility>

#include "src/bag/bag_summary.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/option_names.hpp"

namespace raymap::cli {
namespace {

void printBagJson(const std::string& path, const bag::BagSummary& s) {
  Json list = Json::array();
  for (const bag::TopicSummary& topic : s.topics) {
    Json t = {
        {"name", topic.topic.name},
        {"type", topic.topic.type},
        {"serialization_format", topic.topic.serialization_format},
        {"messages", topic.messages},
    };
    if (!s.from_summary) {
      t["bytes"] = topic.bytes;
    }
    list.push_back(std::move(t));
  }
  const Json j = {
      {"path", path},
      {"storage", s.storage},
      {"messages", s.messages},
      {"start_ns", s.start_ns},
      {"end_ns", s.end_ns},
      {"duration_s", s.durationSeconds()},
      {"counted_from", s.from_summary ? "summary" : "messages"},
      {"truncated", s.truncated},
      {"topics", list},
  };
  std::printf("%s\n", dumpJson(j).c_str());
}

void printBagText(const std::string& path, const bag::BagSummary& s) {
  std::printf("bag            %s (%s)\n", path.c_str(), s.storage.c_str());
  std::printf("messages       %" PRIu64 " over %.3f s", s.messages, s.durationSeconds());
  if (s.messages > 0) {
    std::printf(" (log time %" PRId64 ".%09" PRId64 " to %" PRId64 ".%09" PRId64 " s)",
                s.start_ns / 1000000000, s.start_ns % 1000000000, s.end_ns / 1000000000,
                s.end_ns % 1000000000);
  }
  std::printf("%s\ntopics         %zu\n", s.from_summary ? " (from the file's summary)" : "",
              s.topics.size());
  for (const bag::TopicSummary& topic : s.topics) {
    char bytes[32] = "";
    if (!s.from_summary) {
      std::snprintf(bytes, sizeof(bytes), "  %.3f MB", static_cast<double>(topic.bytes) / 1e6);
    }
    std::printf("  %-28s %-32s %8" PRIu64 " messages%s  %s\n", topic.topic.name.c_str(),
                topic.topic.type.c_str(), topic.messages, bytes,
                topic.topic.serialization_format.c_str());
  }
}

}  // namespace

int runBagInfo(const std::string& path, bool json, bool full) {
  const Result<bag::BagSummary> summary = bag::summariseBag(path, full);
  if (!summary) {
    printError("info", summary.error().message);
    return kExitFailure;
  }
  if (json) {
    printBagJson(path, *summary);
  } else {
    printBagText(path, *summary);
  }
  for (const std::string& warning : summary->warnings) {
    std::fprintf(stderr, "raymap info: warning: %s\n", withCliFlags(warning).c_str());
  }
  return 0;
}

}  // namespace raymap::cli
