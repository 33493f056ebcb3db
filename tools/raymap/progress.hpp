// SPDX-License-Identifier: BSD-3-Clause
// A progress bar on standard error, shown only when it is a terminal.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace raymap::cli {

/// @brief Redraws one status line on stderr at most five times a second. Silent when stderr is
/// not a terminal or when disabled, so logs and pipes stay clean. Not thread-safe.
class ProgressBar {
 public:
  ProgressBar(std::string label, bool enabled);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// @brief fraction in [0, 1]; rays so far; rays per second of integration.
  /// @brief Redraws (at most five times a second) with `extra` after the rate (may be empty).
  void update(double fraction, std::uint64_t rays, double rays_per_second,
              const std::string& extra = {});
  /// @brief True when the next update() would draw: compute costly extra text only then.
  bool due() const;
  /// @brief Clears the line.
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace raymap::cli
