// SPDX-License-Identifier: BSD-3-Clause
// parseJson and the lookups over nlohmann's documents.
#include "tests/support/json_doc.hpp"

#include <gtest/gtest.h>

namespace raymap::test {

std::optional<Json> parseJson(std::string_view text) {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    ADD_FAILURE() << "not JSON (" << e.what() << "):\n" << text;
    return std::nullopt;
  }
}

const Json* findPath(const Json& json, const std::vector<std::string>& path) {
  const Json* at = &json;
  for (const std::string& key : path) {
    if (!at->is_object()) {
      return nullptr;
    }
    const auto member = at->find(key);
    if (member == at->end()) {
      return nullptr;
    }
    at = &*member;
  }
  return at;
}

const Json* findFirst(const Json& json, std::string_view key) {
  if (json.is_object()) {
    for (const auto& [name, value] : json.items()) {
      if (name == key) {
        return &value;
      }
      if (const Json* inner = findFirst(value, key); inner != nullptr) {
        return inner;
      }
    }
  } else if (json.is_array()) {
    for (const Json& item : json) {
      if (const Json* inner = findFirst(item, key); inner != nullptr) {
        return inner;
      }
    }
  }
  return nullptr;
}

}  // namespace raymap::test
