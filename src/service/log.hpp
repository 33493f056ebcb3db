// SPDX-License-Identifier: BSD-3-Clause
// raymapd's log lines on standard error, with the syslog priority prefix journald understands
// when running under systemd. Not for real-time threads (it formats): they count events and the
// diagnostics reporter logs them.
#pragma once

namespace raymap::service {

enum class LogLevel : int { kError = 3, kWarning = 4, kNotice = 5, kInfo = 6 };

/// @brief Writes one line: "<N>text" under systemd (JOURNAL_STREAM set), else
/// "raymapd: level: text". Thread-safety: any thread (one write per line).
void logLine(LogLevel level, const char* format, ...) __attribute__((format(printf, 2, 3)));

}  // namespace raymap::service
