// SPDX-License-Identifier: BSD-3-Clause
// buildProgram: a cached device binary when one loads, else the source, whose binary is then saved.
#include "src/device/opencl/program_cache.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <system_error>
#include <utility>
#include <vector>

#include "src/io/atomic_file.hpp"

namespace raymap::opencl {
namespace {

// Bumped when the layout of a cache file or the key changes, so old files are simply not found.
constexpr std::string_view kCacheFormat = "raymap-clbin-1";

// FNV-1a, 64-bit: not cryptographic, only a name. Each field is followed by its length so that
// moving text from one field to the next changes the key.
class KeyHash {
 public:
  void add(std::string_view field) {
    for (const char c : field) {
      mix(static_cast<unsigned char>(c));
    }
    std::uint64_t length = field.size();
    for (int i = 0; i < 8; ++i) {
      mix(static_cast<unsigned char>(length & 0xFFu));
      length >>= 8;
    }
  }
  std::string hex() const {
    char buffer[17];
    std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(state_));
    return buffer;
  }

 private:
  void mix(unsigned char byte) {
    state_ ^= byte;
    state_ *= 0x100000001b3ull;
  }
  std::uint64_t state_ = 0xcbf29ce484222325ull;
};

std::string cacheKey(const DeviceInfo& d, std::string_view source, const std::string& options) {
  KeyHash h;
  h.add(kCacheFormat);
  h.add(source);
  h.add(options);
  h.add(d.platform_name);
  h.add(d.platform_version);
  h.add(d.device_name);
  h.add(d.driver_version);
  return h.hex();
}

std::string envDir(const char* name, const char* suffix) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') {
    return {};
  }
  return (std::filesystem::path(value) / suffix).string();
}

// The header's order: explicit directory, $RAYMAP_CACHE_DIR, $XDG_CACHE_HOME, $HOME/.cache.
std::string cacheDirectory(const ProgramCacheOptions& cache) {
  if (!cache.directory.empty()) {
    return cache.directory;
  }
  for (const std::string& dir :
       {envDir("RAYMAP_CACHE_DIR", "opencl"), envDir("XDG_CACHE_HOME", "raymap/opencl"),
        envDir("HOME", ".cache/raymap/opencl")}) {
    if (!dir.empty()) {
      return dir;
    }
  }
  return {};
}

std::string buildLog(cl_program program, cl_device_id device) {
  std::size_t size = 0;
  if (clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size) !=
          CL_SUCCESS ||
      size == 0) {
    return {};
  }
  std::string log(size, '\0');
  if (clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr) !=
      CL_SUCCESS) {
    return {};
  }
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n' || log.back() == ' ')) {
    log.pop_back();
  }
  return log;
}

std::vector<unsigned char> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return {};
  }
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in),
                                    std::istreambuf_iterator<char>());
}

// Any failure (unreadable, rejected by the driver, build error) yields an empty handle and a
// reason; the caller then builds from source.
ProgramHandle loadBinary(const DeviceContext& ctx, const std::string& path,
                         const std::string& options, std::string* reason) {
  const std::vector<unsigned char> binary = readFile(path);
  if (binary.empty()) {
    *reason = "empty or unreadable";
    return {};
  }
  const unsigned char* data = binary.data();
  const std::size_t size = binary.size();
  cl_int binary_status = CL_SUCCESS;
  cl_int status = CL_SUCCESS;
  ProgramHandle program(clCreateProgramWithBinary(ctx.context.get(), 1, &ctx.info.device, &size,
                                                  &data, &binary_status, &status));
  if (status != CL_SUCCESS || binary_status != CL_SUCCESS || !program) {
    *reason = errorName(status != CL_SUCCESS ? status : binary_status);
    return {};
  }
  status = clBuildProgram(program.get(), 1, &ctx.info.device, options.c_str(), nullptr, nullptr);
  if (status != CL_SUCCESS) {
    *reason = errorName(status);
    return {};
  }
  return program;
}

// Returns a warning, or "" when the binary was saved.
std::string saveBinary(const ProgramHandle& program, const std::string& path) {
  std::size_t size = 0;
  cl_int status =
      clGetProgramInfo(program.get(), CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, nullptr);
  if (status != CL_SUCCESS || size == 0) {
    return std::string("the driver returned no program binary (") + errorName(status) +
           "); not cached";
  }
  std::vector<unsigned char> binary(size);
  unsigned char* data = binary.data();
  status = clGetProgramInfo(program.get(), CL_PROGRAM_BINARIES, sizeof(data), &data, nullptr);
  if (status != CL_SUCCESS) {
    return std::string("cannot read the program binary (") + errorName(status) + "); not cached";
  }
  auto writer = io::AtomicFileWriter::open(path);
  if (!writer) {
    return writer.error().message + "; not cached";
  }
  if (auto ok = writer->write(std::as_bytes(std::span<const unsigned char>(binary))); !ok) {
    return ok.error().message + "; not cached";
  }
  if (auto ok = writer->commit(); !ok) {
    return ok.error().message + "; not cached";
  }
  return {};
}

void appendWarning(std::string* warnings, const std::string& text) {
  if (!text.empty()) {
    *warnings += (warnings->empty() ? "" : "; ") + text;
  }
}

}  // namespace

Result<BuiltProgram> buildProgram(const DeviceContext& ctx, std::string_view source,
                                  const std::string& options, const ProgramCacheOptions& cache) {
  BuiltProgram built;
  std::string path;
  if (cache.enabled) {
    const std::string dir = cacheDirectory(cache);
    std::error_code error;
    if (!dir.empty()) {
      std::filesystem::create_directories(dir, error);
    }
    if (dir.empty()) {
      built.warning = "no OpenCL program cache: set RAYMAP_CACHE_DIR, XDG_CACHE_HOME or HOME";
    } else if (error) {
      built.warning = "cannot create the OpenCL program cache '" + dir + "': " + error.message() +
                      "; building from source every time";
    } else {
      path =
          (std::filesystem::path(dir) / (cacheKey(ctx.info, source, options) + ".clbin")).string();
    }
  }
  std::error_code unreadable;  // treated like a missing file: build from source
  if (!path.empty() && std::filesystem::exists(path, unreadable)) {
    std::string reason;
    if (ProgramHandle program = loadBinary(ctx, path, options, &reason)) {
      built.program = std::move(program);
      built.from_cache = true;
      built.cache_path = path;
      return built;
    }
    appendWarning(&built.warning, "cached OpenCL binary '" + path + "' did not load (" + reason +
                                      "); rebuilt from source");
  }

  const char* text = source.data();
  const std::size_t length = source.size();
  cl_int status = CL_SUCCESS;
  ProgramHandle program(clCreateProgramWithSource(ctx.context.get(), 1, &text, &length, &status));
  if (status != CL_SUCCESS || !program) {
    return fail(ErrorCode::kUnsupported, "cannot create an OpenCL program on " +
                                             ctx.info.device_name + ": " + errorName(status));
  }
  status = clBuildProgram(program.get(), 1, &ctx.info.device, options.c_str(), nullptr, nullptr);
  if (status != CL_SUCCESS) {
    std::string log = buildLog(program.get(), ctx.info.device);
    return fail(ErrorCode::kUnsupported, "OpenCL kernel build failed on " + ctx.info.device_name +
                                             ": " + (log.empty() ? errorName(status) : log));
  }
  if (!path.empty()) {
    const std::string problem = saveBinary(program, path);
    appendWarning(&built.warning, problem);
    if (problem.empty()) {
      built.cache_path = path;
    }
  }
  built.program = std::move(program);
  return built;
}

}  // namespace raymap::opencl
