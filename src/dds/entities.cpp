// SPDX-License-Identifier: BSD-3-Clause
// The RAII entity owners over Cyclone's C API and the QoS that ROS 2 peers match.
#include "src/dds/entities.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include <dds/ddsi/ddsi_serdata.h>

namespace raymap::dds {
namespace {

std::string describe(const char* what, const char* topic_name, dds_return_t code) {
  std::string message = what;
  if (topic_name != nullptr) {
    message += " for topic \"";
    message += topic_name;
    message += "\"";
  }
  message += ": ";
  message += dds_strretcode(code);
  return message;
}

/// describe() for a topic, reader or writer, naming the permissions document and `use`
/// ("publishing") when DDS Security refused it.
std::string describeEndpoint(const Participant& participant, const char* what, const char* use,
                             const char* topic_name, dds_return_t code) {
  if (code == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && !participant.permissionsFile().empty()) {
    return participant.permissionsFile() + ": the enclave's permissions do not allow " + use +
           " \"" + topic_name + "\" (DDS Security refused " + what + ")";
  }
  return describe(what, topic_name, code);
}

/// The participant QoS that turns on Cyclone's DDS Security plugins with an enclave's files.
dds_qos_t* makeSecureParticipantQos(const SecurityFiles& files) {
  dds_qos_t* qos = dds_create_qos();
  const auto file = [](const std::string& path) { return "file:" + path; };
  dds_qset_prop(qos, "dds.sec.auth.library.path", "dds_security_auth");
  dds_qset_prop(qos, "dds.sec.auth.library.init", "init_authentication");
  dds_qset_prop(qos, "dds.sec.auth.library.finalize", "finalize_authentication");
  dds_qset_prop(qos, "dds.sec.crypto.library.path", "dds_security_crypto");
  dds_qset_prop(qos, "dds.sec.crypto.library.init", "init_crypto");
  dds_qset_prop(qos, "dds.sec.crypto.library.finalize", "finalize_crypto");
  dds_qset_prop(qos, "dds.sec.access.library.path", "dds_security_ac");
  dds_qset_prop(qos, "dds.sec.access.library.init", "init_access_control");
  dds_qset_prop(qos, "dds.sec.access.library.finalize", "finalize_access_control");
  dds_qset_prop(qos, "dds.sec.auth.identity_ca", file(files.identity_ca).c_str());
  dds_qset_prop(qos, "dds.sec.auth.identity_certificate", file(files.certificate).c_str());
  dds_qset_prop(qos, "dds.sec.auth.private_key", file(files.private_key).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions_ca", file(files.permissions_ca).c_str());
  dds_qset_prop(qos, "dds.sec.access.governance", file(files.governance).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions", file(files.permissions).c_str());
  return qos;
}

void deleteEntity(dds_entity_t entity) noexcept {
  if (entity > 0) {
    // ALREADY_DELETED when the participant went first: nothing left to do.
    static_cast<void>(dds_delete(entity));
  }
}

/// The QoS both sides share: keep-last depth, volatile, XCDR1, and the reliability asked for.
dds_qos_t* makeQos(Reliability reliability, std::int32_t depth, Durability durability) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos,
                       reliability == Reliability::kReliable ? DDS_RELIABILITY_RELIABLE
                                                             : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(100));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(qos, durability == Durability::kTransientLocal
                               ? DDS_DURABILITY_TRANSIENT_LOCAL
                               : DDS_DURABILITY_VOLATILE);
  // ROS 2 (rmw_cyclonedds) accepts only XCDR1; an XCDR2 writer does not match its readers.
  dds_data_representation_id_t xcdr1[1] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos, 1, xcdr1);
  return qos;
}

/// Creates the topic of a reader or writer; `*topic` is set on success.
Result<void> createTopic(const Participant& participant, const char* topic_name,
                         const dds_topic_descriptor_t* descriptor, std::int32_t depth,
                         dds_entity_t* topic) {
  if (topic_name == nullptr || descriptor == nullptr || depth < 1) {
    return fail(ErrorCode::kInvalidArgument,
                "dds: a topic needs a name, a type and a history depth >= 1");
  }
  const dds_entity_t created =
      dds_create_topic(participant.handle(), descriptor, topic_name, nullptr, nullptr);
  if (created < 0) {
    return fail(ErrorCode::kInvalidArgument,
                describeEndpoint(participant, "dds_create_topic", "publishing or subscribing to",
                                 topic_name, created));
  }
  *topic = created;
  return {};
}

/// Cyclone XML for `settings` ("" when they ask for nothing).
std::string domainConfiguration(const DomainSettings& settings) {
  std::string internal;
  if (settings.receive_buffer_bytes > 0) {
    internal +=
        "<SocketReceiveBufferSize min=\"" + std::to_string(settings.receive_buffer_bytes) + "B\"/>";
  }
  if (settings.repair_burst_bytes > 0) {
    const std::string burst = std::to_string(settings.repair_burst_bytes) + "B";
    internal += "<BurstSize><MaxRexmit>" + burst +
                "</MaxRexmit></BurstSize>"
                "<MaxQueuedRexmitBytes>4MiB</MaxQueuedRexmitBytes>"
                "<HeartbeatInterval min=\"1ms\" minsched=\"2ms\">5ms</HeartbeatInterval>";
  }
  if (internal.empty()) {
    return {};
  }
  return "<CycloneDDS><Domain Id=\"any\"><Internal>" + internal +
         "</Internal></Domain></CycloneDDS>";
}

}  // namespace

