// SPDX-License-Identifier: BSD-3-Clause
#include "src/msgs/ros_names.hpp"

#include <vector>

namespace raymap::msgs {
namespace {

// rmw_cyclonedds prefixes ROS topics with "rt" when it names their DDS topics.
constexpr std::string_view kRosTopicPrefix = "rt";

}  // namespace

std::string ddsTopicName(std::string_view name) {
  if (name.starts_with('/')) {
    std::string dds(kRosTopicPrefix);
    dds += name;
    return dds;
  }
  return std::string(name);
}

std::string rosTopicName(std::string_view dds_name) {
  if (dds_name.size() > kRosTopicPrefix.size() + 1 && dds_name.starts_with(kRosTopicPrefix) &&
      dds_name[kRosTopicPrefix.size()] == '/') {
    return std::string(dds_name.substr(kRosTopicPrefix.size()));
  }
  return {};
}

std::string rosTypeName(std::string_view dds_type_name) {
  // rmw builds "<pkg>::msg::dds_::<Msg>_" (MessageTypeSupport_impl.hpp): at least three parts
  // before the name, the last of them "dds_", and the name ending in '_'.
  std::vector<std::string_view> parts;
  std::string_view rest = dds_type_name;
  for (;;) {
    const std::size_t separator = rest.find("::");
    parts.push_back(rest.substr(0, separator));
    if (separator == std::string_view::npos) {
      break;
    }
    rest.remove_prefix(separator + 2);
  }
  if (parts.size() < 4 || parts[parts.size() - 2] != "dds_" || parts.back().size() < 2 ||
      !parts.back().ends_with('_')) {
    return std::string(dds_type_name);
  }
  std::string ros;
  for (std::size_t i = 0; i + 2 < parts.size(); ++i) {
    if (parts[i].empty()) {
      return std::string(dds_type_name);
    }
    ros += parts[i];
    ros += '/';
  }
  std::string_view name = parts.back();
  name.remove_suffix(1);
  ros += name;
  return ros;
}

}  // namespace raymap::msgs
