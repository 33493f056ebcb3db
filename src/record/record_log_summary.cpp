// SPDX-License-Identifier: BSD-3-Clause
// RecordLogReader::summarize(): one checked pass over a log for replay's summary and time range.
#include <cstddef>
#include <utility>

#include "src/record/record_log_reader.hpp"

namespace raymap::record {

Result<RecordLogReader::Summary> RecordLogReader::summarize(const std::string& path) {
  auto opened = open(path);
  if (!opened) {
    return Unexpected(std::move(opened).error());
  }
  RecordLogReader& reader = **opened;
  Summary summary;
  bool any = false;
  for (;;) {
    auto message = reader.next();
    if (!message) {
      return Unexpected(std::move(message).error());
    }
    if (!*message) {
      break;
    }
    const LogMessage& m = **message;
    if (summary.messages_per_topic.size() <= m.topic_id) {
      summary.messages_per_topic.resize(std::size_t{m.topic_id} + 1, 0);
    }
    ++summary.messages_per_topic[m.topic_id];
    if (!any) {
      summary.first_receive_unix_ns = m.receive_unix_ns;
      any = true;
    }
    summary.last_receive_unix_ns = m.receive_unix_ns;
  }
  summary.topics = reader.topics();
  summary.messages_per_topic.resize(summary.topics.size(), 0);
  summary.complete = reader.complete();
  summary.truncation = reader.truncation();
  return summary;
}

}  // namespace raymap::record