// ---- Participant ----

Result<Participant> Participant::create(std::uint32_t domain_id, const DomainSettings& settings) {
  if (domain_id >= DDS_DOMAIN_DEFAULT) {
    return fail(ErrorCode::kInvalidArgument, "dds: domain id out of range");
  }
  dds_entity_t domain = 0;
  if (const std::string ours = domainConfiguration(settings); !ours.empty()) {
    // Cyclone reads a list of configuration sources in order, a later one overriding an
    // earlier one: ours first, then whatever CYCLONEDDS_URI names.
    std::string config = ours;
    if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri != nullptr && uri[0] != '\0') {
      config += ",";
      config += uri;
    }
    domain = dds_create_domain(domain_id, config.c_str());
    if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {
      domain = 0;  // this process already has the domain, configured when it was created
    } else if (domain < 0) {
      std::string what = "dds_create_domain (check CYCLONEDDS_URI";
      if (settings.receive_buffer_bytes > 0) {
        what += ", and that the kernel allows a receive buffer of " +
                std::to_string(settings.receive_buffer_bytes) + " bytes: net.core.rmem_max";
      }
      what += ")";
      return fail(ErrorCode::kIo, describe(what.c_str(), nullptr, domain));
    }
  }
  dds_qos_t* qos =
      settings.security.enabled() ? makeSecureParticipantQos(settings.security) : nullptr;
  const dds_entity_t handle = dds_create_participant(domain_id, qos, nullptr);
  dds_delete_qos(qos);
  if (handle < 0) {
    deleteEntity(domain);
    if (settings.security.enabled()) {
      // Cyclone's security plugins say why on stderr (its log); they refuse files they cannot
      // use and a domain the governance does not list.
      return fail(
          ErrorCode::kIo,
          describe(("dds_create_participant with DDS Security (certificate " +
                    settings.security.certificate + ", governance " + settings.security.governance +
                    ", permissions " + settings.security.permissions +
                    "; does the governance cover domain " + std::to_string(domain_id) + "?)")
                       .c_str(),
                   nullptr, handle));
    }
    return fail(ErrorCode::kIo,
                describe("dds_create_participant (check CYCLONEDDS_URI)", nullptr, handle));
  }
  return Participant(handle, domain, settings.security.permissions);
}

