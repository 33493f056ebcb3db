// SPDX-License-Identifier: BSD-3-Clause
// The grant of one subject in a DDS Security permissions document: a small reader of the
// elements the OMG schema defines (no general XML parser: the documents are machine-written,
// without nested elements of the same name or CDATA), and the rule evaluation.
#include "src/security/permissions_document.hpp"

#include <algorithm>
#include <charconv>
#include <iterator>
#include <string>

#include <fnmatch.h>

namespace raymap::security {
namespace {

/// One element found by a scan: its inner text and where it ends in the scanned text.
struct Element {
  std::string_view inner;
  std::size_t end = std::string_view::npos;  // npos: not found
};

/// The first <tag ...>inner</tag> at or after `from` (also <tag/>: empty inner).
Element findElement(std::string_view xml, std::string_view tag, std::size_t from = 0) {
  std::string open(1, '<');  // built by appending: GCC 12 warns (-Wrestrict) on "<" + string
  open.append(tag);
  for (std::size_t at = xml.find(open, from); at != std::string_view::npos;
       at = xml.find(open, at + 1)) {
    const std::size_t after = at + open.size();
    if (after >= xml.size() || (xml[after] != '>' && xml[after] != ' ' && xml[after] != '/' &&
                                xml[after] != '\t' && xml[after] != '\n' && xml[after] != '\r')) {
      continue;  // a longer tag name with the same prefix
    }
    const std::size_t open_end = xml.find('>', after);
    if (open_end == std::string_view::npos) {
      return {};
    }
    if (xml[open_end - 1] == '/') {
      return {std::string_view(), open_end + 1};
    }
    std::string close("</");
    close.append(tag).push_back('>');
    const std::size_t close_at = xml.find(close, open_end + 1);
    if (close_at == std::string_view::npos) {
      return {};
    }
    return {xml.substr(open_end + 1, close_at - open_end - 1), close_at + close.size()};
  }
  return {};
}

/// Every element `tag` in `xml`, in order.
std::vector<std::string_view> allElements(std::string_view xml, std::string_view tag) {
  std::vector<std::string_view> found;
  for (Element e = findElement(xml, tag); e.end != std::string_view::npos;
       e = findElement(xml, tag, e.end)) {
    found.push_back(e.inner);
  }
  return found;
}

/// Text content with the five XML entities decoded and surrounding white space removed.
std::string textOf(std::string_view inner) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!inner.empty() && space(inner.front())) {
    inner.remove_prefix(1);
  }
  while (!inner.empty() && space(inner.back())) {
    inner.remove_suffix(1);
  }
  static constexpr std::pair<std::string_view, char> kEntities[] = {
      {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
  std::string text;
  for (std::size_t i = 0; i < inner.size(); ++i) {
    bool decoded = false;
    for (const auto& [entity, c] : kEntities) {
      if (inner.substr(i, entity.size()) == entity) {
        text += c;
        i += entity.size() - 1;
        decoded = true;
        break;
      }
    }
    if (!decoded) {
      text += inner[i];
    }
  }
  return text;
}

std::string withoutSpaces(std::string_view text) {
  std::string out;
  std::copy_if(text.begin(), text.end(), std::back_inserter(out), [](char c) { return c != ' '; });
  return out;
}

std::uint32_t toDomain(std::string_view inner) {
  const std::string text = textOf(inner);
  std::uint32_t value = 0;
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

/// The domains of a rule: <id> and <id_range><min/><max/></id_range> (a range without max:
/// open-ended).
std::vector<std::pair<std::uint32_t, std::uint32_t>> domainsOf(std::string_view rule) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> domains;
  const std::string_view block = findElement(rule, "domains").inner;
  for (std::string_view id : allElements(block, "id")) {
    domains.emplace_back(toDomain(id), toDomain(id));
  }
  for (std::string_view range : allElements(block, "id_range")) {
    const Element min = findElement(range, "min");
    const Element max = findElement(range, "max");
    domains.emplace_back(min.end == std::string_view::npos ? 0u : toDomain(min.inner),
                         max.end == std::string_view::npos ? ~0u : toDomain(max.inner));
  }
  return domains;
}

/// The topic patterns of every <publish> (or <subscribe>) criterion of a rule.
std::vector<std::string> topicsOf(std::string_view rule, std::string_view criterion) {
  std::vector<std::string> topics;
  for (std::string_view block : allElements(rule, criterion)) {
    for (std::string_view topic : allElements(block, "topic")) {
      topics.push_back(textOf(topic));
    }
  }
  return topics;
}

int twoDigits(std::string_view text, std::size_t at) {
  return (text[at] - '0') * 10 + (text[at + 1] - '0');
}

}  // namespace

Result<std::time_t> parseIsoTime(std::string_view text) {
  const std::string t = textOf(text);
  const auto bad = [&]() {
    return fail(ErrorCode::kFormat, "\"" + t + "\" is not an ISO 8601 time (2030-05-01T00:00:00)");
  };
  if (t.size() < 19 || t[4] != '-' || t[7] != '-' || t[10] != 'T' || t[13] != ':' || t[16] != ':') {
    return bad();
  }
  for (std::size_t i : {0u, 1u, 2u, 3u, 5u, 6u, 8u, 9u, 11u, 12u, 14u, 15u, 17u, 18u}) {
    if (t[i] < '0' || t[i] > '9') {
      return bad();
    }
  }
  std::tm tm{};
  tm.tm_year = twoDigits(t, 0) * 100 + twoDigits(t, 2) - 1900;
  tm.tm_mon = twoDigits(t, 5) - 1;
  tm.tm_mday = twoDigits(t, 8);
  tm.tm_hour = twoDigits(t, 11);
  tm.tm_min = twoDigits(t, 14);
  tm.tm_sec = twoDigits(t, 17);
  std::time_t seconds = timegm(&tm);
  std::size_t at = 19;
  while (at < t.size() && (t[at] == '.' || (t[at] >= '0' && t[at] <= '9'))) {
    ++at;  // a fraction of a second: below the documents' resolution
  }
  if (at + 6 == t.size() && (t[at] == '+' || t[at] == '-') && t[at + 3] == ':') {
    const int offset = (twoDigits(t, at + 1) * 60 + twoDigits(t, at + 4)) * 60;
    seconds -= t[at] == '+' ? offset : -offset;
  } else if (at != t.size() && !(at + 1 == t.size() && t[at] == 'Z')) {
    return bad();
  }
  return seconds;
}

std::vector<PermissionsGrant::Rule> PermissionsGrant::rulesOf(std::string_view grant) {
  std::vector<Rule> rules;
  std::size_t from = 0;
  while (true) {
    const Element allow = findElement(grant, "allow_rule", from);
    const Element deny = findElement(grant, "deny_rule", from);
    if (allow.end == std::string_view::npos && deny.end == std::string_view::npos) {
      return rules;
    }
    const bool is_allow = deny.end == std::string_view::npos ||
                          (allow.end != std::string_view::npos && allow.end < deny.end);
    const Element& e = is_allow ? allow : deny;
    rules.push_back(Rule{is_allow, domainsOf(e.inner), topicsOf(e.inner, "publish"),
                         topicsOf(e.inner, "subscribe")});
    from = e.end;
  }
}

Result<PermissionsGrant> PermissionsGrant::find(std::string_view xml, std::string_view subject) {
  const std::string wanted = withoutSpaces(subject);
  std::string subjects;
  for (std::string_view grant : allElements(xml, "grant")) {
    const std::string name = textOf(findElement(grant, "subject_name").inner);
    if (withoutSpaces(name) != wanted) {
      subjects += subjects.empty() ? "\"" + name + "\"" : ", \"" + name + "\"";
      continue;
    }
    PermissionsGrant result;
    result.rules_ = rulesOf(grant);
    result.default_allow_ = textOf(findElement(grant, "default").inner) == "ALLOW";
    const std::string_view validity = findElement(grant, "validity").inner;
    auto not_before = parseIsoTime(findElement(validity, "not_before").inner);
    auto not_after = parseIsoTime(findElement(validity, "not_after").inner);
    if (!not_before || !not_after) {
      return fail(ErrorCode::kFormat,
                  "the grant of " + std::string(subject) + " has no valid " +
                      "<validity>: " + (!not_before ? not_before : not_after).error().message);
    }
    result.not_before_ = *not_before;
    result.not_after_ = *not_after;
    return result;
  }
  return fail(ErrorCode::kFormat, "no <grant> for the certificate's subject \"" +
                                      std::string(subject) + "\" (it grants " +
                                      (subjects.empty() ? "nobody" : subjects) + ")");
}

bool governanceCoversDomain(std::string_view xml, std::uint32_t domain) {
  for (std::string_view rule : allElements(xml, "domain_rule")) {
    for (const auto& [min, max] : domainsOf(rule)) {
      if (domain >= min && domain <= max) {
        return true;
      }
    }
  }
  return false;
}

bool PermissionsGrant::coversDomain(std::uint32_t domain) const {
  return default_allow_ || std::any_of(rules_.begin(), rules_.end(), [&](const Rule& rule) {
           return rule.allow &&
                  std::any_of(rule.domains.begin(), rule.domains.end(), [&](auto range) {
                    return domain >= range.first && domain <= range.second;
                  });
         });
}

bool PermissionsGrant::allows(std::uint32_t domain, std::string_view topic, TopicUse use) const {
  const std::string name(topic);
  for (const Rule& rule : rules_) {
    const bool in_domain = std::any_of(rule.domains.begin(), rule.domains.end(), [&](auto range) {
      return domain >= range.first && domain <= range.second;
    });
    if (!in_domain) {
      continue;
    }
    const std::vector<std::string>& patterns =
        use == TopicUse::kPublish ? rule.publish : rule.subscribe;
    const bool named = std::any_of(patterns.begin(), patterns.end(), [&](const std::string& p) {
      return fnmatch(p.c_str(), name.c_str(), 0) == 0;
    });
    if (named) {
      return rule.allow;
    }
  }
  return default_allow_;
}

}  // namespace raymap::security
