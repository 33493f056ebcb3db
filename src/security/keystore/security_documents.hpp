// SPDX-License-Identifier: BSD-3-Clause
// The text of DDS Security's governance and permissions documents (OMG DDS Security 1.1
// schemas), as sros2 writes them by default.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/keystore/pem_files.hpp"

namespace raymap::security {

/// The DDS topic every enclave may publish and subscribe: the ROS 2 graph information that
/// rmw_cyclonedds and rmw_fastrtps exchange (sros2 grants it too).
inline constexpr const char* kRosDiscoveryTopic = "ros_discovery_info";

/// @brief `text` with &, <, >, " and ' as XML entities.
std::string xmlEscaped(std::string_view text);

/// @brief The governance: authenticated participants only, join access control, discovery and
/// liveliness encrypted, RTPS messages signed; one rule for every topic ("*") with read and
/// write access control, metadata and data encrypted.
std::string governanceXml(const DomainRange& domains);

/// @brief One grant for `grant.enclave` (subject CN=<enclave>) over `domains` and `validity`:
/// an allow rule with the grant's topics (duplicates dropped, ros_discovery_info added), then
/// <default>DENY</default>.
std::string permissionsXml(const EnclaveGrant& grant, const DomainRange& domains,
                           const ValidityText& validity);

/// @brief What create-enclave grants before any policy, like sros2's default policy: publish
/// and subscribe every topic ("rt/*"), service request ("rq/*") and reply ("rr/*").
EnclaveGrant allowEverythingGrant(std::string_view enclave);

}  // namespace raymap::security
