// SPDX-License-Identifier: BSD-3-Clause
// CUDA runtime handles and error text.
#include "src/device/cuda/cuda_handles.hpp"

#include <new>

namespace raymap::cuda {

std::string errorText(cudaError_t status) {
  return std::string(cudaGetErrorName(status)) + " (" + cudaGetErrorString(status) + ")";
}

Error cudaFailure(const std::string& what, cudaError_t status) {
  const ErrorCode code =
      status == cudaErrorMemoryAllocation ? ErrorCode::kCapacity : ErrorCode::kUnsupported;
  return Error{code, what + ": " + errorText(status)};
}

HostRegistration& HostRegistration::operator=(HostRegistration&& other) noexcept {
  if (this != &other) {
    reset();
    ptr_ = other.ptr_;
    other.ptr_ = nullptr;
  }
  return *this;
}

Result<HostRegistration> HostRegistration::create(void* ptr, std::size_t bytes, unsigned flags,
                                                  const std::string& what) {
  HostRegistration registration;
  if (bytes == 0) {
    return registration;
  }
  if (const cudaError_t status = cudaHostRegister(ptr, bytes, flags); status != cudaSuccess) {
    (void)cudaGetLastError();
    return Unexpected(
        cudaFailure("page-locking " + what + " (" + std::to_string(bytes) + " bytes)", status));
  }
  registration.ptr_ = ptr;
  return registration;
}

void HostRegistration::reset() noexcept {
  if (ptr_ != nullptr) {
    (void)cudaHostUnregister(ptr_);
    ptr_ = nullptr;
  }
}

namespace {

class PinnedHostResource final : public std::pmr::memory_resource {
 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override {
    // cudaHostAlloc returns page-aligned memory, more than any alignment asked of it here.
    void* p = nullptr;
    if (alignment > 4096 ||
        cudaHostAlloc(&p, bytes > 0 ? bytes : 1, cudaHostAllocPortable) != cudaSuccess) {
      (void)cudaGetLastError();
      throw std::bad_alloc();
    }
    return p;
  }
  void do_deallocate(void* p, std::size_t, std::size_t) override { (void)cudaFreeHost(p); }
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }
};

}  // namespace

std::pmr::memory_resource* pinnedHostMemory() noexcept {
  static PinnedHostResource resource;
  return &resource;
}

Result<DeviceMemoryHandle> allocateDevice(std::size_t bytes, const std::string& what) {
  void* p = nullptr;
  if (const cudaError_t status = cudaMalloc(&p, bytes > 0 ? bytes : 4); status != cudaSuccess) {
    (void)cudaGetLastError();
    return Unexpected(
        cudaFailure("CUDA " + what + " (" + std::to_string(bytes) + " bytes)", status));
  }
  return DeviceMemoryHandle(p);
}

Result<StreamHandle> createStream() {
  cudaStream_t stream = nullptr;
  if (const cudaError_t s = cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking);
      s != cudaSuccess) {
    (void)cudaGetLastError();  // a later launch's check must not see this failure as its own
    return Unexpected(cudaFailure("CUDA stream", s));
  }
  return StreamHandle(stream);
}

Result<EventHandle> createEvent() {
  cudaEvent_t event = nullptr;
  if (const cudaError_t s =
          cudaEventCreateWithFlags(&event, cudaEventDisableTiming | cudaEventBlockingSync);
      s != cudaSuccess) {
    (void)cudaGetLastError();
    return Unexpected(cudaFailure("CUDA event", s));
  }
  return EventHandle(event);
}

}  // namespace raymap::cuda
