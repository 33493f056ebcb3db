// SPDX-License-Identifier: BSD-3-Clause
// The three ROS 2 profiles, applied to Fast DDS's default writer and reader QoS.
#include "tests/fastdds/peer/ros_qos.hpp"

#include <cstdint>

namespace raymap::fastdds_peer {
namespace dds = eprosima::fastdds::dds;

namespace {

struct Profile {
  dds::ReliabilityQosPolicyKind reliability;
  dds::DurabilityQosPolicyKind durability;
  std::int32_t depth;
};

Profile profileOf(RosProfile profile) {
  switch (profile) {
    case RosProfile::kSensorData:
      return {dds::BEST_EFFORT_RELIABILITY_QOS, dds::VOLATILE_DURABILITY_QOS, 5};
    case RosProfile::kStaticTf:
      return {dds::RELIABLE_RELIABILITY_QOS, dds::TRANSIENT_LOCAL_DURABILITY_QOS, 1};
    case RosProfile::kDefault:
      break;
  }
  return {dds::RELIABLE_RELIABILITY_QOS, dds::VOLATILE_DURABILITY_QOS, 10};
}

/// What rmw_fastrtps's get_datawriter_qos / get_datareader_qos set from a ROS profile.
template <typename Qos>
void applyProfile(RosProfile profile, Qos& qos) {
  const Profile p = profileOf(profile);
  qos.reliability().kind = p.reliability;
  qos.durability().kind = p.durability;
  qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = p.depth;
  qos.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  qos.data_sharing().off();
}

}  // namespace

dds::DataWriterQos writerQos(RosProfile profile) {
  dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
  qos.publish_mode().kind = eprosima::fastdds::dds::SYNCHRONOUS_PUBLISH_MODE;
  applyProfile(profile, qos);
  return qos;
}

dds::DataReaderQos readerQos(RosProfile profile) {
  dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
  applyProfile(profile, qos);
  return qos;
}

}  // namespace raymap::fastdds_peer
