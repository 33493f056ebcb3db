// SPDX-License-Identifier: BSD-3-Clause
// Governance and permissions XML written as text (no XML library: the documents are fixed
// shapes, and every name in them is escaped).
#include "src/security/keystore/security_documents.hpp"

#include <algorithm>

namespace raymap::security {
namespace {

constexpr const char* kGovernanceSchema =
    "http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd";
constexpr const char* kPermissionsSchema =
    "http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd";

std::string ddsOpening(const char* schema) {
  return std::string("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n") +
         "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n" +
         "     xsi:noNamespaceSchemaLocation=\"" + schema + "\">\n";
}

/// <domains> at `indent` spaces: <id>N</id> for one domain, else <id_range>.
std::string domainsXml(const DomainRange& domains, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  std::string xml = pad + "<domains>\n";
  if (domains.min == domains.max) {
    xml += pad + "  <id>" + std::to_string(domains.min) + "</id>\n";
  } else {
    xml += pad + "  <id_range>\n";
    xml += pad + "    <min>" + std::to_string(domains.min) + "</min>\n";
    xml += pad + "    <max>" + std::to_string(domains.max) + "</max>\n";
    xml += pad + "  </id_range>\n";
  }
  return xml + pad + "</domains>\n";
}

/// `topics` in order without repeats, plus ros_discovery_info.
std::vector<std::string> grantedTopics(const std::vector<std::string>& topics) {
  std::vector<std::string> unique;
  for (const std::string& topic : topics) {
    if (std::find(unique.begin(), unique.end(), topic) == unique.end()) {
      unique.push_back(topic);
    }
  }
  if (std::find(unique.begin(), unique.end(), kRosDiscoveryTopic) == unique.end()) {
    unique.emplace_back(kRosDiscoveryTopic);
  }
  return unique;
}

/// <publish> or <subscribe> with its <topics>, inside an allow rule.
std::string topicsXml(const char* element, const std::vector<std::string>& topics) {
  std::string xml = std::string("        <") + element + ">\n          <topics>\n";
  for (const std::string& topic : grantedTopics(topics)) {
    xml += "            <topic>" + xmlEscaped(topic) + "</topic>\n";
  }
  return xml + "          </topics>\n        </" + element + ">\n";
}

}  // namespace

std::string xmlEscaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string governanceXml(const DomainRange& domains) {
  return ddsOpening(kGovernanceSchema) +
         "  <domain_access_rules>\n"
         "    <domain_rule>\n" +
         domainsXml(domains, 6) +
         "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
         "      <enable_join_access_control>true</enable_join_access_control>\n"
         "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
         "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
         "      <rtps_protection_kind>SIGN</rtps_protection_kind>\n"
         "      <topic_access_rules>\n"
         "        <topic_rule>\n"
         "          <topic_expression>*</topic_expression>\n"
         "          <enable_discovery_protection>true</enable_discovery_protection>\n"
         "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
         "          <enable_read_access_control>true</enable_read_access_control>\n"
         "          <enable_write_access_control>true</enable_write_access_control>\n"
         "          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>\n"
         "          <data_protection_kind>ENCRYPT</data_protection_kind>\n"
         "        </topic_rule>\n"
         "      </topic_access_rules>\n"
         "    </domain_rule>\n"
         "  </domain_access_rules>\n"
         "</dds>\n";
}

std::string permissionsXml(const EnclaveGrant& grant, const DomainRange& domains,
                           const ValidityText& validity) {
  const std::string name = xmlEscaped(grant.enclave);
  return ddsOpening(kPermissionsSchema) +
         "  <permissions>\n"
         "    <grant name=\"" +
         name + "\">\n" + "      <subject_name>CN=" + name + "</subject_name>\n" +
         "      <validity>\n" + "        <not_before>" + xmlEscaped(validity.not_before) +
         "</not_before>\n" + "        <not_after>" + xmlEscaped(validity.not_after) +
         "</not_after>\n" + "      </validity>\n" + "      <allow_rule>\n" +
         domainsXml(domains, 8) + topicsXml("publish", grant.publish) +
         topicsXml("subscribe", grant.subscribe) +
         "      </allow_rule>\n"
         "      <default>DENY</default>\n"
         "    </grant>\n"
         "  </permissions>\n"
         "</dds>\n";
}

EnclaveGrant allowEverythingGrant(std::string_view enclave) {
  const std::vector<std::string> everything = {"rt/*", "rq/*", "rr/*"};
  return EnclaveGrant{std::string(enclave), everything, everything};
}

}  // namespace raymap::security
