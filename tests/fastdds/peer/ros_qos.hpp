// SPDX-License-Identifier: BSD-3-Clause
// ROS 2's QoS profiles as rmw_fastrtps (Humble) maps them onto Fast DDS 2.9 writers and readers.
#pragma once

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

namespace raymap::fastdds_peer {

/// @brief The profiles the peer's endpoints use.
enum class RosProfile {
  kDefault,     ///< rmw_qos_profile_default: reliable, volatile, keep last 10
  kSensorData,  ///< rmw_qos_profile_sensor_data (SensorDataQoS): best effort, volatile, keep last 5
  kStaticTf,    ///< tf2_ros's StaticBroadcasterQoS: reliable, transient local, keep last 1
};

/// @brief A writer's QoS: the profile's reliability, durability and history on Fast DDS's
/// defaults, plus what rmw_fastrtps sets on every writer: synchronous publishing, a history that
/// may reallocate (messages of any size), no data sharing.
eprosima::fastdds::dds::DataWriterQos writerQos(RosProfile profile);

/// @brief A reader's QoS: the profile's, plus rmw_fastrtps's reallocating history and no data
/// sharing.
eprosima::fastdds::dds::DataReaderQos readerQos(RosProfile profile);

}  // namespace raymap::fastdds_peer
