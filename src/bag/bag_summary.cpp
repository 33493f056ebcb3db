// SPDX-License-Identifier: BSD-3-Clause
// summariseBag: a bag's stated statistics (an indexed MCAP summary), or one pass counting its
// messages.
#include "src/bag/bag_summary.hpp"

#include <algorithm>
#include <limits>
#include <optional>

namespace raymap::bag {
namespace {

void takeStatedCounts(const BagStatistics& stated, BagSummary& summary) {
  summary.from_summary = true;
  summary.messages = stated.messages;
  if (summary.messages > 0) {
    summary.start_ns = stated.start_ns;
    summary.end_ns = stated.end_ns;
  }
  for (std::size_t i = 0; i < summary.topics.size() && i < stated.topic_messages.size(); ++i) {
    summary.topics[i].messages = stated.topic_messages[i];
  }
}

Expected<void, Error> countEveryMessage(BagReader& reader, BagSummary& summary) {
  std::int64_t first = std::numeric_limits<std::int64_t>::max();
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  auto pass = reader.forEach([&](const BagMessage& m) {
    if (m.topic < summary.topics.size()) {
      ++summary.topics[m.topic].messages;
      summary.topics[m.topic].bytes += m.data.size();
    }
    first = std::min(first, m.log_time_ns);
    last = std::max(last, m.log_time_ns);
    return true;
  });
  if (!pass) {
    return Unexpected(pass.error());
  }
  summary.messages = pass->messages;
  if (summary.messages > 0) {
    summary.start_ns = first;
    summary.end_ns = last;
  }
  summary.truncated = pass->truncated;
  summary.warnings.insert(summary.warnings.end(), pass->damage.begin(), pass->damage.end());
  return {};
}

}  // namespace

Result<BagSummary> summariseBag(const std::string& path, bool count_messages) {
  // A description reads what a damaged bag holds and says what is damaged.
  BagReadOptions options;
  options.skip_damaged = true;
  auto bag = openBag(path, options);
  if (!bag) {
    return Unexpected(bag.error());
  }
  BagReader& reader = *bag.value();
  BagSummary summary;
  summary.storage = reader.storage();
  for (const BagTopic& topic : reader.topics()) {
    summary.topics.push_back(TopicSummary{topic, 0, 0});
  }
  summary.warnings = reader.openWarnings();
  const std::optional<BagStatistics> stated = count_messages ? std::nullopt : reader.statistics();
  if (stated) {
    takeStatedCounts(*stated, summary);
    return summary;
  }
  if (auto counted = countEveryMessage(reader, summary); !counted) {
    return Unexpected(counted.error());
  }
  return summary;
}

}  // namespace raymap::bag
