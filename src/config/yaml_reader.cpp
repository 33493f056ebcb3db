// SPDX-License-Identifier: BSD-3-Clause
// The checked YAML reader's out-of-line helpers.
#include "src/config/yaml_reader.hpp"

#include <sstream>

namespace raymap::config {

std::string formatNumber(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

std::string child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string item(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

double toNumber(Context& ctx, const YAML::Node& node, const std::string& path) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value)) {
    ctx.fail(node, path, "expected a number");
    return 0.0;
  }
  if (!std::isfinite(value)) {
    ctx.fail(node, path, "must be finite (got " + node.Scalar() + ")");
    return 0.0;
  }
  return value;
}

std::vector<double> toNumbers(Context& ctx, const YAML::Node& node, const std::string& path,
                              std::size_t count, const char* shape) {
  std::vector<double> values(count, 0.0);
  if (!node.IsSequence() || node.size() != count) {
    ctx.fail(
        node, path,
        std::string("expected ") + shape + " (a list of " + std::to_string(count) + " numbers)");
    return values;
  }
  for (std::size_t i = 0; i < count; ++i) {
    values[i] = toNumber(ctx, node[i], item(path, i));
  }
  return values;
}

std::string text(Fields& f, const std::string& key, const std::string& fallback) {
  const YAML::Node value = f.get(key);
  if (!value.IsDefined()) {
    return fallback;
  }
  if (!value.IsScalar()) {
    f.check(false, key, "expected a text value");
    return fallback;
  }
  return value.Scalar();
}

bool flag(Fields& f, const std::string& key, bool fallback) {
  const YAML::Node value = f.get(key);
  bool result = fallback;
  if (value.IsDefined() && (!value.IsScalar() || !YAML::convert<bool>::decode(value, result))) {
    f.check(false, key, "expected true or false");
  }
  return result;
}

std::size_t choiceOr(Fields& f, const std::string& key, const std::vector<std::string>& choices,
                     std::size_t fallback) {
  return f.has(key) ? f.choice(key, choices) : fallback;
}

}  // namespace raymap::config
