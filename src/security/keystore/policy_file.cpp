// SPDX-License-Identifier: BSD-3-Clause
// The policy file of `raymap security create-permissions`: which enclave may publish and
// subscribe which ROS 2 topics. yaml-cpp parses; its exceptions stay in this file.
#include <exception>
#include <set>
#include <string>

#include <yaml-cpp/yaml.h>

#include "src/security/keystore/keystore_files.hpp"
#include "src/security/keystore/keystore_layout.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/pem_reading.hpp"

namespace raymap::security {
namespace {

/// Where a problem is: "FILE: line N: " (the line of `at`, when it has one).
std::string where(const std::filesystem::path& file, const YAML::Node& at) {
  std::string text = file.string() + ": ";
  if (at.IsDefined() && at.Mark().line >= 0) {
    text += "line " + std::to_string(at.Mark().line + 1) + ": ";
  }
  return text;
}

Unexpected<Error> policyError(const std::filesystem::path& file, const YAML::Node& at,
                              const std::string& reason) {
  return fail(ErrorCode::kFormat, where(file, at) + reason);
}

/// The DDS names of a list of ROS 2 topics ("/points" -> "rt/points").
Result<std::vector<std::string>> readTopics(const std::filesystem::path& file,
                                            const std::string& enclave, const std::string& key,
                                            const YAML::Node& list) {
  const std::string path = "enclave " + enclave + ": " + key;
  if (!list.IsSequence()) {
    return policyError(file, list, path + ": must be a list of ROS 2 topic names ([/a, /b])");
  }
  std::vector<std::string> topics;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node entry = list[i];
    const std::string item = path + "[" + std::to_string(i) + "]";
    if (!entry.IsScalar()) {
      return policyError(file, entry, item + ": must be a ROS 2 topic name (/points)");
    }
    const std::string& name = entry.Scalar();
    if (name.size() < 2 || name.front() != '/') {
      std::string reason = item;
      reason.append(" \"").append(name).append(
          "\": a ROS 2 topic name starts with '/' and names a topic (/points)");
      return policyError(file, entry, reason);
    }
    topics.push_back("rt" + name);
  }
  return topics;
}

Result<EnclaveGrant> readEnclave(const std::filesystem::path& file, const YAML::Node& key,
                                 const YAML::Node& body) {
  EnclaveGrant grant{key.Scalar(), {}, {}};
  if (auto named = checkEnclaveName(grant.enclave); !named) {
    return policyError(file, key, named.error().message);
  }
  if (body.IsNull()) {
    return grant;  // no topics: only ros_discovery_info
  }
  if (!body.IsMap()) {
    return policyError(file, body,
                       "enclave " + grant.enclave + ": must be a mapping (publish:, subscribe:)");
  }
  for (const auto& entry : body) {
    const std::string name = entry.first.Scalar();
    if (name != "publish" && name != "subscribe") {
      return policyError(file, entry.first,
                         "enclave " + grant.enclave + ": unknown key \"" + name +
                             "\" (known here: publish, subscribe)");
    }
    auto topics = readTopics(file, grant.enclave, name, entry.second);
    if (!topics) {
      return Unexpected(std::move(topics).error());
    }
    (name == "publish" ? grant.publish : grant.subscribe) = std::move(*topics);
  }
  return grant;
}

Result<std::vector<EnclaveGrant>> readEnclaves(const std::filesystem::path& file,
                                               const YAML::Node& root) {
  if (!root.IsMap()) {
    return policyError(file, root, "a policy is a mapping with the key enclaves:");
  }
  for (const auto& entry : root) {
    if (entry.first.Scalar() != "enclaves") {
      return policyError(file, entry.first,
                         "unknown key \"" + entry.first.Scalar() + "\" (known here: enclaves)");
    }
  }
  const YAML::Node enclaves = root["enclaves"];
  if (!enclaves || !enclaves.IsMap() || enclaves.size() == 0) {
    return policyError(file, enclaves ? enclaves : root,
                       "enclaves: must map at least one enclave name to its topics");
  }
  std::vector<EnclaveGrant> grants;
  std::set<std::string> seen;
  for (const auto& entry : enclaves) {
    auto grant = readEnclave(file, entry.first, entry.second);
    if (!grant) {
      return Unexpected(std::move(grant).error());
    }
    if (!seen.insert(grant->enclave).second) {
      return policyError(file, entry.first, "enclave " + grant->enclave + ": listed twice");
    }
    grants.push_back(std::move(*grant));
  }
  return grants;
}

}  // namespace

Result<std::vector<EnclaveGrant>> readPolicyFile(const std::filesystem::path& policy) {
  auto text = readWholeFile(policy, "the policy file");
  if (!text) {
    return Unexpected(std::move(text).error());
  }
  try {
    return readEnclaves(policy, YAML::Load(*text));
  } catch (const YAML::Exception& e) {
    const std::string line =
        e.mark.is_null() ? "" : "line " + std::to_string(e.mark.line + 1) + ": ";
    return fail(ErrorCode::kFormat, policy.string() + ": " + line + "not YAML: " + e.msg);
  }
}

}  // namespace raymap::security
