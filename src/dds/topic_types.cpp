// SPDX-License-Identifier: BSD-3-Clause
// The idlc descriptors behind src/dds/topic_types.hpp.
#include "src/dds/topic_types.hpp"

#include "diagnostic_msgs.h"
#include "grid_map_msgs.h"
#include "nav_msgs.h"
#include "sensor_msgs.h"
#include "tf2_msgs.h"

namespace raymap::dds {

const dds_topic_descriptor_t* pointCloud2Type() noexcept {
  return &sensor_msgs_msg_dds__PointCloud2__desc;
}
const dds_topic_descriptor_t* odometryType() noexcept { return &nav_msgs_msg_dds__Odometry__desc; }
const dds_topic_descriptor_t* tfMessageType() noexcept {
  return &tf2_msgs_msg_dds__TFMessage__desc;
}
const dds_topic_descriptor_t* gridMapType() noexcept {
  return &grid_map_msgs_msg_dds__GridMap__desc;
}
const dds_topic_descriptor_t* diagnosticArrayType() noexcept {
  return &diagnostic_msgs_msg_dds__DiagnosticArray__desc;
}

}  // namespace raymap::dds
