// SPDX-License-Identifier: BSD-3-Clause
// A checked reader over yaml-cpp nodes for configuration files (scenes, raymapd): every error
// names the file, the line, the key path and the reason; unknown keys are errors (typos are not
// silently ignored). Start-up code only.
#pragma once

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include <yaml-cpp/yaml.h>

#include "src/core/vec3.hpp"

namespace raymap::config {

/// A number as the messages print it ("0.5", "1e+09").
std::string formatNumber(double value);

/// Where the reader is and the first error it met.
class Context {
 public:
  explicit Context(std::string file) : file_(std::move(file)) {}

  bool failed() const noexcept { return error_.has_value(); }

  /// Records "FILE: line N: PATH: REASON" unless an error is already recorded. `at` gives the
  /// line (the mapping that lacks a key, the value that is wrong).
  void fail(const YAML::Node& at, const std::string& path, const std::string& reason) {
    if (error_) {
      return;
    }
    std::string message = file_ + ": ";
    if (at.IsDefined()) {
      const YAML::Mark mark = at.Mark();
      if (mark.line >= 0) {
        message += "line " + std::to_string(mark.line + 1) + ": ";
      }
    }
    if (!path.empty()) {
      message += path + ": ";
    }
    error_ = Error{ErrorCode::kFormat, message + reason};
  }

  Error error() const { return error_.value_or(Error{}); }

