// SPDX-License-Identifier: BSD-3-Clause
// The subscriptions: one listener per topic takes and decodes in Fast DDS's receive thread; the
// main thread waits and then reports.
#include "tests/fastdds/peer/subscribe_mode.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "platform/socket_buffers.hpp"
#include "tests/fastdds/peer/message_summary.hpp"
#include "tests/fastdds/peer/period_stats.hpp"
#include "tests/fastdds/peer/ros_qos.hpp"
#include "tests/fastdds/peer/stop_signal.hpp"

namespace raymap::fastdds_peer {
namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

namespace {

/// Everything received, guarded by `mutex` (listeners run on Fast DDS's threads).
struct Received {
  std::mutex mutex;
  std::vector<std::int64_t> map_arrivals_ns;  // steady clock
  /// GridMaps the writer wrote but this reader never received (gaps in the writer's sequence
  /// numbers: with keep-last 1 a map not complete when the next is written is dropped).
  std::int64_t maps_skipped = 0;
  std::int64_t last_map_sequence = 0;  // 0: none yet
  std::int64_t costmaps = 0;
  std::int64_t diagnostics = 0;
  std::int64_t diagnostics_after_first_map = 0;  // what they say counts the maps
  GridMapSummary last_map;
  CostmapSummary last_costmap;
  DiagnosticValues values;
};

std::int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

/// Takes every sample of type `Message` when data is available and hands it to `on_message`
/// (message, arrival, the writer's sequence number);
/// notes when the reader first matched a writer.
template <typename Message, typename OnMessage>
class TakingListener : public dds::DataReaderListener {
  using ReturnCode_t = eprosima::fastrtps::types::ReturnCode_t;

 public:
  explicit TakingListener(OnMessage on_message) : on_message_(std::move(on_message)) {}
  /// @brief Steady-clock nanoseconds of the first match, 0 before it.
  std::int64_t matchedNs() const noexcept { return matched_ns_.load(); }
  void on_subscription_matched(dds::DataReader* /*reader*/,
                               const dds::SubscriptionMatchedStatus& status) override {
    std::int64_t none = 0;
    if (status.current_count > 0) {
      matched_ns_.compare_exchange_strong(none, steadyNs());
    }
  }
  void on_data_available(dds::DataReader* reader) override {
    const std::int64_t arrival_ns = steadyNs();      // before decoding
    const std::lock_guard<std::mutex> lock(mutex_);  // in case two receive threads call
    dds::SampleInfo info;
    while (reader->take_next_sample(&message_, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) {
        on_message_(message_, arrival_ns,
                    static_cast<std::int64_t>(info.sample_identity.sequence_number().to64long()));
      }
    }
  }

