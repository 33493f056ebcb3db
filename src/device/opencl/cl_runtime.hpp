// SPDX-License-Identifier: BSD-3-Clause
// OpenCL start-up: finding platforms and devices, picking one, and owning the context, queue,
// programs, kernels, buffers and events as RAII values. Only start-up code allocates here; the
// handles are then used on the integration path through the raw cl_* calls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "raymap/error.hpp"
#include <CL/cl.h>

namespace raymap::opencl {

/// @brief Name of an OpenCL status code ("CL_OUT_OF_RESOURCES"), or "CL_ERROR(<n>)".
const char* errorName(cl_int status) noexcept;

/// @brief What raymap needs to know about one device. Plain value type.
struct DeviceInfo {
  std::uint32_t platform_index = 0;  ///< position in clGetPlatformIDs order
  std::uint32_t device_index = 0;    ///< position among the platform's devices (all types)
  cl_platform_id platform = nullptr;
  cl_device_id device = nullptr;
  std::string platform_name;
  std::string platform_version;
  std::string device_name;  ///< trimmed
  std::string vendor;
  std::string device_version;  ///< "OpenCL 3.0 PoCL ..."
  std::string driver_version;
  std::string opencl_c_version;  ///< "OpenCL C 1.2 ..."
  std::string type;              ///< "GPU", "CPU", "accelerator" or "other"
  std::uint32_t compute_units = 0;
  std::uint64_t global_mem_bytes = 0;
  std::uint64_t max_alloc_bytes = 0;  ///< CL_DEVICE_MAX_MEM_ALLOC_SIZE
  std::size_t max_work_group_size = 0;
  bool int64_atomics = false;   ///< cl_khr_int64_base_atomics
  bool fp64 = false;            ///< cl_khr_fp64: double precision (rays prepared on the device)
  bool unified_memory = false;  ///< CL_DEVICE_HOST_UNIFIED_MEMORY
};

/// @brief Every device of every platform. Fails with a clear message when no platform exists
/// (no ICD installed: "install pocl-opencl-icd or your GPU's OpenCL driver").
Result<std::vector<DeviceInfo>> listDevices();

/// @brief How the user picks a device: each field empty (default), a decimal index, or a
/// case-insensitive substring of the platform / device name.
struct DeviceSelector {
  std::string platform;
  std::string device;
};

/// @brief The device a selector names. Default: the first GPU of the chosen platform(s), else
/// their first device. Errors list what is available.
Result<DeviceInfo> selectDevice(const std::vector<DeviceInfo>& devices,
                                const DeviceSelector& selector);

/// @brief listDevices() then selectDevice(): the device the options name.
Result<DeviceInfo> findDevice(const DeviceSelector& selector);

/// @brief RAII owner of one OpenCL object (release function R). Move-only.
template <class Handle, cl_int (*Release)(Handle)>
class Owned {
 public:
  Owned() = default;
  explicit Owned(Handle handle) noexcept : handle_(handle) {}
  Owned(Owned&& other) noexcept : handle_(other.handle_) { other.handle_ = nullptr; }
  Owned& operator=(Owned&& other) noexcept {
    if (this != &other) {
      reset();
      handle_ = other.handle_;
      other.handle_ = nullptr;
    }
    return *this;
  }
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  ~Owned() { reset(); }
  Handle get() const noexcept { return handle_; }
  explicit operator bool() const noexcept { return handle_ != nullptr; }
  void reset() noexcept {
    if (handle_ != nullptr) {
      (void)Release(handle_);
      handle_ = nullptr;
    }
  }

 private:
  Handle handle_ = nullptr;
};

using ContextHandle = Owned<cl_context, clReleaseContext>;
using QueueHandle = Owned<cl_command_queue, clReleaseCommandQueue>;
using ProgramHandle = Owned<cl_program, clReleaseProgram>;
using KernelHandle = Owned<cl_kernel, clReleaseKernel>;
using BufferHandle = Owned<cl_mem, clReleaseMemObject>;
using EventHandle = Owned<cl_event, clReleaseEvent>;

/// @brief A context with one in-order command queue on one device. Move-only.
struct DeviceContext {
  DeviceInfo info;
  ContextHandle context;
  QueueHandle queue;
};

/// @brief Creates a context and an in-order queue on the device.
Result<DeviceContext> createContext(const DeviceInfo& device);

/// @brief Allocates a device buffer of `bytes` (read-write). Errors name `what` and the size, and
/// say when the size exceeds the device's maximum allocation.
Result<BufferHandle> createBuffer(const DeviceContext& ctx, std::size_t bytes,
                                  std::string_view what);

/// @brief Wraps `bytes` of host memory at `host` as a device buffer (CL_MEM_USE_HOST_PTR): on a
/// device that shares memory with the host (CL_DEVICE_HOST_UNIFIED_MEMORY) kernels work on that
/// memory in place. `host` must stay valid for the buffer's life. Same errors as createBuffer().
Result<BufferHandle> createHostBuffer(const DeviceContext& ctx, void* host, std::size_t bytes,
                                      std::string_view what);

/// @brief Creates a kernel from a built program.
Result<KernelHandle> createKernel(const ProgramHandle& program, const char* name);

/// @brief Creates each named kernel of a built program into its handle; the first failure is
/// returned.
Expected<void, Error> createKernels(
    const ProgramHandle& program,
    std::initializer_list<std::pair<KernelHandle*, const char*>> kernels);

}  // namespace raymap::opencl