 private:
  std::string file_;
  std::optional<Error> error_;
};

/// Key paths as the messages write them: "objects[3].rise".
std::string child(const std::string& path, const std::string& key);
std::string item(const std::string& path, std::size_t index);

/// A finite number.
double toNumber(Context& ctx, const YAML::Node& node, const std::string& path);

/// An integer written as one (no fraction, no exponent), within [lo, hi].
template <class Int>
Int toInteger(Context& ctx, const YAML::Node& node, const std::string& path, Int lo, Int hi) {
  Int value{};
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    const char* end = text.data() + text.size();
    const auto [at, ec] = std::from_chars(text.data(), end, value);
    if (ec == std::errc() && at == end && !text.empty()) {
      if (value >= lo && value <= hi) {
        return value;
      }
      ctx.fail(node, path,
               "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + " (got " +
                   text + ")");
      return lo;
    }
  }
  ctx.fail(node, path, "expected an integer");
  return lo;
}

/// A list of exactly `count` numbers; `shape` names them in the message ("[x, y, z]").
std::vector<double> toNumbers(Context& ctx, const YAML::Node& node, const std::string& path,
                              std::size_t count, const char* shape);

/// One YAML mapping being read. Every key a reader asks for is known; finish() reports any other.
class Fields {
 public:
  Fields(Context& ctx, const YAML::Node& node, std::string path)
      : ctx_(ctx), node_(node), path_(std::move(path)) {
    if (!node.IsMap()) {
      ctx_.fail(node, path_, "expected a mapping (key: value lines)");
      return;
    }
    std::set<std::string> seen;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) {
        ctx_.fail(entry.first, path_, "keys must be plain words");
        return;
      }
      if (!seen.insert(entry.first.Scalar()).second) {
        ctx_.fail(entry.first, child(path_, entry.first.Scalar()), "duplicate key");
        return;
      }
    }
    map_ = true;
  }

  std::string path(const std::string& key) const { return child(path_, key); }

  /// The value of `key` (undefined when absent); `key` becomes known.
  YAML::Node get(const std::string& key) {
    asked_.push_back(key);
    return map_ ? node_[key] : YAML::Node(YAML::NodeType::Undefined);
  }
  bool has(const std::string& key) { return get(key).IsDefined(); }

  /// The value of a key that must be there (a null node after reporting it missing).
  YAML::Node required(const std::string& key) {
    YAML::Node value = get(key);
    if (!value.IsDefined()) {
      ctx_.fail(node_, path(key), "required key missing");
      return YAML::Node(YAML::NodeType::Null);
    }
    return value;
  }

  double number(const std::string& key) { return toNumber(ctx_, required(key), path(key)); }
  double number(const std::string& key, double fallback) {
    const YAML::Node value = get(key);
    return value.IsDefined() ? toNumber(ctx_, value, path(key)) : fallback;
  }
  /// A number that must be > 0 (or >= 0 with `allow_zero`).
  double positive(const std::string& key, std::optional<double> fallback = std::nullopt,
                  bool allow_zero = false) {
    const double value = fallback && !has(key) ? *fallback : number(key);
    if (allow_zero ? value < 0.0 : value <= 0.0) {
      ctx_.fail(get(key), path(key),
                std::string("must be ") + (allow_zero ? ">= 0" : "> 0") + " (got " +
                    formatNumber(value) + ")");
    }
    return value;
  }
  template <class Int>
  Int integer(const std::string& key, Int lo, Int hi) {
    return toInteger<Int>(ctx_, required(key), path(key), lo, hi);
  }
  template <class Int>
  Int integer(const std::string& key, Int fallback, Int lo, Int hi) {
    const YAML::Node value = get(key);
    return value.IsDefined() ? toInteger<Int>(ctx_, value, path(key), lo, hi) : fallback;
  }
  Vec3d vec3(const std::string& key) {
    const std::vector<double> v = toNumbers(ctx_, required(key), path(key), 3, "[x, y, z]");
    return {v[0], v[1], v[2]};
  }
  std::array<double, 2> vec2(const std::string& key) {
    const std::vector<double> v = toNumbers(ctx_, required(key), path(key), 2, "[x, y]");
    return {v[0], v[1]};
  }
  /// One of `choices`, as its index.
  std::size_t choice(const std::string& key, const std::vector<std::string>& choices) {
    const YAML::Node value = required(key);
    if (value.IsScalar()) {
      const auto at = std::find(choices.begin(), choices.end(), value.Scalar());
      if (at != choices.end()) {
        return static_cast<std::size_t>(at - choices.begin());
      }
    }
    std::string list;
    for (std::size_t i = 0; i < choices.size(); ++i) {
      list += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
    }
    ctx_.fail(value, path(key),
              "must be " + list + (value.IsScalar() ? " (got '" + value.Scalar() + "')" : ""));
    return 0;
  }
  /// Reports a failed check of `key`'s value.
  void check(bool ok, const std::string& key, const std::string& reason) {
    if (!ok) {
      ctx_.fail(get(key), path(key), reason);
    }
  }

  /// Makes `keys` known and reports any other key now, before a missing key is reported for what
  /// may be a misspelt one.
  void knownKeys(std::initializer_list<const char*> keys) {
    asked_.insert(asked_.end(), keys.begin(), keys.end());
    finish();
  }

  /// Reports the first key nobody asked for.
  void finish() {
    if (!map_ || ctx_.failed()) {
      return;
    }
    for (const auto& entry : node_) {
      const std::string& key = entry.first.Scalar();
      if (std::find(asked_.begin(), asked_.end(), key) == asked_.end()) {
        std::vector<std::string> known = asked_;
        std::sort(known.begin(), known.end());
        known.erase(std::unique(known.begin(), known.end()), known.end());
        std::string list;
        for (const std::string& k : known) {
          list += (list.empty() ? "" : ", ") + k;
        }
        ctx_.fail(entry.first, path(key), "unknown key (known here: " + list + ")");
        return;
      }
    }
  }

 private:
  Context& ctx_;
  const YAML::Node node_;
  std::string path_;
  std::vector<std::string> asked_;
  bool map_ = false;
};

/// @brief A text value (a YAML scalar) at `key`, or `fallback` when the key is absent.
std::string text(Fields& f, const std::string& key, const std::string& fallback);
/// @brief true/false at `key`, or `fallback` when absent.
bool flag(Fields& f, const std::string& key, bool fallback);
/// @brief The index of the value at `key` in `choices` (an error lists them), or `fallback`
/// when absent.
std::size_t choiceOr(Fields& f, const std::string& key, const std::vector<std::string>& choices,
                     std::size_t fallback);

}  // namespace raymap::config