bool Participant::waitForAcknowledgements(std::int64_t timeout_ns) const noexcept {
  // Writers belong to publishers (an implicit one when created on the participant): waiting on
  // a publisher waits for all of its writers.
  constexpr std::size_t kMaxChildren = 64;
  dds_entity_t children[kMaxChildren] = {};
  const dds_return_t n = dds_get_children(handle_, children, kMaxChildren);
  if (n < 0) {
    return false;
  }
  const dds_time_t deadline = dds_time() + timeout_ns;
  bool all = true;
  for (dds_return_t i = 0; i < n && i < static_cast<dds_return_t>(kMaxChildren); ++i) {
    // Cyclone 0.10 has no entity-kind query: a subscriber or a topic refuses the call
    // (ILLEGAL_OPERATION or BAD_PARAMETER), only a publisher can time out.
    const dds_duration_t left = std::max<dds_duration_t>(0, deadline - dds_time());
    if (dds_wait_for_acks(children[i], left) == DDS_RETCODE_TIMEOUT) {
      all = false;
    }
  }
  return all;
}

Participant& Participant::operator=(Participant&& other) noexcept {
  if (this != &other) {
    deleteEntity(handle_);
    deleteEntity(domain_);
    handle_ = std::exchange(other.handle_, 0);
    domain_ = std::exchange(other.domain_, 0);
    permissions_ = std::move(other.permissions_);
  }
  return *this;
}

Participant::~Participant() {
  deleteEntity(handle_);
  deleteEntity(domain_);
}

// ---- RawReader ----

Result<RawReader> RawReader::create(const Participant& participant, const char* topic_name,
                                    const dds_topic_descriptor_t* descriptor,
                                    Reliability reliability, std::int32_t depth,
                                    Durability durability, Origin origin) {
  dds_entity_t topic = 0;
  if (auto created = createTopic(participant, topic_name, descriptor, depth, &topic); !created) {
    return Unexpected(std::move(created).error());
  }
  dds_qos_t* qos = makeQos(reliability, depth, durability);
  if (origin == Origin::kOtherParticipants) {
    dds_qset_ignorelocal(qos, DDS_IGNORELOCAL_PARTICIPANT);
  }
  const dds_entity_t reader = dds_create_reader(participant.handle(), topic, qos, nullptr);
  dds_delete_qos(qos);
  if (reader < 0) {
    deleteEntity(topic);
    return fail(
        ErrorCode::kInvalidArgument,
        describeEndpoint(participant, "dds_create_reader", "subscribing to", topic_name, reader));
  }
  return RawReader(topic, reader);
}

RawReader& RawReader::operator=(RawReader&& other) noexcept {
  if (this != &other) {
    deleteEntity(reader_);
    deleteEntity(topic_);
    topic_ = std::exchange(other.topic_, 0);
    reader_ = std::exchange(other.reader_, 0);
  }
  return *this;
}

RawReader::~RawReader() {
  deleteEntity(reader_);
  deleteEntity(topic_);
}

HeldSample& HeldSample::operator=(HeldSample&& other) noexcept {
  if (this != &other) {
    reset();
    sample_ = std::exchange(other.sample_, nullptr);
    ref_ = std::exchange(other.ref_, nullptr);
    ref_base_ = std::exchange(other.ref_base_, nullptr);
    bytes_ = std::exchange(other.bytes_, {});
    source_timestamp_ns_ = other.source_timestamp_ns_;
    writer_handle_ = other.writer_handle_;
  }
  return *this;
}

void HeldSample::reset() noexcept {
  if (ref_ != nullptr) {
    ddsrt_iovec_t ref{};
    ref.iov_base = ref_base_;
    ref.iov_len = static_cast<decltype(ref.iov_len)>(bytes_.size());
    ddsi_serdata_to_ser_unref(ref_, &ref);
    ref_ = nullptr;
    ref_base_ = nullptr;
  }
  if (sample_ != nullptr) {
    ddsi_serdata_unref(sample_);
    sample_ = nullptr;
  }
  bytes_ = {};
}

