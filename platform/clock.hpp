// SPDX-License-Identifier: BSD-3-Clause
// Monotonic and wall-clock time in integer nanoseconds, and absolute-deadline sleeps.
#pragma once

#include <cstdint>

namespace raymap::platform {

/// @brief Nanoseconds on CLOCK_MONOTONIC (never jumps; the time base of deadlines and budgets).
/// @return nanoseconds since an unspecified start (boot on Linux).
/// @rt wait-free; allocates: no; syscalls: none (vDSO); thread: any.
std::int64_t monotonicNowNs() noexcept;

/// @brief Nanoseconds on CLOCK_REALTIME since the Unix epoch (message stamps; may jump).
/// @rt wait-free; allocates: no; syscalls: none (vDSO); thread: any.
std::int64_t realtimeNowNs() noexcept;

/// @brief Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (clock_nanosleep TIMER_ABSTIME).
/// Resumes after EINTR, so it never returns before the deadline; returns at once when the
/// deadline has passed.
/// @param[in] deadline_ns absolute time on the monotonic clock (see monotonicNowNs()).
/// @rt blocks (by design); allocates: no; thread: any.
void sleepUntilMonotonicNs(std::int64_t deadline_ns) noexcept;

}  // namespace raymap::platform
