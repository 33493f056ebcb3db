// SPDX-License-Identifier: BSD-3-Clause
// OpenCL device discovery and selection, and creation of contexts, buffers and kernels.
#include "src/device/opencl/cl_runtime.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <optional>
#include <utility>

#include <CL/cl_ext.h>

namespace raymap::opencl {
namespace {

constexpr const char* kNoPlatformMessage =
    "no OpenCL platform found: install an OpenCL driver (pocl-opencl-icd for the CPU, "
    "intel-opencl-icd for Intel graphics) or pick backend.name: cpu";

std::string trimmed(std::string text) {
  // Drivers pad names with spaces (Intel) and count the terminating NUL in the size.
  const auto is_blank = [](char c) {
    return c == '\0' || std::isspace(static_cast<unsigned char>(c)) != 0;
  };
  const auto first = std::find_if_not(text.begin(), text.end(), is_blank);
  const auto last = std::find_if_not(text.rbegin(), text.rend(), is_blank).base();
  return first < last ? std::string(first, last) : std::string();
}

std::string platformString(cl_platform_id platform, cl_platform_info param) {
  std::size_t size = 0;
  if (clGetPlatformInfo(platform, param, 0, nullptr, &size) != CL_SUCCESS || size == 0) {
    return {};
  }
  std::string text(size, '\0');
  if (clGetPlatformInfo(platform, param, size, text.data(), nullptr) != CL_SUCCESS) {
    return {};
  }
  return trimmed(std::move(text));
}

std::string deviceString(cl_device_id device, cl_device_info param) {
  std::size_t size = 0;
  if (clGetDeviceInfo(device, param, 0, nullptr, &size) != CL_SUCCESS || size == 0) {
    return {};
  }
  std::string text(size, '\0');
  if (clGetDeviceInfo(device, param, size, text.data(), nullptr) != CL_SUCCESS) {
    return {};
  }
  return trimmed(std::move(text));
}

// A query that fails leaves the zero default: the listing should still show the device.
template <class T>
T deviceValue(cl_device_id device, cl_device_info param) {
  T value{};
  if (clGetDeviceInfo(device, param, sizeof(value), &value, nullptr) != CL_SUCCESS) {
    return T{};
  }
  return value;
}

const char* typeName(cl_device_type type) {
  if ((type & CL_DEVICE_TYPE_GPU) != 0) {
    return "GPU";
  }
  if ((type & CL_DEVICE_TYPE_CPU) != 0) {
    return "CPU";
  }
  if ((type & CL_DEVICE_TYPE_ACCELERATOR) != 0) {
    return "accelerator";
  }
  return "other";
}

// Whole-word match: the extension list is space-separated, and some names are prefixes of others.
bool hasExtension(const std::string& extensions, std::string_view name) {
  std::size_t at = 0;
  while ((at = extensions.find(name, at)) != std::string::npos) {
    const std::size_t end = at + name.size();
    const bool starts = at == 0 || extensions[at - 1] == ' ';
    const bool ends = end == extensions.size() || extensions[end] == ' ';
    if (starts && ends) {
      return true;
    }
    at = end;
  }
  return false;
}

DeviceInfo describe(std::uint32_t platform_index, std::uint32_t device_index,
                    cl_platform_id platform, cl_device_id device) {
  DeviceInfo info;
  info.platform_index = platform_index;
  info.device_index = device_index;
  info.platform = platform;
  info.device = device;
  info.platform_name = platformString(platform, CL_PLATFORM_NAME);
  info.platform_version = platformString(platform, CL_PLATFORM_VERSION);
  info.device_name = deviceString(device, CL_DEVICE_NAME);
  info.vendor = deviceString(device, CL_DEVICE_VENDOR);
  info.device_version = deviceString(device, CL_DEVICE_VERSION);
  info.driver_version = deviceString(device, CL_DRIVER_VERSION);
  info.opencl_c_version = deviceString(device, CL_DEVICE_OPENCL_C_VERSION);
  info.type = typeName(deviceValue<cl_device_type>(device, CL_DEVICE_TYPE));
  info.compute_units = deviceValue<cl_uint>(device, CL_DEVICE_MAX_COMPUTE_UNITS);
  info.global_mem_bytes = deviceValue<cl_ulong>(device, CL_DEVICE_GLOBAL_MEM_SIZE);
  info.max_alloc_bytes = deviceValue<cl_ulong>(device, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
  info.max_work_group_size = deviceValue<std::size_t>(device, CL_DEVICE_MAX_WORK_GROUP_SIZE);
  const std::string extensions = deviceString(device, CL_DEVICE_EXTENSIONS);
  info.int64_atomics = hasExtension(extensions, "cl_khr_int64_base_atomics");
  info.fp64 = hasExtension(extensions, "cl_khr_fp64");
  info.unified_memory = deviceValue<cl_bool>(device, CL_DEVICE_HOST_UNIFIED_MEMORY) == CL_TRUE;
  return info;
}

std::string lowered(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

bool containsIgnoringCase(std::string_view haystack, std::string_view needle) {
  return lowered(haystack).find(lowered(needle)) != std::string::npos;
}

// A selector made only of digits is an index; anything else is a name substring.
std::optional<std::uint32_t> parseIndex(const std::string& text) {
  if (text.empty() || !std::all_of(text.begin(), text.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c)) != 0;
      })) {
    return std::nullopt;
  }
  std::uint32_t value = 0;
  const auto [end, status] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (status != std::errc() || end != text.data() + text.size()) {
    return std::uint32_t{0xFFFFFFFFu};  // too large to exist: reported as not found
  }
  return value;
}

std::string deviceLabel(const DeviceInfo& d) {
  return "platform " + std::to_string(d.platform_index) + " device " +
         std::to_string(d.device_index) + ": " + d.device_name + " (" + d.platform_name + ")";
}

std::string availableList(const std::vector<DeviceInfo>& devices) {
  std::string text = "; available: ";
  for (std::size_t i = 0; i < devices.size(); ++i) {
    text += (i == 0 ? "" : ", ") + deviceLabel(devices[i]);
  }
  return text;
}

bool matchesPlatform(const DeviceInfo& d, const std::string& selector) {
  if (selector.empty()) {
    return true;
  }
  if (const auto index = parseIndex(selector)) {
    return d.platform_index == *index;
  }
  return containsIgnoringCase(d.platform_name, selector);
}

std::string formatBytes(std::uint64_t bytes) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.1f MiB (%llu bytes)",
                static_cast<double>(bytes) / (1024.0 * 1024.0),
                static_cast<unsigned long long>(bytes));
  return buffer;
}

