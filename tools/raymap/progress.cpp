// SPDX-License-Identifier: BSD-3-Clause
// Terminal progress bar.
#include "tools/raymap/progress.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "platform/process.hpp"

namespace raymap::cli {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && platform::stderrIsTerminal()) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::due() const {
  return enabled_ &&
         (!drawn_ || std::chrono::steady_clock::now() - last_ >= std::chrono::milliseconds(200));
}

void ProgressBar::update(double fraction, std::uint64_t rays, double rays_per_second,
                         const std::string& extra) {
  if (!due()) {
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  last_ = now;
  drawn_ = true;
  constexpr int kWidth = 30;
  const double f = std::clamp(fraction, 0.0, 1.0);
  const int filled = static_cast<int>(f * kWidth);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(kWidth - filled), ' ');
  std::fprintf(stderr, "\r%s [%s] %5.1f%%  %llu rays  %.2f M rays/s %s%s", label_.c_str(),
               bar.c_str(), 100.0 * f, static_cast<unsigned long long>(rays), rays_per_second / 1e6,
               extra.empty() ? "" : " ", extra.c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (enabled_ && drawn_) {
    std::fprintf(stderr, "\r%*s\r", 160, "");
    std::fflush(stderr);
    drawn_ = false;
  }
}

}  // namespace raymap::cli
