// SPDX-License-Identifier: BSD-3-Clause
// RAII owners of Cyclone DDS entities: participant, raw-CDR reader, writer and waitset, with the
// QoS that ROS 2 peers match (XCDR1, keyless topics, volatile, no autodispose).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

#include "raymap/error.hpp"
#include "raymap/expected.hpp"
#include <dds/dds.h>

#include "src/dds/dds_error.hpp"

namespace raymap::dds {

/// @brief The files of an SROS2 enclave that Cyclone's DDS Security plugins read (absolute
/// paths; all empty: no security). Checked beforehand by src/security (enclave_check.hpp).
struct SecurityFiles {
  std::string identity_ca;     ///< identity_ca.cert.pem: the CA that signed every identity
  std::string certificate;     ///< cert.pem: this participant's identity
  std::string private_key;     ///< key.pem: its private key
  std::string permissions_ca;  ///< permissions_ca.cert.pem: the CA that signed both documents
  std::string governance;      ///< governance.p7s: how the domain is protected
  std::string permissions;     ///< permissions.p7s: what this identity may publish and subscribe
  bool enabled() const noexcept { return !certificate.empty(); }
};

/// @brief What a process asks of its DDS domain beyond CYCLONEDDS_URI. Settings of the
/// configuration CYCLONEDDS_URI names win over these.
struct DomainSettings {
  /// Minimum receive buffer of the domain's sockets (bytes; 0: leave it to CYCLONEDDS_URI or
  /// Cyclone's default, which asks for 1 MiB and takes what the kernel gives). Put before the
  /// configuration CYCLONEDDS_URI names, so a size the user's file sets wins. The kernel must
  /// allow it (net.core.rmem_max), or the domain cannot be created.
  std::uint64_t receive_buffer_bytes = 0;
  /// Largest burst of a reliable sample's data resent at once to a reader that missed part of it
  /// (bytes; 0: leave it to Cyclone, which resends up to 1 MiB, or two thirds of a Cyclone
  /// reader's announced buffer, per request). A sample still goes out whole the first time, so a
  /// reader that can take it pays nothing. A reader whose socket buffer is smaller than the
  /// sample (the OS default, 208 KiB on Linux, as rmw_fastrtps and a plain Cyclone file leave it,
  /// against a 0.2-1 MB GridMap) loses the fragments that did not fit; its repairs then come in
  /// bursts it can hold, each as it asks, instead of bursts that overrun it again. The kernel
  /// charges a socket buffer for the memory a datagram occupies, up to twice its size (a 64 KB
  /// datagram on loopback: 128 KiB), so keep it at most a third of the smallest reader buffer.
  /// With it, writers send heartbeats every 5 ms (at least 1 ms apart) while a sample is
  /// unacknowledged, so that readers ask again promptly (Fast DDS readers answer heartbeats,
  /// not the fragment heartbeats after a burst), and the retransmit queue holds 4 MiB (a map for
  /// several readers; Cyclone's default, 512 kB, is less than one map).
  std::uint64_t repair_burst_bytes = 0;
  /// DDS Security for the participant (authentication, access control, encryption as the
  /// governance says), set as participant QoS properties as rmw_cyclonedds sets them. Empty:
  /// none (a participant without security neither hears nor is heard by secure ones).
  SecurityFiles security;
};

/// @brief Owns a domain participant (dds_delete on destruction deletes every entity created
/// under it). Configuration comes from CYCLONEDDS_URI as usual: the service sets that variable
/// from its YAML before it creates the participant. Readers, writers and waitsets created from a
/// participant must be destroyed before it (their handles are then already deleted; their
/// destructors tolerate that).
/// Thread-safety: handle() from any thread; creation and destruction from one thread.
class Participant {
 public:
  /// @brief Creates a participant on `domain_id` (0..232 like ROS_DOMAIN_ID), creating the
  /// domain with `settings` merged into CYCLONEDDS_URI's configuration when they ask for
  /// anything and the process has no participant on that domain yet. Start-up only (allocates,
  /// starts Cyclone's threads, may take tens of milliseconds).
  static Result<Participant> create(std::uint32_t domain_id, const DomainSettings& settings = {});