/// The OpenCL 1.2 status codes (and the ICD loader's CL_PLATFORM_NOT_FOUND_KHR) by name: a table,
/// so that adding one is one line. RAYMAP_CL_NAME spells each name once.
#define RAYMAP_CL_NAME(code) \
  ClStatusName { code, #code }
struct ClStatusName {
  cl_int code;
  const char* name;
};
constexpr ClStatusName kClStatusNames[] = {
    RAYMAP_CL_NAME(CL_SUCCESS),
    RAYMAP_CL_NAME(CL_DEVICE_NOT_FOUND),
    RAYMAP_CL_NAME(CL_DEVICE_NOT_AVAILABLE),
    RAYMAP_CL_NAME(CL_COMPILER_NOT_AVAILABLE),
    RAYMAP_CL_NAME(CL_MEM_OBJECT_ALLOCATION_FAILURE),
    RAYMAP_CL_NAME(CL_OUT_OF_RESOURCES),
    RAYMAP_CL_NAME(CL_OUT_OF_HOST_MEMORY),
    RAYMAP_CL_NAME(CL_PROFILING_INFO_NOT_AVAILABLE),
    RAYMAP_CL_NAME(CL_MEM_COPY_OVERLAP),
    RAYMAP_CL_NAME(CL_IMAGE_FORMAT_MISMATCH),
    RAYMAP_CL_NAME(CL_IMAGE_FORMAT_NOT_SUPPORTED),
    RAYMAP_CL_NAME(CL_BUILD_PROGRAM_FAILURE),
    RAYMAP_CL_NAME(CL_MAP_FAILURE),
    RAYMAP_CL_NAME(CL_MISALIGNED_SUB_BUFFER_OFFSET),
    RAYMAP_CL_NAME(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST),
    RAYMAP_CL_NAME(CL_COMPILE_PROGRAM_FAILURE),
    RAYMAP_CL_NAME(CL_LINKER_NOT_AVAILABLE),
    RAYMAP_CL_NAME(CL_LINK_PROGRAM_FAILURE),
    RAYMAP_CL_NAME(CL_DEVICE_PARTITION_FAILED),
    RAYMAP_CL_NAME(CL_KERNEL_ARG_INFO_NOT_AVAILABLE),
    RAYMAP_CL_NAME(CL_INVALID_VALUE),
    RAYMAP_CL_NAME(CL_INVALID_DEVICE_TYPE),
    RAYMAP_CL_NAME(CL_INVALID_PLATFORM),
    RAYMAP_CL_NAME(CL_INVALID_DEVICE),
    RAYMAP_CL_NAME(CL_INVALID_CONTEXT),
    RAYMAP_CL_NAME(CL_INVALID_QUEUE_PROPERTIES),
    RAYMAP_CL_NAME(CL_INVALID_COMMAND_QUEUE),
    RAYMAP_CL_NAME(CL_INVALID_HOST_PTR),
    RAYMAP_CL_NAME(CL_INVALID_MEM_OBJECT),
    RAYMAP_CL_NAME(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR),
    RAYMAP_CL_NAME(CL_INVALID_IMAGE_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_SAMPLER),
    RAYMAP_CL_NAME(CL_INVALID_BINARY),
    RAYMAP_CL_NAME(CL_INVALID_BUILD_OPTIONS),
    RAYMAP_CL_NAME(CL_INVALID_PROGRAM),
    RAYMAP_CL_NAME(CL_INVALID_PROGRAM_EXECUTABLE),
    RAYMAP_CL_NAME(CL_INVALID_KERNEL_NAME),
    RAYMAP_CL_NAME(CL_INVALID_KERNEL_DEFINITION),
    RAYMAP_CL_NAME(CL_INVALID_KERNEL),
    RAYMAP_CL_NAME(CL_INVALID_ARG_INDEX),
    RAYMAP_CL_NAME(CL_INVALID_ARG_VALUE),
    RAYMAP_CL_NAME(CL_INVALID_ARG_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_KERNEL_ARGS),
    RAYMAP_CL_NAME(CL_INVALID_WORK_DIMENSION),
    RAYMAP_CL_NAME(CL_INVALID_WORK_GROUP_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_WORK_ITEM_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_GLOBAL_OFFSET),
    RAYMAP_CL_NAME(CL_INVALID_EVENT_WAIT_LIST),
    RAYMAP_CL_NAME(CL_INVALID_EVENT),
    RAYMAP_CL_NAME(CL_INVALID_OPERATION),
    RAYMAP_CL_NAME(CL_INVALID_GL_OBJECT),
    RAYMAP_CL_NAME(CL_INVALID_BUFFER_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_MIP_LEVEL),
    RAYMAP_CL_NAME(CL_INVALID_GLOBAL_WORK_SIZE),
    RAYMAP_CL_NAME(CL_INVALID_PROPERTY),
    RAYMAP_CL_NAME(CL_INVALID_IMAGE_DESCRIPTOR),
    RAYMAP_CL_NAME(CL_INVALID_COMPILER_OPTIONS),
    RAYMAP_CL_NAME(CL_INVALID_LINKER_OPTIONS),
    RAYMAP_CL_NAME(CL_INVALID_DEVICE_PARTITION_COUNT),
    RAYMAP_CL_NAME(CL_PLATFORM_NOT_FOUND_KHR),
};
#undef RAYMAP_CL_NAME

}  // namespace

