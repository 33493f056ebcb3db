// SPDX-License-Identifier: BSD-3-Clause
// Field lists as in ROS 2 Humble's message packages (comments and constants left out, except
// where a field's meaning needs them).
#include "src/bag/ros2_definitions.hpp"

#include <array>
#include <set>
#include <vector>

namespace raymap::bag {
namespace {

struct Definition {
  std::string_view type;  ///< pkg/msg/Type
  std::string_view fields;
  std::vector<std::string_view> uses;  ///< types its fields use (pkg/msg/Type)
};

/// builtin_interfaces, std_msgs and geometry_msgs: the types the others use.
void addCommonDefinitions(std::vector<Definition>& out) {
  out.insert(
      out.end(),
      {
          {"builtin_interfaces/msg/Time", "int32 sec\nuint32 nanosec\n", {}},
          {"std_msgs/msg/Header",
           "builtin_interfaces/Time stamp\nstring frame_id\n",
           {"builtin_interfaces/msg/Time"}},
          {"std_msgs/msg/MultiArrayDimension", "string label\nuint32 size\nuint32 stride\n", {}},
          {"std_msgs/msg/MultiArrayLayout",
           "MultiArrayDimension[] dim\nuint32 data_offset\n",
           {"std_msgs/msg/MultiArrayDimension"}},
          {"std_msgs/msg/Float32MultiArray",
           "MultiArrayLayout layout\nfloat32[] data\n",
           {"std_msgs/msg/MultiArrayLayout"}},
          {"geometry_msgs/msg/Point", "float64 x\nfloat64 y\nfloat64 z\n", {}},
          {"geometry_msgs/msg/Quaternion",
           "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
           {}},
          {"geometry_msgs/msg/Vector3", "float64 x\nfloat64 y\nfloat64 z\n", {}},
          {"geometry_msgs/msg/Pose",
           "Point position\nQuaternion orientation\n",
           {"geometry_msgs/msg/Point", "geometry_msgs/msg/Quaternion"}},
          {"geometry_msgs/msg/PoseWithCovariance",
           "Pose pose\nfloat64[36] covariance\n",
           {"geometry_msgs/msg/Pose"}},
          {"geometry_msgs/msg/Twist",
           "Vector3 linear\nVector3 angular\n",
           {"geometry_msgs/msg/Vector3"}},
          {"geometry_msgs/msg/TwistWithCovariance",
           "Twist twist\nfloat64[36] covariance\n",
           {"geometry_msgs/msg/Twist"}},
          {"geometry_msgs/msg/Transform",
           "Vector3 translation\nQuaternion rotation\n",
           {"geometry_msgs/msg/Vector3", "geometry_msgs/msg/Quaternion"}},
          {"geometry_msgs/msg/TransformStamped",
           "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
           {"std_msgs/msg/Header", "geometry_msgs/msg/Transform"}},
      });
}

/// sensor_msgs: point clouds, images and camera calibration.
void addSensorDefinitions(std::vector<Definition>& out) {
  out.insert(
      out.end(),
      {
          {"sensor_msgs/msg/PointField",
           "uint8 INT8    = 1\nuint8 UINT8   = 2\nuint8 INT16   = 3\nuint8 UINT16  = 4\n"
           "uint8 INT32   = 5\nuint8 UINT32  = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
           "string name\nuint32 offset\nuint8 datatype\nuint32 count\n",
           {}},
          {"sensor_msgs/msg/PointCloud2",
           "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
           "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
           {"std_msgs/msg/Header", "sensor_msgs/msg/PointField"}},
          {"sensor_msgs/msg/RegionOfInterest",
           "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
           {}},
          {"sensor_msgs/msg/CameraInfo",
           "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
           "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
           "uint32 binning_y\nRegionOfInterest roi\n",
           {"std_msgs/msg/Header", "sensor_msgs/msg/RegionOfInterest"}},
          {"sensor_msgs/msg/Image",
           "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
           "uint8 is_bigendian\nuint32 step\nuint8[] data\n",
           {"std_msgs/msg/Header"}},
      });
}

/// nav_msgs, tf2_msgs, grid_map_msgs and diagnostic_msgs.
void addOutputDefinitions(std::vector<Definition>& out) {
  out.insert(
      out.end(),
      {
          {"nav_msgs/msg/Odometry",
           "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
           "geometry_msgs/TwistWithCovariance twist\n",
           {"std_msgs/msg/Header", "geometry_msgs/msg/PoseWithCovariance",
            "geometry_msgs/msg/TwistWithCovariance"}},
          {"nav_msgs/msg/MapMetaData",
           "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 "
           "height\n"
           "geometry_msgs/Pose origin\n",
           {"builtin_interfaces/msg/Time", "geometry_msgs/msg/Pose"}},
          {"nav_msgs/msg/OccupancyGrid",
           "std_msgs/Header header\nMapMetaData info\nint8[] data\n",
           {"std_msgs/msg/Header", "nav_msgs/msg/MapMetaData"}},
          {"tf2_msgs/msg/TFMessage",
           "geometry_msgs/TransformStamped[] transforms\n",
           {"geometry_msgs/msg/TransformStamped"}},
          {"grid_map_msgs/msg/GridMapInfo",
           "float64 resolution\nfloat64 length_x\nfloat64 length_y\ngeometry_msgs/Pose pose\n",
           {"geometry_msgs/msg/Pose"}},
          {"grid_map_msgs/msg/GridMap",
           "std_msgs/Header header\nGridMapInfo info\nstring[] layers\nstring[] basic_layers\n"
           "std_msgs/Float32MultiArray[] data\nuint16 outer_start_index\nuint16 "
           "inner_start_index\n",
           {"std_msgs/msg/Header", "grid_map_msgs/msg/GridMapInfo",
            "std_msgs/msg/Float32MultiArray"}},
          {"diagnostic_msgs/msg/KeyValue", "string key\nstring value\n", {}},
          {"diagnostic_msgs/msg/DiagnosticStatus",
           "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
           "byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n",
           {"diagnostic_msgs/msg/KeyValue"}},
          {"diagnostic_msgs/msg/DiagnosticArray",
           "std_msgs/Header header\nDiagnosticStatus[] status\n",
           {"std_msgs/msg/Header", "diagnostic_msgs/msg/DiagnosticStatus"}},
      });
}

const std::vector<Definition>& definitions() {
  static const std::vector<Definition> all = [] {
    std::vector<Definition> d;
    addCommonDefinitions(d);
    addSensorDefinitions(d);
    addOutputDefinitions(d);
    return d;
  }();
  return all;
}

const Definition* find(std::string_view type) {
  for (const Definition& d : definitions()) {
    if (d.type == type) {
      return &d;
    }
  }
  return nullptr;
}

/// Every type `d` uses, directly or not, each once, in first-use order.
void collect(const Definition& d, std::vector<const Definition*>& out,
             std::set<std::string_view>& seen) {
  for (std::string_view used : d.uses) {
    const Definition* u = find(used);
    if (u == nullptr || !seen.insert(used).second) {
      continue;
    }
    out.push_back(u);
    collect(*u, out, seen);
  }
}

}  // namespace

std::string ros2MessageDefinition(std::string_view type) {
  const Definition* d = find(type);
  if (d == nullptr) {
    return {};
  }
  std::string text(d->fields);
  std::vector<const Definition*> used;
  std::set<std::string_view> seen{type};
  collect(*d, used, seen);
  for (const Definition* u : used) {
    // "pkg/msg/Type" is written "pkg/Type" after MSG:, as rosbag2 does.
    std::string name(u->type);
    const std::size_t msg = name.find("/msg/");
    if (msg != std::string::npos) {
      name.erase(msg, 4);
    }
    text += "\n" + std::string(80, '=') + "\nMSG: " + name + "\n" + std::string(u->fields);
  }
  return text;
}

}  // namespace raymap::bag