int RawReader::takeHeld(HeldSampleFn fn, void* context, int max_samples) noexcept {
  // Samples are taken in small batches into a stack array: no allocation on our side.
  constexpr int kBatch = 16;
  struct ddsi_serdata* samples[kBatch];
  dds_sample_info_t infos[kBatch];
  int delivered = 0;
  int remaining = max_samples;
  while (remaining > 0) {
    const int batch = remaining < kBatch ? remaining : kBatch;
    for (int i = 0; i < batch; ++i) {
      samples[i] = nullptr;
    }
    const dds_return_t taken =
        dds_takecdr(reader_, samples, static_cast<std::uint32_t>(batch), infos, DDS_ANY_STATE);
    if (taken < 0) {
      return delivered > 0 ? delivered : taken;
    }
    for (int i = 0; i < taken; ++i) {
      HeldSample held;
      held.sample_ = samples[i];  // given back by `held` whatever happens below
      if (!infos[i].valid_data) {
        continue;
      }
      // The default serdata is one contiguous block: the 4-byte encapsulation header followed
      // by the payload, and ddsi_serdata_size() counts both. to_ser_ref hands out a reference
      // to it (no copy, no allocation).
      const std::uint32_t size = ddsi_serdata_size(samples[i]);
      ddsrt_iovec_t ref{};
      held.ref_ = ddsi_serdata_to_ser_ref(samples[i], 0, size, &ref);
      if (held.ref_ == nullptr) {
        continue;
      }
      held.ref_base_ = ref.iov_base;
      held.bytes_ = std::span<const std::byte>(static_cast<const std::byte*>(ref.iov_base),
                                               static_cast<std::size_t>(ref.iov_len));
      held.source_timestamp_ns_ = infos[i].source_timestamp;
      held.writer_handle_ = infos[i].publication_handle;
      fn(context, held);
      ++delivered;
    }
    remaining -= taken;
    if (taken < batch) {
      break;
    }
  }
  return delivered;
}

int RawReader::take(SampleFn fn, void* context, int max_samples) noexcept {
  struct Forward {
    SampleFn fn;
    void* context;
  } forward{fn, context};
  return takeHeld(
      [](void* c, HeldSample& sample) {
        const auto* f = static_cast<const Forward*>(c);
        f->fn(f->context, sample.bytes(), sample.sourceTimestampNs());
      },
      &forward, max_samples);
}

std::uint32_t RawReader::matchedWriters() const noexcept {
  dds_subscription_matched_status_t status{};
  if (dds_get_subscription_matched_status(reader_, &status) < 0) {
    return 0;
  }
  return status.current_count;
}

void RawReader::describeMatchedWriters(char* out, std::size_t size) const noexcept {
  if (size == 0) {
    return;
  }
  out[0] = '\0';
  dds_instance_handle_t handles[8];
  const dds_return_t n = dds_get_matched_publications(reader_, handles, 8);
  std::size_t used = 0;
  for (dds_return_t i = 0; i < n && i < 8 && used + 1 < size; ++i) {
    dds_builtintopic_endpoint_t* writer = dds_get_matched_publication_data(reader_, handles[i]);
    if (writer == nullptr) {
      continue;  // it left meanwhile
    }
    char guid[25] = {};
    for (int b = 0; b < 12; ++b) {  // the GUID prefix: host, process, participant
      std::snprintf(guid + 2 * b, 3, "%02x", writer->participant_key.v[b]);
    }
    char* name = nullptr;
    const bool named = writer->qos != nullptr && dds_qget_entity_name(writer->qos, &name) &&
                       name != nullptr && name[0] != '\0';
    const int wrote =
        std::snprintf(out + used, size - used, "%sparticipant %s%s%s%s", used == 0 ? "" : ", ",
                      guid, named ? " (" : "", named ? name : "", named ? ")" : "");
    used = wrote > 0 ? std::min(size - 1, used + static_cast<std::size_t>(wrote)) : used;
    dds_free(name);
    dds_builtintopic_free_endpoint(writer);
  }
}

// ---- Writer ----

Result<Writer> Writer::create(const Participant& participant, const char* topic_name,
                              const dds_topic_descriptor_t* descriptor, Reliability reliability,
                              std::int32_t depth, Durability durability) {
  dds_entity_t topic = 0;
  if (auto created = createTopic(participant, topic_name, descriptor, depth, &topic); !created) {
    return Unexpected(std::move(created).error());
  }
  dds_qos_t* qos = makeQos(reliability, depth, durability);
  dds_qset_writer_data_lifecycle(qos, false);  // no autodispose, as rmw_cyclonedds
  const dds_entity_t writer = dds_create_writer(participant.handle(), topic, qos, nullptr);
  dds_delete_qos(qos);
  if (writer < 0) {
    deleteEntity(topic);
    return fail(ErrorCode::kInvalidArgument, describeEndpoint(participant, "dds_create_writer",
                                                              "publishing", topic_name, writer));
  }
  return Writer(topic, writer);
}