 private:
  OnMessage on_message_;
  std::atomic<std::int64_t> matched_ns_{0};
  std::mutex mutex_;
  Message message_;
};

template <typename Message, typename OnMessage>
std::unique_ptr<TakingListener<Message, OnMessage>> takingListener(OnMessage on_message) {
  return std::make_unique<TakingListener<Message, OnMessage>>(std::move(on_message));
}

dds::DataReader* makeReader(PeerParticipant& participant, const std::string& topic_name,
                            dds::TopicDataType* type, dds::DataReaderListener& listener) {
  dds::Topic* topic = participant.topic(topic_name, type);
  return topic == nullptr ? nullptr
                          : participant.subscriber().create_datareader(
                                topic, readerQos(RosProfile::kDefault), &listener);
}

std::int64_t matchedWriters(dds::DataReader* reader) {
  dds::SubscriptionMatchedStatus status;
  reader->get_subscription_matched_status(status);
  return status.current_count;
}

bool enough(Received& received, const SubscribeOptions& options) {
  const std::int64_t until = options.until;
  const std::lock_guard<std::mutex> lock(received.mutex);
  const auto maps = static_cast<std::int64_t>(received.map_arrivals_ns.size());
  return until > 0 && maps >= std::max(until, options.min_maps) && received.costmaps >= until &&
         received.diagnostics_after_first_map >= until;
}

/// Milliseconds from `from_ns` to `to_ns`, NaN when either has not happened (0).
double afterMs(std::int64_t from_ns, std::int64_t to_ns) {
  return from_ns == 0 || to_ns == 0 ? std::nan("") : static_cast<double>(to_ns - from_ns) * 1e-6;
}

/// `window_*`: what was measured (from the start or the match to the end).
void report(Received& received, std::int64_t start_ns, std::int64_t matched_ns,
            std::int64_t window_start_ns, std::int64_t window_end_ns, Json& result) {
  const std::lock_guard<std::mutex> lock(received.mutex);
  const std::vector<std::int64_t>& arrivals = received.map_arrivals_ns;
  const PeriodStats period = periodStats(arrivals);
  const std::int64_t first_ns = arrivals.empty() ? 0 : arrivals.front();
  result["grid_map_writer_matched_after_ms"] = afterMs(start_ns, matched_ns);
  result["maps"] = arrivals.size();
  result["maps_skipped"] = received.maps_skipped;
  result["map_period_p50_ms"] = period.p50_ms;
  result["map_period_p99_ms"] = period.p99_ms;
  result["map_period_max_ms"] = period.max_ms;
  result["map_gap_max_ms"] = longestGapMs(arrivals, window_start_ns, window_end_ns);
  result["first_map_after_ms"] = afterMs(start_ns, first_ns);
  result["first_map_after_match_ms"] = afterMs(matched_ns, first_ns);
  result["costmaps"] = received.costmaps;
  result["diagnostics"] = received.diagnostics;
  result["diagnostics_after_first_map"] = received.diagnostics_after_first_map;
  const std::string level = received.values.find(": pipeline", "level");
  result["pipeline_level"] = level.empty() ? -1 : std::stoll(level);
  result["pipeline_message"] = received.values.find(": pipeline", "message");
  if (!arrivals.empty()) {
    result["last_map"] = toJson(received.last_map);
  }
  if (received.costmaps > 0) {
    result["last_costmap"] = toJson(received.last_costmap);
  }
  result["last_diagnostics"] = toJson(received.values);
}

}  // namespace

bool runSubscribe(PeerParticipant& participant, const SubscribeOptions& options, Json& result) {
  const std::int64_t start_ns = steadyNs();
  Received received;
  auto maps = takingListener<grid_map_msgs::msg::dds_::GridMap_>(
      [&received](const grid_map_msgs::msg::dds_::GridMap_& map, std::int64_t arrival_ns,
                  std::int64_t sequence) {
        GridMapSummary summary = summarize(map);
        const std::lock_guard<std::mutex> lock(received.mutex);
        if (received.last_map_sequence > 0 && sequence > received.last_map_sequence + 1) {
          received.maps_skipped += sequence - received.last_map_sequence - 1;
        }
        received.last_map_sequence = sequence;
        received.map_arrivals_ns.push_back(arrival_ns);
        received.last_map = std::move(summary);
      });
  auto costmaps = takingListener<nav_msgs::msg::dds_::OccupancyGrid_>(
      [&received](const nav_msgs::msg::dds_::OccupancyGrid_& costmap, std::int64_t, std::int64_t) {
        CostmapSummary summary = summarize(costmap);
        const std::lock_guard<std::mutex> lock(received.mutex);
        ++received.costmaps;
        received.last_costmap = std::move(summary);
      });
  auto diagnostics = takingListener<diagnostic_msgs::msg::dds_::DiagnosticArray_>(
      [&received](const diagnostic_msgs::msg::dds_::DiagnosticArray_& array, std::int64_t,
                  std::int64_t) {
        const std::lock_guard<std::mutex> lock(received.mutex);
        ++received.diagnostics;
        if (!received.map_arrivals_ns.empty()) {
          ++received.diagnostics_after_first_map;
        }
        received.values.absorb(array);
      });
  dds::DataReader* map_reader = makeReader(
      participant, options.grid_topic, new grid_map_msgs::msg::dds_::GridMap_PubSubType(), *maps);
  dds::DataReader* costmap_reader =
      makeReader(participant, options.costmap_topic,
                 new nav_msgs::msg::dds_::OccupancyGrid_PubSubType(), *costmaps);
  dds::DataReader* diagnostics_reader =
      makeReader(participant, options.diagnostics_topic,
                 new diagnostic_msgs::msg::dds_::DiagnosticArray_PubSubType(), *diagnostics);
  // No listener may run once this returns: the readers go before their listeners.
  const auto delete_readers = [&] {
    for (dds::DataReader* reader : {map_reader, costmap_reader, diagnostics_reader}) {
      if (reader != nullptr) {
        participant.subscriber().delete_datareader(reader);
      }
    }
  };
  if (map_reader == nullptr || costmap_reader == nullptr || diagnostics_reader == nullptr) {
    delete_readers();
    result["error"] = "Fast DDS refused a reader";
    return false;
  }
  // Every socket exists once the participant does: count what the kernel drops from here on.
  raymap::platform::UdpDrops socket_drops = raymap::platform::UdpDrops::ofThisProcess();
  const std::uint64_t drops_before = socket_drops.total();
  const auto run = std::chrono::nanoseconds(std::llround(options.seconds * 1e9));
  Clock::time_point end = Clock::now() + run;
  bool window_from_match = options.from_match;
  while (Clock::now() < end && !stopRequested() && !enough(received, options)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (window_from_match && maps->matchedNs() != 0) {
      end = Clock::time_point(std::chrono::nanoseconds(maps->matchedNs())) + run;
      window_from_match = false;
    }
  }
  const std::int64_t writers[3] = {matchedWriters(map_reader), matchedWriters(costmap_reader),
                                   matchedWriters(diagnostics_reader)};
  const std::uint64_t drops_after = socket_drops.total();
  delete_readers();
  const std::int64_t end_ns = steadyNs();
  result["seconds"] = static_cast<double>(end_ns - start_ns) * 1e-9;
  const std::int64_t window_start_ns =
      options.from_match && maps->matchedNs() != 0 ? maps->matchedNs() : start_ns;
  report(received, start_ns, maps->matchedNs(), window_start_ns, end_ns, result);
  result["writers"] = {
      {"grid_map", writers[0]},
      {"costmap", writers[1]},
      {"diagnostics", writers[2]},
  };
  // Datagrams the kernel dropped because a socket's buffer was full: fragments of maps that
  // had to be sent again (or were never completed).
  result["socket_sockets"] = socket_drops.sockets();
  result["socket_datagrams_dropped"] = static_cast<std::int64_t>(drops_after - drops_before);
  return true;
}

}  // namespace raymap::fastdds_peer
