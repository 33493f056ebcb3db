// SPDX-License-Identifier: BSD-3-Clause
// The hand-over between raymapd's ingest thread and its integrator while the integrator is
// behind: when a scan waits as received (PendingScans) rather than decoded (ScanMailbox), and the
// wake-up that brings the ingest thread back to decode it.
#pragma once

#include <atomic>

#include "src/pipeline/scan_mailbox.hpp"
#include "src/service/pending_scans.hpp"

namespace raymap::service {

/// @brief No decoded scan waits for the integrator and it holds none (relaxed snapshots).
inline bool mailboxIdle(const pipeline::ScanMailbox& mailbox) noexcept {
  return mailbox.waiting() == 0 && !mailbox.consumerHolds();
}

/// @brief Whether a scan arriving now must wait as received: the integrator holds a scan or has
/// one waiting, or older scans already wait (first in, first out). Ingest thread.
/// @rt wait-free; allocates: no.
inline bool integratorBusy(const PendingScans& pending,
                           const pipeline::ScanMailbox& mailbox) noexcept {
  return pending.size() > 0 || !mailboxIdle(mailbox);
}

/// @brief Whether the ingest thread, holding scans (pending.size() > 0, the push already made),
/// may decode the oldest now; if not, the integrator's next release wakes it (heldScansWait).
///
/// Memory ordering, a store-buffering (Dekker) pair that every architecture may reorder without
/// fences, arm64 and x86-64 alike:
///
///     ingest thread                         integrator (ScanMailbox::release)
///     pending.size_ = n   (seq_cst store)   slot state = free   (release store)
///     fence(seq_cst)      (here)            fence(seq_cst)
///     read slot states    (relaxed)         read pending.size_  (seq_cst, heldScansWait)
///
/// The two fences are ordered one way or the other, so at least one side sees the other's store:
/// the ingest thread sees the slot free and decodes, or the integrator sees a scan held and
/// wakes it. Neither missing the other would strand a held scan until the next cloud arrives.
/// A plain store then load on either side would not do (a store may be passed by a later load
/// of another location: x86's store buffer, arm64's stlr then ldr). Stress test:
/// ScanHandOff.AHeldScanIsNeverStrandedWhileTheIntegratorIdles (tests/service).
/// @rt wait-free; allocates: no.
inline bool integratorReadyForHeld(const pipeline::ScanMailbox& mailbox) noexcept {
  std::atomic_thread_fence(std::memory_order_seq_cst);
  return mailboxIdle(mailbox);
}

/// @brief Decodes held scans, oldest first, while the integrator is ready for them: `decode`
/// takes each PendingScans::Entry popped. Returns when none is held, or when the integrator is
/// busy (its next release wakes the ingest thread: heldScansWait). Ingest thread.
/// @rt as `decode`; allocates: no.
template <class Decode>
void decodeHeldWhileReady(PendingScans& pending, const pipeline::ScanMailbox& mailbox,
                          Decode&& decode) {
  while (pending.size() > 0 && integratorReadyForHeld(mailbox)) {
    decode(pending.pop());
  }
}

/// @brief Asked by the integrator after each release (ScanMailbox's release listener, after its
/// fence): whether the ingest thread holds scans and must be woken to decode the oldest.
/// @rt wait-free; allocates: no.
inline bool heldScansWait(const PendingScans& pending) noexcept { return pending.size() > 0; }

}  // namespace raymap::service