  Participant(Participant&& other) noexcept
      : handle_(std::exchange(other.handle_, 0)),
        domain_(std::exchange(other.domain_, 0)),
        permissions_(std::move(other.permissions_)) {}
  Participant& operator=(Participant&& other) noexcept;
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  ~Participant();

  dds_entity_t handle() const noexcept { return handle_; }

  /// @brief The permissions document this participant runs under ("" without security): named
  /// in the error when a reader or writer is not allowed by it.
  const std::string& permissionsFile() const noexcept { return permissions_; }

  /// @brief Waits until every matched reader has acknowledged everything the participant's
  /// reliable writers wrote, at most `timeout_ns` (best-effort writers never wait): before a
  /// program that writes and exits deletes its writers, which drops what is unacknowledged.
  /// @return false when it timed out (or a writer was refused). Blocks; not for a real-time loop.
  bool waitForAcknowledgements(std::int64_t timeout_ns) const noexcept;

 private:
  Participant(dds_entity_t handle, dds_entity_t domain, std::string permissions) noexcept
      : handle_(handle), domain_(domain), permissions_(std::move(permissions)) {}
  dds_entity_t handle_ = 0;
  dds_entity_t domain_ = 0;  // the domain this participant created (deleted after it), or 0
  std::string permissions_;
};

/// Reliability QoS. Subscribe to sensor data best effort (matches best-effort and reliable
/// writers, e.g. rclcpp's SensorDataQoS); publish maps reliable (matches both kinds of reader).
enum class Reliability : std::uint8_t { kBestEffort, kReliable };
/// Durability: volatile (only samples written after matching), or transient-local (a late
/// reader also gets the writer's kept history: how ROS 2 latches /tf_static and maps). A
/// transient-local reader matches only transient-local writers.
enum class Durability : std::uint8_t { kVolatile, kTransientLocal };
/// Which writers a reader matches: any, or only those of other participants (a service watching
/// for another publisher of its own output topic).
enum class Origin : std::uint8_t { kAny, kOtherParticipants };

/// @brief Called once per sample by RawReader::take.
/// @param context the pointer given to take()
/// @param cdr the serialized sample including its 4-byte encapsulation header (readable with
///        CdrReader / decodePointCloud2); valid only during the call
/// @param source_timestamp_ns the writer's source timestamp (DDS time, nanoseconds)
using SampleFn = void (*)(void* context, std::span<const std::byte> cdr,
                          std::int64_t source_timestamp_ns);

/// @brief One received sample kept past RawReader::takeHeld's callback without copying it: a
/// reference to Cyclone's receive buffer that is given back on destruction (or reset()). Lets
/// the service hold a scan as received and decode it only once it will be integrated.
/// Thread-safety: none (one owner at a time; moving it hands it over).
/// @rt moving: no allocation; destruction and reset() free Cyclone's buffer (its allocator).
class HeldSample {
 public:
  HeldSample() = default;
  HeldSample(HeldSample&& other) noexcept { *this = std::move(other); }
  HeldSample& operator=(HeldSample&& other) noexcept;
  HeldSample(const HeldSample&) = delete;
  HeldSample& operator=(const HeldSample&) = delete;
  ~HeldSample() { reset(); }

  /// @brief The serialized sample with its 4-byte encapsulation header; empty when none is held.
  std::span<const std::byte> bytes() const noexcept { return bytes_; }
  /// @brief The writer's source timestamp (DDS time, nanoseconds).
  std::int64_t sourceTimestampNs() const noexcept { return source_timestamp_ns_; }
  /// @brief Which writer sent it (its instance handle in this participant; nonzero).
  std::uint64_t writerHandle() const noexcept { return writer_handle_; }
  bool empty() const noexcept { return sample_ == nullptr; }
  /// @brief Gives the buffer back to Cyclone now.
  void reset() noexcept;

