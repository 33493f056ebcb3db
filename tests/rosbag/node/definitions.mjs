// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 Humble .msg field lists the fixture writer knows, and the complete `ros2msg` definition
// text that rosbag2 stores for a type (root text, then each dependency behind a delimiter).

/** .msg text by the name a field refers to it with (`pkg/Type`); constants and defaults kept. */
const kMsgText = new Map([
  ["builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"],
  ["std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"],
  [
    "sensor_msgs/PointField",
    [
      "uint8 INT8    = 1",
      "uint8 UINT8   = 2",
      "uint8 INT16   = 3",
      "uint8 UINT16  = 4",
      "uint8 INT32   = 5",
      "uint8 UINT32  = 6",
      "uint8 FLOAT32 = 7",
      "uint8 FLOAT64 = 8",
      "",
      "string name",
      "uint32 offset",
      "uint8  datatype",
      "uint32 count",
      "",
    ].join("\n"),
  ],
  [
    "sensor_msgs/PointCloud2",
    [
      "std_msgs/Header header",
      "",
      "uint32 height",
      "uint32 width",
      "",
      "PointField[] fields",
      "",
      "bool    is_bigendian",
      "uint32  point_step",
      "uint32  row_step",
      "uint8[] data",
      "",
      "bool is_dense",
      "",
    ].join("\n"),
  ],
  [
    "sensor_msgs/Image",
    [
      "std_msgs/Header header",
      "uint32 height",
      "uint32 width",
      "string encoding",
      "uint8 is_bigendian",
      "uint32 step",
      "uint8[] data",
      "",
    ].join("\n"),
  ],
  [
    "sensor_msgs/RegionOfInterest",
    "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
  ],
  [
    "sensor_msgs/CameraInfo",
    [
      "std_msgs/Header header",
      "uint32 height",
      "uint32 width",
      "string distortion_model",
      "float64[] d",
      "float64[9]  k",
      "float64[9]  r",
      "float64[12] p",
      "uint32 binning_x",
      "uint32 binning_y",
      "RegionOfInterest roi",
      "",
    ].join("\n"),
  ],
  ["geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"],
  ["geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"],
  // ROS 2 gives Quaternion defaults, so a default-constructed one is the identity rotation.
  ["geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"],
  ["geometry_msgs/Pose", "Point position\nQuaternion orientation\n"],
  ["geometry_msgs/Twist", "Vector3  linear\nVector3  angular\n"],
  ["geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"],
  ["geometry_msgs/PoseWithCovariance", "Pose pose\n\nfloat64[36] covariance\n"],
  ["geometry_msgs/TwistWithCovariance", "Twist twist\n\nfloat64[36] covariance\n"],
  ["geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose\n"],
  [
    "geometry_msgs/TransformStamped",
    "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
  ],
  [
    "nav_msgs/Odometry",
    [
      "std_msgs/Header header",
      "string child_frame_id",
      "geometry_msgs/PoseWithCovariance pose",
      "geometry_msgs/TwistWithCovariance twist",
      "",
    ].join("\n"),
  ],
  ["tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"],
  ["diagnostic_msgs/KeyValue", "string key\nstring value\n"],
  [
    "diagnostic_msgs/DiagnosticStatus",
    [
      "byte OK=0",
      "byte WARN=1",
      "byte ERROR=2",
      "byte STALE=3",
      "byte level",
      "string name",
      "string message",
      "string hardware_id",
      "KeyValue[] values",
      "",
    ].join("\n"),
  ],
  ["diagnostic_msgs/DiagnosticArray", "std_msgs/Header header\nDiagnosticStatus[] status\n"],
]);

/** The top-level types a spec may declare, by their ROS 2 name. */
export const kSupportedTypes = Object.freeze([
  "sensor_msgs/msg/PointCloud2",
  "sensor_msgs/msg/Image",
  "sensor_msgs/msg/CameraInfo",
  "nav_msgs/msg/Odometry",
  "tf2_msgs/msg/TFMessage",
  "geometry_msgs/msg/PoseStamped",
  "diagnostic_msgs/msg/DiagnosticArray",
]);

const kPrimitives = new Set([
  "bool",
  "byte",
  "char",
  "float32",
  "float64",
  "int8",
  "uint8",
  "int16",
  "uint16",
  "int32",
  "uint32",
  "int64",
  "uint64",
  "string",
  "wstring",
]);

const kDelimiter = "=".repeat(80) + "\n";

/**
 * Splits `pkg/Type` or `pkg/msg/Type` into the package and the type name.
 * @returns {{pkg: string, name: string} | undefined}
 */
function splitTypeName(type) {
  const match = /^([A-Za-z][A-Za-z0-9_]*)\/(?:msg\/)?([A-Za-z][A-Za-z0-9_]*)$/.exec(type);
  return match ? { pkg: match[1], name: match[2] } : undefined;
}

/** `sensor_msgs/PointCloud2` or `sensor_msgs/msg/PointCloud2` -> `sensor_msgs/msg/PointCloud2`. */
export function canonicalTypeName(type) {
  const parts = splitTypeName(type);
  return parts ? `${parts.pkg}/msg/${parts.name}` : undefined;
}

/**
 * The complex types a .msg text refers to, as rosbag2's definition cache finds them: the first word
 * of every line that is not a primitive, qualified with the package when it has no `/`, sorted.
 */
function dependenciesOf(text, pkg) {
  const deps = new Set();
  for (const line of text.split("\n")) {
    const match = /^\s*([A-Za-z0-9_/]+)(?:\[[^\]]*\])?\s+/.exec(line);
    if (!match || kPrimitives.has(match[1])) {
      continue;
    }
    deps.add(match[1].includes("/") ? match[1] : `${pkg}/${match[1]}`);
  }
  // std::set<std::string> order: plain code-unit comparison, as the strings are ASCII.
  return [...deps].sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
}

/**
 * The complete message definition of `type` in rosbag2's `ros2msg` encoding: the type's own text,
 * then depth first each dependency not seen yet as "\n", 80 `=`, "MSG: pkg/Type" and its text.
 * @param {string} type `pkg/msg/Type` or `pkg/Type`
 * @returns {string}
 */
export function fullDefinitionText(type) {
  const root = splitTypeName(type);
  if (!root || !kMsgText.has(`${root.pkg}/${root.name}`)) {
    throw new Error(`unsupported message type ${type} (supported: ${kSupportedTypes.join(", ")})`);
  }
  const seen = new Set();
  const appendRecursive = (key) => {
    const text = kMsgText.get(key);
    if (text === undefined) {
      throw new Error(`no .msg text for dependency ${key}`);
    }
    let result = text;
    for (const dep of dependenciesOf(text, key.split("/")[0])) {
      if (!seen.has(dep)) {
        seen.add(dep);
        result += "\n" + kDelimiter + `MSG: ${dep}\n` + appendRecursive(dep);
      }
    }
    return result;
  };
  return appendRecursive(`${root.pkg}/${root.name}`);
}