Writer& Writer::operator=(Writer&& other) noexcept {
  if (this != &other) {
    deleteEntity(writer_);
    deleteEntity(topic_);
    topic_ = std::exchange(other.topic_, 0);
    writer_ = std::exchange(other.writer_, 0);
  }
  return *this;
}

Writer::~Writer() {
  deleteEntity(writer_);
  deleteEntity(topic_);
}

Expected<void, DdsError> Writer::write(const void* sample) noexcept {
  const dds_return_t code = dds_write(writer_, sample);
  if (code < 0) {
    return Unexpected(ddsErrorFromReturnCode(code));
  }
  return {};
}

Expected<void, DdsError> Writer::writeWithTimestamp(const void* sample,
                                                    std::int64_t source_timestamp_ns) noexcept {
  const dds_return_t code = dds_write_ts(writer_, sample, source_timestamp_ns);
  if (code < 0) {
    return Unexpected(ddsErrorFromReturnCode(code));
  }
  return {};
}

std::uint32_t Writer::matchedReaders() const noexcept {
  dds_publication_matched_status_t status{};
  if (dds_get_publication_matched_status(writer_, &status) < 0) {
    return 0;
  }
  return status.current_count;
}

// ---- Waitset ----

Result<Waitset> Waitset::create(const Participant& participant) {
  const dds_entity_t waitset = dds_create_waitset(participant.handle());
  if (waitset < 0) {
    return fail(ErrorCode::kInvalidArgument, describe("dds_create_waitset", nullptr, waitset));
  }
  // Attached to itself, the waitset triggers on dds_waitset_set_trigger: that is wake().
  const dds_return_t attached = dds_waitset_attach(waitset, waitset, kWakeToken);
  if (attached < 0) {
    deleteEntity(waitset);
    return fail(ErrorCode::kInvalidArgument, describe("dds_waitset_attach", nullptr, attached));
  }
  return Waitset(waitset);
}

Waitset& Waitset::operator=(Waitset&& other) noexcept {
  if (this != &other) {
    deleteEntity(waitset_);
    waitset_ = std::exchange(other.waitset_, 0);
  }
  return *this;
}

Waitset::~Waitset() { deleteEntity(waitset_); }

Result<void> Waitset::attach(dds_entity_t reader, std::intptr_t token) {
  if (token == kWakeToken) {
    return fail(ErrorCode::kInvalidArgument, "dds: Waitset::attach token kWakeToken is reserved");
  }
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (condition < 0) {
    return fail(ErrorCode::kInvalidArgument,
                describe("dds_create_readcondition", nullptr, condition));
  }
  const dds_return_t attached = dds_waitset_attach(waitset_, condition, token);
  if (attached < 0) {
    deleteEntity(condition);
    return fail(ErrorCode::kInvalidArgument, describe("dds_waitset_attach", nullptr, attached));
  }
  return {};
}

int Waitset::wait(std::int64_t timeout_ns, std::span<std::intptr_t> triggered) noexcept {
  constexpr std::size_t kMaxTriggered = 16;
  dds_attach_t tokens[kMaxTriggered];
  const dds_return_t count =
      dds_waitset_wait(waitset_, tokens, kMaxTriggered, timeout_ns < 0 ? 0 : timeout_ns);
  if (count <= 0) {
    return count;
  }
  const std::size_t reported = static_cast<std::size_t>(count) < kMaxTriggered
                                   ? static_cast<std::size_t>(count)
                                   : kMaxTriggered;
  std::size_t written = 0;
  for (std::size_t i = 0; i < reported; ++i) {
    if (tokens[i] == kWakeToken) {
      static_cast<void>(dds_waitset_set_trigger(waitset_, false));
    }
    if (written < triggered.size()) {
      triggered[written] = tokens[i];
      ++written;
    }
  }
  return static_cast<int>(written);
}

void Waitset::wake() noexcept { static_cast<void>(dds_waitset_set_trigger(waitset_, true)); }

}  // namespace raymap::dds