 private:
  friend class RawReader;
  struct ddsi_serdata* sample_ = nullptr;  // the taken sample (one reference)
  struct ddsi_serdata* ref_ = nullptr;     // ddsi_serdata_to_ser_ref's reference to its bytes
  void* ref_base_ = nullptr;               // and its iovec's base, as Cyclone wants it back
  std::span<const std::byte> bytes_;
  std::int64_t source_timestamp_ns_ = 0;
  std::uint64_t writer_handle_ = 0;
};

/// @brief Called once per sample by RawReader::takeHeld; may move the sample out to keep it.
using HeldSampleFn = void (*)(void* context, HeldSample& sample);

/// @brief A keep-last reader that hands out samples as serialized XCDR1 bytes, never
/// deserialised into heap-allocated structs (dds_takecdr + ddsi_serdata_to_ser_ref: the bytes
/// are Cyclone's own receive buffer, so a 2 MB cloud is not copied).
/// Thread-safety: take() from one thread at a time; handle() from any.
class RawReader {
 public:
  /// @brief Creates a topic and a reader on it. Start-up only (allocates).
  /// @param topic_name the DDS name in full, e.g. "rt/points" for ROS's /points
  /// @param descriptor the idlc type (e.g. pointCloud2Type() from src/dds/topic_types.hpp)
  /// @param depth KEEP_LAST history depth (>= 1)
  static Result<RawReader> create(const Participant& participant, const char* topic_name,
                                  const dds_topic_descriptor_t* descriptor, Reliability reliability,
                                  std::int32_t depth, Durability durability = Durability::kVolatile,
                                  Origin origin = Origin::kAny);

  RawReader(RawReader&& other) noexcept
      : topic_(std::exchange(other.topic_, 0)), reader_(std::exchange(other.reader_, 0)) {}
  RawReader& operator=(RawReader&& other) noexcept;
  RawReader(const RawReader&) = delete;
  RawReader& operator=(const RawReader&) = delete;
  ~RawReader();

  dds_entity_t handle() const noexcept { return reader_; }

  /// @brief Takes up to `max_samples` samples (oldest first) and calls `fn` for each one with
  /// valid data (disposal/unregistration notices are taken and skipped).
  /// @return how many samples were passed to `fn` (0 when none), or a negative dds_return_t
  /// @rt allocates: no on our side (Cyclone frees the taken samples); blocks: on Cyclone's
  /// reader lock only (held briefly by its receive thread).
  int take(SampleFn fn, void* context, int max_samples) noexcept;

  /// @brief take(), handing each sample over as a HeldSample that `fn` may keep (move out);
  /// one it leaves is given back when `fn` returns.
  /// @rt as take(); a kept sample holds its receive buffer until it is destroyed.
  int takeHeld(HeldSampleFn fn, void* context, int max_samples) noexcept;

  /// @brief takeHeld() with a callable `f(HeldSample&)`; the callable must not throw.
  template <class F>
  int takeEachHeld(F&& f, int max_samples) noexcept {
    return takeHeld(
        [](void* context, HeldSample& sample) {
          (*static_cast<std::remove_reference_t<F>*>(context))(sample);
        },
        static_cast<void*>(&f), max_samples);
  }

  /// @brief take() with a callable `f(std::span<const std::byte> cdr, std::int64_t
  /// source_timestamp_ns)`; the callable must not throw.
  template <class F>
  int takeEach(F&& f, int max_samples) noexcept {
    return take(
        [](void* context, std::span<const std::byte> cdr, std::int64_t source_timestamp_ns) {
          (*static_cast<std::remove_reference_t<F>*>(context))(cdr, source_timestamp_ns);
        },
        static_cast<void*>(&f), max_samples);
  }

  /// @brief Writers currently matched (dds_get_subscription_matched_status).
  std::uint32_t matchedWriters() const noexcept;

  /// @brief Names the matched writers into `out` (NUL-terminated, truncated to `size`):
  /// "participant 0f1a2b3c4d5e6f7081928374 (its entity name, when it has one)", ", "-separated,
  /// at most 8. For telling an operator where a second publisher of an input comes from.
  /// @rt allocates: yes (Cyclone copies the discovery data): call it only when
  /// matchedWriters() has found something wrong, never in steady state.
  void describeMatchedWriters(char* out, std::size_t size) const noexcept;