const char* errorName(cl_int status) noexcept {
  for (const ClStatusName& entry : kClStatusNames) {
    if (entry.code == status) {
      return entry.name;
    }
  }
  // Unknown codes (vendor extensions) still need a printable name; one buffer per thread keeps
  // the pointer valid until that thread's next unknown code.
  thread_local char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "CL_ERROR(%d)", static_cast<int>(status));
  return buffer;
}

Result<std::vector<DeviceInfo>> listDevices() {
  cl_uint platform_count = 0;
  const cl_int status = clGetPlatformIDs(0, nullptr, &platform_count);
  // The ICD loader answers CL_PLATFORM_NOT_FOUND_KHR when no vendor driver is registered.
  if (status == CL_PLATFORM_NOT_FOUND_KHR || (status == CL_SUCCESS && platform_count == 0)) {
    return fail(ErrorCode::kUnsupported, kNoPlatformMessage);
  }
  if (status != CL_SUCCESS) {
    return fail(ErrorCode::kUnsupported,
                std::string("cannot list OpenCL platforms: ") + errorName(status));
  }
  std::vector<cl_platform_id> platforms(platform_count);
  if (const cl_int s = clGetPlatformIDs(platform_count, platforms.data(), nullptr);
      s != CL_SUCCESS) {
    return fail(ErrorCode::kUnsupported,
                std::string("cannot list OpenCL platforms: ") + errorName(s));
  }
  std::vector<DeviceInfo> devices;
  for (cl_uint p = 0; p < platform_count; ++p) {
    cl_uint device_count = 0;
    // A platform without devices (a GPU driver with its card absent) answers
    // CL_DEVICE_NOT_FOUND; it is skipped rather than hiding the other platforms.
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &device_count) != CL_SUCCESS ||
        device_count == 0) {
      continue;
    }
    std::vector<cl_device_id> ids(device_count);
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, device_count, ids.data(), nullptr) !=
        CL_SUCCESS) {
      continue;
    }
    for (cl_uint d = 0; d < device_count; ++d) {
      devices.push_back(describe(p, d, platforms[p], ids[d]));
    }
  }
  if (devices.empty()) {
    return fail(ErrorCode::kUnsupported,
                std::to_string(platform_count) +
                    " OpenCL platform(s) found but no device: check that the driver sees the "
                    "hardware, or pick backend.name: cpu");
  }
  return devices;
}

