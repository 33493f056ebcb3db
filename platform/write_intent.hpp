// SPDX-License-Identifier: BSD-3-Clause
// First touch of a page as a write, for memory that is read and then written.
#pragma once

namespace raymap::platform {

/// @brief Accesses the byte at `object` with write intent and leaves its value as it is.
///
/// Why: a page of anonymous memory that is *read* before it is ever written is mapped to the
/// kernel's shared zero page; the write that follows then faults a second time, copies the zero
/// page and flushes the old mapping from every core that runs this process (an inter-processor
/// interrupt, a VM exit on a virtual machine). Touching the word with write intent first makes
/// the first fault allocate the page directly. Measured on a 2-core VM with a second thread of
/// the process running: 5.8-6.7 us a page read then written, 1.8-2.0 us touched first
/// (one fault a page instead of two).
///
/// Where it pays: layers written only where samples land (voxel means, NDT Gaussians), whose
/// pages stay the OS's zero pages until the first sample, and whose update reads the old value
/// first. On an already-resident page it costs a read-modify-write of a cache line about to be
/// written anyway.
///
/// Thread-safety: only for memory the calling thread may write (on x86 it is a plain,
/// non-atomic read-modify-write of one byte). Real-time: no allocation, no system call; may
/// page-fault once on a page that is not resident, as the write it precedes would.
inline void touchForWrite(void* object) noexcept {
  auto* byte = static_cast<unsigned char*>(object);  // a char type may alias any object
#if defined(__x86_64__) || defined(__i386__)
  // An x86 read-modify-write instruction faults as a write. The compiler must not drop it:
  // volatile asm with the byte as an in-out memory operand.
  asm volatile("addb $0, %0" : "+m"(*byte));
#else
  // Elsewhere an atomic add of 0 (a store-exclusive or LSE atomic: a write access); relaxed, as
  // it orders nothing. Where the architecture's atomic reads first, it is as before: harmless.
  (void)__atomic_fetch_add(byte, 0U, __ATOMIC_RELAXED);
#endif
}

}  // namespace raymap::platform