 private:
  RawReader(dds_entity_t topic, dds_entity_t reader) noexcept : topic_(topic), reader_(reader) {}
  dds_entity_t topic_ = 0;
  dds_entity_t reader_ = 0;
};

/// @brief A keep-last, volatile writer: XCDR1 data representation, autodispose off (as
/// rmw_cyclonedds), so ROS 2 readers of the same type name match it.
/// Thread-safety: write() from one thread at a time (Cyclone locks internally).
class Writer {
 public:
  /// @brief Creates a topic and a writer on it. Start-up only (allocates).
  /// @param topic_name the DDS name in full, e.g. "rt/elevation_map"
  /// @param depth KEEP_LAST history depth (>= 1); a keep-last writer never blocks on readers
  static Result<Writer> create(const Participant& participant, const char* topic_name,
                               const dds_topic_descriptor_t* descriptor, Reliability reliability,
                               std::int32_t depth, Durability durability = Durability::kVolatile);

  Writer(Writer&& other) noexcept
      : topic_(std::exchange(other.topic_, 0)), writer_(std::exchange(other.writer_, 0)) {}
  Writer& operator=(Writer&& other) noexcept;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  ~Writer();

  dds_entity_t handle() const noexcept { return writer_; }

  /// @brief Serialises and sends `sample` (an idlc struct of the writer's type, e.g.
  /// GridMapMessage::sample()), stamped with the current time.
  /// @rt allocates: no on our side, but Cyclone allocates the serialized copy and its
  /// retransmit-history entry inside dds_write (see the measurement in the tests); call it from
  /// a publishing thread, not from a hard-deadline loop. blocks: on Cyclone's writer lock.
  Expected<void, DdsError> write(const void* sample) noexcept;
  /// @brief write() with an explicit source timestamp (nanoseconds since the epoch).
  Expected<void, DdsError> writeWithTimestamp(const void* sample,
                                              std::int64_t source_timestamp_ns) noexcept;

  /// @brief Readers currently matched (dds_get_publication_matched_status). @rt allocates: no.
  std::uint32_t matchedReaders() const noexcept;

 private:
  Writer(dds_entity_t topic, dds_entity_t writer) noexcept : topic_(topic), writer_(writer) {}
  dds_entity_t topic_ = 0;
  dds_entity_t writer_ = 0;
};

/// @brief A waitset over readers (each attached with a read condition, so it stays triggered
/// while the reader holds samples) plus a wake-up trigger for shutdown.
/// Thread-safety: wait() from one thread; wake() from any thread (also while wait() runs).
class Waitset {
 public:
  /// The token wait() reports after wake().
  static constexpr std::intptr_t kWakeToken = -1;

  /// @brief Creates a waitset. Start-up only (allocates).
  static Result<Waitset> create(const Participant& participant);

  Waitset(Waitset&& other) noexcept : waitset_(std::exchange(other.waitset_, 0)) {}
  Waitset& operator=(Waitset&& other) noexcept;
  Waitset(const Waitset&) = delete;
  Waitset& operator=(const Waitset&) = delete;
  ~Waitset();

  dds_entity_t handle() const noexcept { return waitset_; }

  /// @brief Attaches a reader (RawReader::handle()): wait() reports `token` while the reader
  /// has samples. `token` must not be kWakeToken. Start-up only (allocates a read condition,
  /// owned by the reader).
  Result<void> attach(dds_entity_t reader, std::intptr_t token);

  /// @brief Blocks until a reader has data, wake() was called, or `timeout_ns` passed.
  /// @param[out] triggered the tokens of the triggered entities (at most its size)
  /// @return the number of tokens written (0 on timeout), or a negative dds_return_t. A wake()
  /// is reported once as kWakeToken and then reset.
  /// @rt allocates: no; blocks: yes, up to timeout_ns.
  int wait(std::int64_t timeout_ns, std::span<std::intptr_t> triggered) noexcept;

  /// @brief Makes a running or the next wait() return with kWakeToken.
  /// @rt allocates: no; blocks: no (a short internal lock).
  void wake() noexcept;

 private:
  explicit Waitset(dds_entity_t waitset) noexcept : waitset_(waitset) {}
  dds_entity_t waitset_ = 0;
};

}  // namespace raymap::dds
