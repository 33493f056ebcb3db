// SPDX-License-Identifier: BSD-3-Clause
// Owning handles for CUDA runtime objects (device memory, page-locked host memory, streams,
// events) and error text. Internal to src/device/cuda: this header brings the CUDA runtime API in.
#pragma once

#include <cstddef>
#include <memory>
#include <memory_resource>
#include <string>

#include "raymap/error.hpp"
#include <cuda_runtime_api.h>

namespace raymap::cuda {

/// @brief "cudaErrorMemoryAllocation (out of memory)".
std::string errorText(cudaError_t status);

/// @brief A failure of `what` as an Error naming the CUDA status.
Error cudaFailure(const std::string& what, cudaError_t status);

struct DeviceFree {
  void operator()(void* p) const noexcept { (void)cudaFree(p); }
};
struct HostFree {
  void operator()(void* p) const noexcept { (void)cudaFreeHost(p); }
};
struct StreamDestroy {
  void operator()(CUstream_st* s) const noexcept { (void)cudaStreamDestroy(s); }
};
struct EventDestroy {
  void operator()(CUevent_st* e) const noexcept { (void)cudaEventDestroy(e); }
};

using DeviceMemoryHandle = std::unique_ptr<void, DeviceFree>;  ///< cudaMalloc
using PinnedMemoryHandle = std::unique_ptr<void, HostFree>;    ///< cudaMallocHost
using StreamHandle = std::unique_ptr<CUstream_st, StreamDestroy>;
using EventHandle = std::unique_ptr<CUevent_st, EventDestroy>;

/// @brief Host memory page-locked in place (cudaHostRegister) until destroyed. Move-only.
class HostRegistration {
 public:
  HostRegistration() = default;
  HostRegistration(HostRegistration&& other) noexcept : ptr_(other.ptr_) { other.ptr_ = nullptr; }
  HostRegistration& operator=(HostRegistration&& other) noexcept;
  HostRegistration(const HostRegistration&) = delete;
  HostRegistration& operator=(const HostRegistration&) = delete;
  ~HostRegistration() { reset(); }

  /// @brief Page-locks [ptr, ptr + bytes) with `flags` (cudaHostRegister*); `what` names it in
  /// the error.
  static Result<HostRegistration> create(void* ptr, std::size_t bytes, unsigned flags,
                                         const std::string& what);
  void reset() noexcept;
  explicit operator bool() const noexcept { return ptr_ != nullptr; }

 private:
  void* ptr_ = nullptr;
};

/// @brief Page-locked host memory as a memory resource (cudaHostAlloc, portable to every device;
/// std::bad_alloc when refused). Stateless and process-wide, so it outlives whatever uses it.
/// Thread-safe. Not for the real-time path: allocation pins pages and is slow.
std::pmr::memory_resource* pinnedHostMemory() noexcept;

/// @brief `bytes` of device memory; `what` names it in the error (which gives the size).
Result<DeviceMemoryHandle> allocateDevice(std::size_t bytes, const std::string& what);
/// @brief A non-blocking stream (it does not synchronise with the legacy default stream).
Result<StreamHandle> createStream();
/// @brief An event without timing whose waits yield the CPU instead of spinning.
Result<EventHandle> createEvent();

}  // namespace raymap::cuda