Result<DeviceInfo> findDevice(const DeviceSelector& selector) {
  auto devices = listDevices();
  if (!devices) {
    return Unexpected(devices.error());
  }
  return selectDevice(*devices, selector);
}

Result<DeviceInfo> selectDevice(const std::vector<DeviceInfo>& devices,
                                const DeviceSelector& selector) {
  if (devices.empty()) {
    return fail(ErrorCode::kUnsupported, "no OpenCL device to select from");
  }
  std::vector<const DeviceInfo*> candidates;
  for (const DeviceInfo& d : devices) {
    if (matchesPlatform(d, selector.platform)) {
      candidates.push_back(&d);
    }
  }
  if (candidates.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                "no OpenCL platform matches '" + selector.platform + "'" + availableList(devices));
  }
  if (selector.device.empty()) {
    const auto gpu = std::find_if(candidates.begin(), candidates.end(),
                                  [](const DeviceInfo* d) { return d->type == "GPU"; });
    return gpu != candidates.end() ? **gpu : *candidates.front();
  }
  const std::string where =
      selector.platform.empty() ? "" : " on platform '" + selector.platform + "'";
  if (const auto index = parseIndex(selector.device)) {
    // Device indices restart on each platform, so without a platform an index that exists on
    // several of them is ambiguous; guessing would silently run on the wrong hardware.
    std::vector<const DeviceInfo*> hits;
    for (const DeviceInfo* d : candidates) {
      if (d->device_index == *index) {
        hits.push_back(d);
      }
    }
    if (hits.empty()) {
      return fail(ErrorCode::kInvalidArgument, "no OpenCL device with index " + selector.device +
                                                   where + availableList(devices));
    }
    if (hits.size() > 1) {
      return fail(ErrorCode::kInvalidArgument,
                  "OpenCL device index " + selector.device +
                      " exists on several platforms: name the platform too" +
                      availableList(devices));
    }
    return *hits.front();
  }
  for (const DeviceInfo* d : candidates) {
    if (containsIgnoringCase(d->device_name, selector.device)) {
      return *d;
    }
  }
  return fail(ErrorCode::kInvalidArgument, "no OpenCL device matches '" + selector.device + "'" +
                                               where + availableList(devices));
}

