// SPDX-License-Identifier: BSD-3-Clause
// raymapd's topics as permissions name them, and its security decision.
#include "src/service/daemon_security.hpp"

#include <cstdlib>
#include <string>
#include <string_view>

namespace raymap::service {
namespace {

constexpr std::string_view kCredentialsVariable = "${CREDENTIALS_DIRECTORY}";

/// dds.security.enclave_dir with systemd's credentials folder put in.
Result<std::string> expandEnclaveDir(const DaemonConfig& config, const std::string& dir) {
  if (dir.rfind(kCredentialsVariable, 0) != 0) {
    return dir;
  }
  // NOLINTNEXTLINE(concurrency-mt-unsafe): start-up, before any thread that sets variables
  const char* credentials = std::getenv("CREDENTIALS_DIRECTORY");
  if (credentials == nullptr || credentials[0] == '\0') {
    return fail(ErrorCode::kInvalidArgument,
                config.where("dds.security.enclave_dir") +
                    ": CREDENTIALS_DIRECTORY is not set: systemd sets it for a service with "
                    "LoadCredential= lines (docs/security.md); run by hand, name the enclave's "
                    "folder instead");
  }
  return std::string(credentials) + dir.substr(kCredentialsVariable.size());
}

}  // namespace

std::vector<security::TopicNeed> daemonTopicNeeds(const DaemonConfig& config) {
  using security::TopicUse;
  std::vector<security::TopicNeed> needs;
  for (const SensorConfig& sensor : config.sensors) {
    needs.push_back({sensor.topic, TopicUse::kSubscribe});
    if (sensor.kind == SensorKind::kDepth) {
      needs.push_back({sensor.camera_info_topic, TopicUse::kSubscribe});
    }
  }
  needs.push_back({config.pose.source == PoseConfig::Source::kOdometry ? config.pose.odometry_topic
                                                                       : std::string("rt/tf"),
                   TopicUse::kSubscribe});
  needs.push_back({"rt/tf_static", TopicUse::kSubscribe});
  needs.push_back({config.dds.grid_map_topic, TopicUse::kPublish});
  needs.push_back({config.dds.grid_map_topic, TopicUse::kSubscribe});
  needs.push_back({config.dds.diagnostics_topic, TopicUse::kPublish});
  for (const std::string* optional : {&config.dds.voxels_topic, &config.dds.costmap_topic}) {
    if (!optional->empty()) {
      needs.push_back({*optional, TopicUse::kPublish});
    }
  }
  return needs;
}

Result<security::SecurityOutcome> resolveDaemonSecurity(const DaemonConfig& config,
                                                        std::time_t now) {
  security::SecurityConfig chosen;
  if (config.dds.security_in_file) {
    chosen = config.dds.security;
    chosen.source = config.where("dds.security");
    auto dir = expandEnclaveDir(config, chosen.enclave_dir);
    if (!dir) {
      return Unexpected(std::move(dir).error());
    }
    chosen.enclave_dir = *dir;
  } else {
    auto from_environment = security::securityFromEnvironment(security::kDaemonEnclave);
    if (!from_environment) {
      return Unexpected(std::move(from_environment).error());
    }
    chosen = *from_environment;
  }
  const std::vector<security::TopicNeed> needs = daemonTopicNeeds(config);
  return security::resolveSecurity(chosen, config.dds.domain, needs, now);
}

}  // namespace raymap::service
