// SPDX-License-Identifier: BSD-3-Clause
// raymapd's DDS Security: the topics its enclave must be allowed (from its configuration) and
// the decision from `dds.security` or, without that section, ROS 2's variables.
#pragma once

#include <ctime>
#include <vector>

#include "raymap/error.hpp"

#include "src/security/permissions_document.hpp"
#include "src/security/secure_participant.hpp"
#include "src/service/daemon_config.hpp"

namespace raymap::service {

/// @brief Every topic raymapd reads or writes with `config`: the sensors' (and camera infos'),
/// the pose's (pose.topic, or rt/tf) and rt/tf_static subscribed; the height map, diagnostics,
/// voxels and costmap topics published; the height-map topic also subscribed (raymapd watches
/// it for a second publisher).
std::vector<security::TopicNeed> daemonTopicNeeds(const DaemonConfig& config);

/// @brief The security raymapd runs with at `now`: `dds.security` when the file has it, else
/// ROS_SECURITY_* (enclave /raymap/raymapd unless ROS_SECURITY_ENCLAVE_OVERRIDE names another).
/// "${CREDENTIALS_DIRECTORY}" at the start of dds.security.enclave_dir is the folder systemd
/// gives the service's credentials (LoadCredential=). Errors name the key or variable, the file
/// and the reason. Start-up only.
Result<security::SecurityOutcome> resolveDaemonSecurity(const DaemonConfig& config,
                                                        std::time_t now);

}  // namespace raymap::service
