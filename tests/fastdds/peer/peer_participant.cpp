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

/// Fast DDS's built-in security plugins with an SROS2 enclave's files: the properties
/// rmw_fastrtps sets (its file names are SROS2's; the values are file:// URIs).
void addSecurity(dds::DomainParticipantQos& qos, const std::string& enclave_dir) {
  auto& properties = qos.properties().properties();
  const auto file = [&](const char* name) { return "file://" + enclave_dir + "/" + name; };
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  properties.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
  properties.emplace_back(auth + "identity_ca", file("identity_ca.cert.pem"));
  properties.emplace_back(auth + "identity_certificate", file("cert.pem"));
  properties.emplace_back(auth + "private_key", file("key.pem"));
  properties.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  properties.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
  properties.emplace_back(access + "permissions_ca", file("permissions_ca.cert.pem"));
  properties.emplace_back(access + "governance", file("governance.p7s"));
  properties.emplace_back(access + "permissions", file("permissions.p7s"));
}

}  // namespace

std::unique_ptr<PeerParticipant> PeerParticipant::create(std::uint32_t domain, Discovery discovery,
                                                         std::uint32_t buffer_bytes,
                                                         const std::string& enclave_dir,
                                                         std::string& error) {
  std::unique_ptr<PeerParticipant> self(new PeerParticipant());
  auto* factory = dds::DomainParticipantFactory::get_instance();
  dds::DomainParticipantQos qos = participantQos(discovery, buffer_bytes);
  if (!enclave_dir.empty()) {
    addSecurity(qos, enclave_dir);
  }
  self->participant_ = factory->create_participant(static_cast<dds::DomainId_t>(domain), qos);
  if (self->participant_ == nullptr) {
    error =
        "Fast DDS refused the participant on domain " + std::to_string(domain) +
        (enclave_dir.empty() ? std::string()
                             : " with DDS Security from " + enclave_dir + " (its log says why)");
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
