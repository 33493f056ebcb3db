// SPDX-License-Identifier: BSD-3-Clause
// PeerParticipant: the participant's transport and discovery QoS, and topic registration.
#include "tests/fastdds/peer/peer_participant.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/common/Locator.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

namespace raymap::fastdds_peer {
namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

/// 127.0.0.1 with port 0: Fast DDS fills in the well-known port of its use.
rtps::Locator_t loopback() {
  rtps::Locator_t locator;
  rtps::IPLocator::setIPv4(locator, 127, 0, 0, 1);
  locator.port = 0;
  return locator;
}

dds::DomainParticipantQos loopbackQos(std::uint32_t buffer_bytes) {
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name("raymap-fastdds-peer");
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.emplace_back("127.0.0.1");
  udp->sendBufferSize = buffer_bytes;
  udp->receiveBufferSize = buffer_bytes;
  // Initial peers without a port stand for the metatraffic ports of this many indices.
  udp->maxInitialPeersRange = kParticipantIndices;
  qos.transport().use_builtin_transports = false;
  qos.transport().user_transports.push_back(udp);
  // Unicast only: with a metatraffic unicast locator given and no multicast one, Fast DDS adds
  // no multicast locator of its own (239.255.0.1 is what loopback lacks).
  auto& builtin = qos.wire_protocol().builtin;
  builtin.metatrafficUnicastLocatorList.push_back(loopback());
  builtin.initialPeersList.push_back(loopback());
  qos.wire_protocol().default_unicast_locator_list.push_back(loopback());
  return qos;
}

dds::DomainParticipantQos stockQos(std::uint32_t buffer_bytes) {
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name("raymap-fastdds-peer");
  qos.transport().send_socket_buffer_size = buffer_bytes;
  qos.transport().listen_socket_buffer_size = buffer_bytes;
  return qos;
}

dds::DomainParticipantQos participantQos(Discovery discovery, std::uint32_t buffer_bytes) {
  dds::DomainParticipantQos qos =
      discovery == Discovery::kLoopback ? loopbackQos(buffer_bytes) : stockQos(buffer_bytes);
  // As rmw_fastrtps: discovery messages larger than the preallocated 5000 bytes.
  auto& builtin = qos.wire_protocol().builtin;
  builtin.readerHistoryMemoryPolicy = rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  builtin.writerHistoryMemoryPolicy = rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return qos;
}

}  // namespace

std::unique_ptr<PeerParticipant> PeerParticipant::create(std::uint32_t domain, Discovery discovery,
                                                         std::uint32_t buffer_bytes,
                                                         std::string& error) {
  std::unique_ptr<PeerParticipant> self(new PeerParticipant());
  auto* factory = dds::DomainParticipantFactory::get_instance();
  self->participant_ = factory->create_participant(static_cast<dds::DomainId_t>(domain),
                                                   participantQos(discovery, buffer_bytes));
  if (self->participant_ == nullptr) {
    error = "Fast DDS refused the participant on domain " + std::to_string(domain);
    return nullptr;
  }
  self->publisher_ = self->participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  self->subscriber_ = self->participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  if (self->publisher_ == nullptr || self->subscriber_ == nullptr) {
    error = "Fast DDS refused the publisher or the subscriber";
    return nullptr;
  }
  return self;
}

PeerParticipant::~PeerParticipant() {
  if (participant_ != nullptr) {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
}

dds::Topic* PeerParticipant::topic(const std::string& name, dds::TopicDataType* type) {
  dds::TypeSupport support(type);
  support->auto_fill_type_object(false);
  support->auto_fill_type_information(false);
  const std::string& type_name = support.get_type_name();
  // Registering a type twice under one name is accepted (the same TypeSupport).
  if (participant_->find_type(type_name).empty() &&
      support.register_type(participant_) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    return nullptr;
  }
  return participant_->create_topic(name, type_name, dds::TOPIC_QOS_DEFAULT);
}

}  // namespace raymap::fastdds_peer