Result<DeviceContext> createContext(const DeviceInfo& device) {
  const cl_context_properties properties[] = {
      CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(device.platform), 0};
  cl_int status = CL_SUCCESS;
  ContextHandle context(clCreateContext(properties, 1, &device.device, nullptr, nullptr, &status));
  if (status != CL_SUCCESS || !context) {
    return fail(ErrorCode::kUnsupported, "cannot create an OpenCL context on " +
                                             device.device_name + ": " + errorName(status));
  }
  // In order and without profiling: the backend orders work by enqueue order and times it on
  // the host.
  QueueHandle queue(clCreateCommandQueue(context.get(), device.device, 0, &status));
  if (status != CL_SUCCESS || !queue) {
    return fail(ErrorCode::kUnsupported, "cannot create an OpenCL command queue on " +
                                             device.device_name + ": " + errorName(status));
  }
  DeviceContext ctx;
  ctx.info = device;
  ctx.context = std::move(context);
  ctx.queue = std::move(queue);
  return ctx;
}

namespace {

Result<BufferHandle> makeBuffer(const DeviceContext& ctx, cl_mem_flags flags, void* host,
                                std::size_t bytes, std::string_view what) {
  const std::string name(what);
  if (bytes == 0) {
    // OpenCL has no empty buffers (CL_INVALID_BUFFER_SIZE); say so in our own words.
    return fail(ErrorCode::kInvalidArgument, "cannot allocate " + name + ": size is 0 bytes");
  }
  if (bytes > ctx.info.max_alloc_bytes) {
    return fail(ErrorCode::kCapacity, "cannot allocate " + name + ": " + formatBytes(bytes) +
                                          " exceeds the maximum single allocation of " +
                                          formatBytes(ctx.info.max_alloc_bytes) + " on " +
                                          ctx.info.device_name);
  }
  cl_int status = CL_SUCCESS;
  BufferHandle buffer(clCreateBuffer(ctx.context.get(), flags, bytes, host, &status));
  if (status != CL_SUCCESS || !buffer) {
    const bool out_of_memory =
        status == CL_MEM_OBJECT_ALLOCATION_FAILURE || status == CL_OUT_OF_RESOURCES;
    return fail(out_of_memory ? ErrorCode::kCapacity : ErrorCode::kUnsupported,
                "cannot allocate " + name + " (" + formatBytes(bytes) + ") on " +
                    ctx.info.device_name + ": " + errorName(status));
  }
  return buffer;
}

}  // namespace

Result<BufferHandle> createBuffer(const DeviceContext& ctx, std::size_t bytes,
                                  std::string_view what) {
  return makeBuffer(ctx, CL_MEM_READ_WRITE, nullptr, bytes, what);
}

Result<BufferHandle> createHostBuffer(const DeviceContext& ctx, void* host, std::size_t bytes,
                                      std::string_view what) {
  return makeBuffer(ctx, CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR, host, bytes, what);
}

Result<KernelHandle> createKernel(const ProgramHandle& program, const char* name) {
  const std::string label = name != nullptr ? name : "(null)";
  if (!program || name == nullptr) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot create OpenCL kernel '" + label + "': no program or no name");
  }
  cl_int status = CL_SUCCESS;
  KernelHandle kernel(clCreateKernel(program.get(), name, &status));
  if (status != CL_SUCCESS || !kernel) {
    return fail(
        status == CL_INVALID_KERNEL_NAME ? ErrorCode::kInvalidArgument : ErrorCode::kUnsupported,
        "cannot create OpenCL kernel '" + label + "': " + errorName(status));
  }
  return kernel;
}

Expected<void, Error> createKernels(
    const ProgramHandle& program,
    std::initializer_list<std::pair<KernelHandle*, const char*>> kernels) {
  for (const auto& [handle, name] : kernels) {
    auto kernel = createKernel(program, name);
    if (!kernel) {
      return Unexpected(kernel.error());
    }
    *handle = std::move(*kernel);
  }
  return {};
}

}  // namespace raymap::opencl
