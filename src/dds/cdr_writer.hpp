// SPDX-License-Identifier: BSD-3-Clause
// A writer that sends samples given as serialized XCDR1 bytes, unchanged: the bytes a recorder
// took with dds_takecdr go back on the wire as they were (raymap replay of a record log).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "raymap/error.hpp"
#include <dds/dds.h>

#include "src/dds/entities.hpp"

struct ddsi_sertype;

namespace raymap::dds {

/// Why CdrWriter::write() refused a sample.
enum class CdrWriteError : std::uint8_t {
  kNotDecodable,  ///< the bytes are not a valid serialization of the writer's type
  kDds,           ///< Cyclone refused the write (see the DdsError)
};

/// @brief A Writer (same QoS rules) whose samples are serialized bytes: each payload is checked
/// against the type by Cyclone (dds_stream_normalize) and sent as is, encapsulation header
/// included, so a reader receives exactly the bytes that were recorded.
///
/// Cyclone 0.10 builds a serialized sample from bytes only through the topic's sertype, which
/// its public API does not expose for a writer; create() obtains it by writing one empty sample
/// on a private probe topic of the same type ("raymap_internal/cdr_probe") to a local reader in
/// the same participant. The probe writes nothing on the writer's own topic.
/// Thread-safety: write() from one thread at a time. Not for real-time loops (allocates).
class CdrWriter {
 public:
  /// @brief Creates the topic, the writer and the sertype probe. Start-up only.
  static Result<CdrWriter> create(const Participant& participant, const char* topic_name,
                                  const dds_topic_descriptor_t* descriptor, Reliability reliability,
                                  std::int32_t depth,
                                  Durability durability = Durability::kVolatile);
  CdrWriter(CdrWriter&& other) noexcept;
  CdrWriter& operator=(CdrWriter&& other) noexcept;
  CdrWriter(const CdrWriter&) = delete;
  CdrWriter& operator=(const CdrWriter&) = delete;
  ~CdrWriter();

  /// @brief Sends `cdr` (4-byte encapsulation header + XCDR1 body), stamped now.
  /// @return the error, with `dds_error` set when Cyclone refused the write.
  Expected<void, CdrWriteError> write(std::span<const std::byte> cdr,
                                      DdsError* dds_error = nullptr) noexcept;

  std::uint32_t matchedReaders() const noexcept { return writer_->matchedReaders(); }
  dds_entity_t handle() const noexcept { return writer_->handle(); }

 private:
  CdrWriter(Writer writer, const ddsi_sertype* sertype) noexcept;
  std::optional<Writer> writer_;
  const ddsi_sertype* sertype_ = nullptr;  // one reference held
};

}  // namespace raymap::dds
