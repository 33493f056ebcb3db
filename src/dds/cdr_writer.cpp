// SPDX-License-Identifier: BSD-3-Clause
// CdrWriter: serialized samples written with dds_writecdr through the topic type's sertype.
#include "src/dds/cdr_writer.hpp"

#include <cstdlib>
#include <string>
#include <utility>

#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>

namespace raymap::dds {
namespace {

constexpr const char* kProbeTopic = "raymap_internal/cdr_probe";

/// Deletes a Cyclone entity on scope exit.
struct EntityGuard {
  dds_entity_t entity = 0;
  ~EntityGuard() {
    if (entity > 0) {
      dds_delete(entity);
    }
  }
};

/// The sertype Cyclone uses for `descriptor` in the participant's domain: a zero-initialised
/// sample (empty strings and sequences) written on the probe topic is taken back as serialized
/// data from a local reader, and the serdata names its type. Sertypes are shared per domain by
/// type, so it is the same object the real writer's topic uses.
Result<const ddsi_sertype*> probeSertype(const Participant& participant,
                                         const dds_topic_descriptor_t* descriptor) {
  EntityGuard topic{
      dds_create_topic(participant.handle(), descriptor, kProbeTopic, nullptr, nullptr)};
  if (topic.entity < 0) {
    return fail(ErrorCode::kIo, std::string(kProbeTopic) + ": cannot create the probe topic: " +
                                    dds_strretcode(topic.entity));
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_data_representation_id_t xcdr1[1] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos, 1, xcdr1);
  EntityGuard reader{dds_create_reader(participant.handle(), topic.entity, qos, nullptr)};
  EntityGuard writer{dds_create_writer(participant.handle(), topic.entity, qos, nullptr)};
  dds_delete_qos(qos);
  if (reader.entity < 0 || writer.entity < 0) {
    return fail(ErrorCode::kIo, std::string(kProbeTopic) + ": cannot create the probe endpoints");
  }
  void* sample = std::calloc(1, descriptor->m_size);
  if (sample == nullptr) {
    return fail(ErrorCode::kIo, "out of memory for the probe sample");
  }
  const dds_return_t written = dds_write(writer.entity, sample);
  std::free(sample);
  if (written < 0) {
    return fail(ErrorCode::kIo,
                std::string(kProbeTopic) + ": probe write failed: " + dds_strretcode(written));
  }
  ddsi_serdata* taken = nullptr;
  dds_sample_info_t info;
  const dds_return_t n = dds_takecdr(reader.entity, &taken, 1, &info, DDS_ANY_STATE);
  if (n != 1 || taken == nullptr) {
    return fail(ErrorCode::kIo, std::string(kProbeTopic) +
                                    ": the probe sample did not come back from the local reader");
  }
  const ddsi_sertype* type = ddsi_sertype_ref(taken->type);
  ddsi_serdata_unref(taken);
  return type;
}

}  // namespace

Result<CdrWriter> CdrWriter::create(const Participant& participant, const char* topic_name,
                                    const dds_topic_descriptor_t* descriptor,
                                    Reliability reliability, std::int32_t depth,
                                    Durability durability) {
  auto writer = Writer::create(participant, topic_name, descriptor, reliability, depth, durability);
  if (!writer) {
    return Unexpected(std::move(writer).error());
  }
  auto sertype = probeSertype(participant, descriptor);
  if (!sertype) {
    return Unexpected(std::move(sertype).error());
  }
  return CdrWriter(std::move(writer).value(), sertype.value());
}

CdrWriter::CdrWriter(Writer writer, const ddsi_sertype* sertype) noexcept
    : writer_(std::move(writer)), sertype_(sertype) {}

CdrWriter::CdrWriter(CdrWriter&& other) noexcept
    : writer_(std::move(other.writer_)), sertype_(std::exchange(other.sertype_, nullptr)) {
  other.writer_.reset();
}

CdrWriter& CdrWriter::operator=(CdrWriter&& other) noexcept {
  if (this != &other) {
    if (sertype_ != nullptr) {
      // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): Cyclone's API
      ddsi_sertype_unref(const_cast<ddsi_sertype*>(sertype_));
    }
    writer_ = std::move(other.writer_);
    other.writer_.reset();
    sertype_ = std::exchange(other.sertype_, nullptr);
  }
  return *this;
}

CdrWriter::~CdrWriter() {
  writer_.reset();
  if (sertype_ != nullptr) {
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): Cyclone's API
    ddsi_sertype_unref(const_cast<ddsi_sertype*>(sertype_));
  }
}

Expected<void, CdrWriteError> CdrWriter::write(std::span<const std::byte> cdr,
                                               DdsError* dds_error) noexcept {
  ddsrt_iovec_t iov;
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read only by Cyclone
  iov.iov_base = const_cast<std::byte*>(cdr.data());
  iov.iov_len = static_cast<ddsrt_iov_len_t>(cdr.size());
  // Validates the bytes against the type (NULL when they do not decode) and copies them.
  ddsi_serdata* data = ddsi_serdata_from_ser_iov(sertype_, SDK_DATA, 1, &iov, cdr.size());
  if (data == nullptr) {
    return Unexpected(CdrWriteError::kNotDecodable);
  }
  const dds_return_t code = dds_writecdr(writer_->handle(), data);  // takes the reference
  if (code < 0) {
    if (dds_error != nullptr) {
      *dds_error = ddsErrorFromReturnCode(code);
    }
    return Unexpected(CdrWriteError::kDds);
  }
  return {};
}

}  // namespace raymap::dds
