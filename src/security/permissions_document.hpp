// SPDX-License-Identifier: BSD-3-Clause
// What a DDS Security permissions document (OMG DDS Security 1.1, the XML inside an SROS2
// permissions.p7s) grants one identity: its validity and whether it may publish or subscribe a
// topic on a domain. Used to refuse, before Cyclone DDS is started, a configuration whose topics
// the enclave may not use, naming each one.
#pragma once

#include <cstdint>
#include <ctime>
#include <string>
#include <string_view>
#include <vector>

#include "raymap/error.hpp"

namespace raymap::security {

/// How an endpoint uses a topic.
enum class TopicUse : std::uint8_t { kPublish, kSubscribe };

/// @brief One topic a program needs (a DDS name, "rt/points") and how it uses it.
struct TopicNeed {
  std::string topic;
  TopicUse use = TopicUse::kSubscribe;
};

/// @brief The grant of one subject, read from a permissions document's XML.
/// Evaluates rules as DDS Security does: the first allow or deny rule (in document order) that
/// covers the domain and names a matching topic (fnmatch patterns) for the use decides; else the
/// grant's <default>. Partitions and data tags are not evaluated (ROS 2 uses neither): a rule
/// with them counts as covering the default partition. Thread-safety: const methods from any
/// thread.
class PermissionsGrant {
 public:
  /// @brief The grant of `subject` (e.g. "CN=/raymap/raymapd", compared without spaces) in
  /// `xml`. @return an error saying which subjects the document grants when none matches.
  static Result<PermissionsGrant> find(std::string_view xml, std::string_view subject);

  /// @brief Whether the grant allows `use` of `topic` on `domain`.
  bool allows(std::uint32_t domain, std::string_view topic, TopicUse use) const;

  /// @brief Whether any rule of the grant (or an ALLOW default) covers `domain`: Cyclone refuses
  /// a participant on a domain its grant says nothing about ("denied by default rule").
  bool coversDomain(std::uint32_t domain) const;

  /// @brief The validity of the grant (seconds since the epoch, UTC).
  std::time_t notBefore() const noexcept { return not_before_; }
  std::time_t notAfter() const noexcept { return not_after_; }

 private:
  struct Rule {
    bool allow = false;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> domains;  // inclusive ranges
    std::vector<std::string> publish;
    std::vector<std::string> subscribe;
  };
  /// The allow and deny rules of a grant's XML, in document order.
  static std::vector<Rule> rulesOf(std::string_view grant);

  std::vector<Rule> rules_;
  bool default_allow_ = false;
  std::time_t not_before_ = 0;
  std::time_t not_after_ = 0;
};

/// @brief Whether a governance document's <domain_rule>s cover `domain` (Cyclone refuses to
/// create a participant on a domain its governance does not list).
bool governanceCoversDomain(std::string_view xml, std::uint32_t domain);

/// @brief An ISO 8601 time as permissions documents write it ("2030-05-01T00:00:00", optional
/// fraction and "Z" or "+hh:mm"; UTC when no offset) as seconds since the epoch.
Result<std::time_t> parseIsoTime(std::string_view text);

}  // namespace raymap::security
