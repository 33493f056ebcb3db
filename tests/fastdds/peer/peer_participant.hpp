// SPDX-License-Identifier: BSD-3-Clause
// A Fast DDS domain participant configured as rmw_fastrtps configures one: either whose traffic
// stays on loopback and which finds Cyclone DDS there without multicast, or with Fast DDS's
// stock transports and multicast discovery (for a network namespace the test makes).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>

namespace raymap::fastdds_peer {

/// @brief How many participant indices the initial peers cover: Cyclone's on
/// config/cyclonedds-loopback.xml go up to MaxAutoParticipantIndex 32, Fast DDS's own count from
/// 0 in the first free port pair.
inline constexpr std::uint32_t kParticipantIndices = 33;

/// How the participant finds others and which transports it uses.
enum class Discovery : std::uint8_t {
  /// One UDPv4 transport whitelisted to 127.0.0.1, the built-in transports (UDPv4 on every
  /// interface, shared memory) off. Unicast only: metatraffic and user traffic on 127.0.0.1 at
  /// the RTPS well-known ports of the participant's index, no multicast locator, and initial
  /// peers 127.0.0.1 at the metatraffic ports of indices 0 to kParticipantIndices - 1 (where
  /// Cyclone's participants listen).
  kLoopback,
  /// Fast DDS's defaults, as a stock ROS 2 node has them: the built-in transports (UDPv4 on
  /// every interface, shared memory) and SPDP over multicast (239.255.0.1). Only for a network
  /// namespace of the caller's own, whose interfaces are all the test's.
  kStock,
};

/// @brief Owns one DomainParticipant with one Publisher and one Subscriber; deletes everything it
/// contains when destroyed.
///
/// Transport and discovery: `discovery`; send and receive buffers `buffer_bytes` (0: the OS
/// default, as rmw_fastrtps leaves them). Writer and reader histories of discovery may grow (as
/// rmw_fastrtps sets them). Thread-safety: one thread creates entities; Fast DDS's own threads
/// call listeners.
class PeerParticipant {
 public:
  /// @param enclave_dir an SROS2 enclave's folder: DDS Security with its files, as
  ///        rmw_fastrtps sets it up from ROS_SECURITY_KEYSTORE and the enclave ("": none)
  /// @return nullptr with `error` set when Fast DDS refuses the participant.
  static std::unique_ptr<PeerParticipant> create(std::uint32_t domain, Discovery discovery,
                                                 std::uint32_t buffer_bytes,
                                                 const std::string& enclave_dir,
                                                 std::string& error);
  ~PeerParticipant();
  PeerParticipant(const PeerParticipant&) = delete;
  PeerParticipant& operator=(const PeerParticipant&) = delete;

  /// @brief The topic `name` of the type `type` (taking ownership), registered under its own
  /// name (the IDL's, e.g. sensor_msgs::msg::dds_::PointCloud2_) without TypeObject or type
  /// information, as rmw_fastrtps registers ROS types. @return nullptr when refused.
  eprosima::fastdds::dds::Topic* topic(const std::string& name,
                                       eprosima::fastdds::dds::TopicDataType* type);
  eprosima::fastdds::dds::Publisher& publisher() noexcept { return *publisher_; }
  eprosima::fastdds::dds::Subscriber& subscriber() noexcept { return *subscriber_; }

 private:
  PeerParticipant() = default;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

}  // namespace raymap::fastdds_peer
