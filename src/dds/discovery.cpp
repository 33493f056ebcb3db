// SPDX-License-Identifier: BSD-3-Clause
// Discovery over the built-in topics: loaned dds_read of the alive instances, QoS decoded from
// each endpoint's announced policies.
#include "src/dds/discovery.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <iterator>
#include <thread>

namespace raymap::dds {
namespace {

void deleteEntity(dds_entity_t entity) noexcept {
  if (entity > 0) {
    // ALREADY_DELETED when the participant went first: nothing left to do.
    static_cast<void>(dds_delete(entity));
  }
}

std::array<std::uint8_t, 16> guidBytes(const dds_guid_t& guid) noexcept {
  std::array<std::uint8_t, 16> bytes{};
  static_assert(sizeof(guid.v) == 16);
  std::memcpy(bytes.data(), guid.v, bytes.size());
  return bytes;
}

/// The announced QoS of an endpoint; a policy that is absent keeps the DDS default (writers:
/// reliable, readers: best effort; volatile; XCDR1).
void decodeQos(const dds_qos_t* qos, DiscoveredEndpoint& out) {
  out.reliability = out.is_writer ? Reliability::kReliable : Reliability::kBestEffort;
  out.durability = Durability::kVolatile;
  out.xcdr1 = true;
  if (qos == nullptr) {
    return;
  }
  dds_reliability_kind_t reliability = DDS_RELIABILITY_BEST_EFFORT;
  dds_duration_t max_blocking = 0;
  if (dds_qget_reliability(qos, &reliability, &max_blocking)) {
    out.reliability =
        reliability == DDS_RELIABILITY_RELIABLE ? Reliability::kReliable : Reliability::kBestEffort;
  }
  dds_durability_kind_t durability = DDS_DURABILITY_VOLATILE;
  if (dds_qget_durability(qos, &durability)) {
    out.durability =
        durability == DDS_DURABILITY_VOLATILE ? Durability::kVolatile : Durability::kTransientLocal;
  }
  std::uint32_t count = 0;
  dds_data_representation_id_t* values = nullptr;
  if (dds_qget_data_representation(qos, &count, &values) && count > 0 && values != nullptr) {
    out.xcdr1 = false;
    for (std::uint32_t i = 0; i < count; ++i) {
      if (values[i] == DDS_DATA_REPRESENTATION_XCDR1) {
        out.xcdr1 = true;
      }
    }
  }
  dds_free(values);  // allocated by dds_qget_data_representation; dds_free(nullptr) is a no-op
}

}  // namespace

Result<Discovery> Discovery::create(const Participant& participant) {
  dds_guid_t own{};
  if (const dds_return_t got = dds_get_guid(participant.handle(), &own); got < 0) {
    return fail(
        ErrorCode::kInvalidArgument,
        std::string("dds: discovery: dds_get_guid of the participant: ") + dds_strretcode(got));
  }
  const dds_entity_t publications =
      dds_create_reader(participant.handle(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (publications < 0) {
    return fail(
        ErrorCode::kInvalidArgument,
        std::string("dds: discovery: reader of DCPSPublication: ") + dds_strretcode(publications));
  }
  const dds_entity_t subscriptions =
      dds_create_reader(participant.handle(), DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr);
  if (subscriptions < 0) {
    deleteEntity(publications);
    return fail(ErrorCode::kInvalidArgument,
                std::string("dds: discovery: reader of DCPSSubscription: ") +
                    dds_strretcode(subscriptions));
  }
  return Discovery(publications, subscriptions, guidBytes(own));
}

Discovery& Discovery::operator=(Discovery&& other) noexcept {
  if (this != &other) {
    deleteEntity(publications_);
    deleteEntity(subscriptions_);
    publications_ = std::exchange(other.publications_, 0);
    subscriptions_ = std::exchange(other.subscriptions_, 0);
    own_participant_ = other.own_participant_;
  }
  return *this;
}

Discovery::~Discovery() {
  deleteEntity(publications_);
  deleteEntity(subscriptions_);
}

void Discovery::readInto(dds_entity_t reader, bool is_writer,
                         std::vector<DiscoveredEndpoint>& out) {
  if (reader <= 0) {
    return;
  }
  // Endpoints that went away are disposed instances: take them, so that they do not pile up in
  // the reader; read the alive ones, which stay for the next call.
  {
    constexpr std::uint32_t kBatch = 64;
    void* samples[kBatch];
    dds_sample_info_t infos[kBatch];
    const std::uint32_t gone_mask = DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE |
                                    DDS_NOT_ALIVE_DISPOSED_INSTANCE_STATE |
                                    DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE;
    for (;;) {
      std::fill(std::begin(samples), std::end(samples), nullptr);  // null: Cyclone lends them
      const dds_return_t taken = dds_take_mask(reader, samples, infos, kBatch, kBatch, gone_mask);
      if (taken <= 0) {
        break;
      }
      static_cast<void>(dds_return_loan(reader, samples, taken));
      if (static_cast<std::uint32_t>(taken) < kBatch) {
        break;
      }
    }
  }
  // One loaned read of every alive instance; when the buffer was full, read again with twice
  // the room (the built-in reader keeps one sample per endpoint).
  const std::uint32_t alive_mask =
      DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE;
  std::size_t capacity = 256;
  for (;;) {
    std::vector<void*> samples(capacity, nullptr);
    std::vector<dds_sample_info_t> infos(capacity);
    const dds_return_t count = dds_read_mask(reader, samples.data(), infos.data(), capacity,
                                             static_cast<std::uint32_t>(capacity), alive_mask);
    if (count < 0) {
      return;
    }
    if (static_cast<std::size_t>(count) == capacity && capacity < (std::size_t{1} << 20)) {
      static_cast<void>(dds_return_loan(reader, samples.data(), count));
      capacity *= 2;
      continue;
    }
    for (dds_return_t i = 0; i < count; ++i) {
      if (!infos[static_cast<std::size_t>(i)].valid_data) {
        continue;
      }
      const auto* e =
          static_cast<const dds_builtintopic_endpoint_t*>(samples[static_cast<std::size_t>(i)]);
      const std::array<std::uint8_t, 16> participant = guidBytes(e->participant_key);
      if (participant == own_participant_) {
        continue;
      }
      DiscoveredEndpoint endpoint;
      endpoint.topic = e->topic_name != nullptr ? e->topic_name : "";
      endpoint.type = e->type_name != nullptr ? e->type_name : "";
      endpoint.is_writer = is_writer;
      endpoint.participant_key = participant;
      decodeQos(e->qos, endpoint);
      out.push_back(std::move(endpoint));
    }
    static_cast<void>(dds_return_loan(reader, samples.data(), count));
    return;
  }
}

std::vector<DiscoveredEndpoint> Discovery::endpoints() {
  std::vector<DiscoveredEndpoint> found;
  readInto(publications_, true, found);
  readInto(subscriptions_, false, found);
  return found;
}

std::optional<DiscoveredEndpoint> waitForWriter(Discovery& discovery, const std::string& topic,
                                                double timeout_s) {
  constexpr auto kPoll = std::chrono::milliseconds(20);
  // At most a year: longer would overflow the clock arithmetic; NaN and negative mean "now".
  constexpr double kMaxTimeoutS = 365.0 * 24 * 3600;
  const double clamped = timeout_s > 0.0 ? std::min(timeout_s, kMaxTimeoutS) : 0.0;
  const auto timeout = std::chrono::duration<double>(clamped);
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
  for (;;) {
    for (DiscoveredEndpoint& endpoint : discovery.endpoints()) {
      if (endpoint.is_writer && endpoint.topic == topic) {
        return std::move(endpoint);
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) {
      return std::nullopt;
    }
    std::this_thread::sleep_for(
        std::min<std::chrono::steady_clock::duration>(kPoll, deadline - now));
  }
}

}  // namespace raymap::dds
