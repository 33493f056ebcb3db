// SPDX-License-Identifier: BSD-3-Clause
// `raymap devices`: the OpenCL platforms and devices this machine offers, and the default pick.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_writer.hpp"

#if RAYMAP_HAVE_OPENCL
#include "src/opencl/cl_runtime.hpp"
#endif

namespace raymap::cli {
namespace {

struct DevicesFlags {
  bool json = false;
};

#if RAYMAP_HAVE_OPENCL

std::string sizeText(std::uint64_t bytes) {
  char buffer[64];
  const double mib = static_cast<double>(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024.0) {
    std::snprintf(buffer, sizeof(buffer), "%.1f GiB", mib / 1024.0);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%.0f MiB", mib);
  }
  return buffer;
}

// JsonObject renders objects only; array elements are indented here so the nesting reads well.
std::string jsonArray(const std::vector<std::string>& items) {
  if (items.empty()) {
    return "[]";
  }
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += i == 0 ? "\n  " : ",\n  ";
    for (const char c : items[i]) {
      out += c;
      if (c == '\n') {
        out += "  ";
      }
    }
  }
  return out + "\n]";
}

bool isDefault(const opencl::DeviceInfo& d, const opencl::DeviceInfo* pick) {
  return pick != nullptr && pick->platform_index == d.platform_index &&
         pick->device_index == d.device_index;
}

std::string deviceJson(const opencl::DeviceInfo& d, bool is_default) {
  JsonObject j;
  j.add("index", d.device_index)
      .add("name", d.device_name)
      .add("vendor", d.vendor)
      .add("type", d.type)
      .add("version", d.device_version)
      .add("driver_version", d.driver_version)
      .add("opencl_c_version", d.opencl_c_version)
      .add("compute_units", d.compute_units)
      .add("global_mem_bytes", d.global_mem_bytes)
      .add("max_alloc_bytes", d.max_alloc_bytes)
      .add("max_work_group_size", std::uint64_t{d.max_work_group_size})
      .add("int64_atomics", d.int64_atomics)
      .add("unified_memory", d.unified_memory)
      .add("default", is_default);
  return j.str();
}

void printJson(const std::vector<opencl::DeviceInfo>& devices, const opencl::DeviceInfo* pick) {
  std::vector<std::string> platforms;
  std::size_t i = 0;
  while (i < devices.size()) {
    const opencl::DeviceInfo& first = devices[i];
    std::vector<std::string> items;
    for (; i < devices.size() && devices[i].platform_index == first.platform_index; ++i) {
      items.push_back(deviceJson(devices[i], isDefault(devices[i], pick)));
    }
    JsonObject p;
    p.add("index", first.platform_index)
        .add("name", first.platform_name)
        .add("version", first.platform_version)
        .raw("devices", jsonArray(items));
    platforms.push_back(p.str());
  }
  JsonObject j;
  j.raw("platforms", jsonArray(platforms));
  if (pick != nullptr) {
    JsonObject d;
    d.add("platform", pick->platform_index)
        .add("device", pick->device_index)
        .add("name", pick->device_name);
    j.raw("default", d.str());
  }
  std::printf("%s\n", j.str().c_str());
}

void printText(const std::vector<opencl::DeviceInfo>& devices, const opencl::DeviceInfo* pick) {
  std::uint32_t platform = 0xFFFFFFFFu;
  for (const opencl::DeviceInfo& d : devices) {
    if (d.platform_index != platform) {
      platform = d.platform_index;
      std::printf("platform %u: %s (%s)\n", d.platform_index, d.platform_name.c_str(),
                  d.platform_version.c_str());
    }
    std::printf("  device %u: %s%s\n", d.device_index, d.device_name.c_str(),
                isDefault(d, pick) ? "  [default]" : "");
    std::printf("    type             %s (%s)\n", d.type.c_str(), d.vendor.c_str());
    std::printf("    version          %s, driver %s\n", d.device_version.c_str(),
                d.driver_version.c_str());
    std::printf("    OpenCL C         %s\n", d.opencl_c_version.c_str());
    std::printf("    compute units    %u\n", d.compute_units);
    std::printf("    global memory    %s\n", sizeText(d.global_mem_bytes).c_str());
    std::printf("    max allocation   %s\n", sizeText(d.max_alloc_bytes).c_str());
    std::printf("    work-group size  %zu\n", d.max_work_group_size);
    std::printf("    int64 atomics    %s\n", d.int64_atomics ? "yes" : "no");
    std::printf("    unified memory   %s\n", d.unified_memory ? "yes" : "no");
  }
  if (pick != nullptr) {
    std::printf("default for --backend opencl: platform %u device %u (%s)\n", pick->platform_index,
                pick->device_index, pick->device_name.c_str());
  }
}

int runDevices(const DevicesFlags& f) {
  auto devices = opencl::listDevices();
  if (!devices) {
    printError("devices", devices.error().message);
    return kExitFailure;
  }
  // The same rule as the backend's default selection, so what is shown is what will run.
  auto pick = opencl::selectDevice(*devices, opencl::DeviceSelector{});
  const opencl::DeviceInfo* chosen = pick ? &*pick : nullptr;
  if (f.json) {
    printJson(*devices, chosen);
  } else {
    printText(*devices, chosen);
  }
  return kExitOk;
}

#else

int runDevices(const DevicesFlags&) {
  printError("devices",
             "this build has no OpenCL backend (install ocl-icd-opencl-dev and opencl-headers, "
             "then configure again)");
  return kExitFailure;
}

#endif

}  // namespace

void addDevicesCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<DevicesFlags>();
  CLI::App* c = app.add_subcommand("devices", "List the OpenCL platforms and devices");
  c->add_flag("--json", flags->json, "Print JSON");
  c->callback([flags, exit_code] { *exit_code = runDevices(*flags); });
}

}  // namespace raymap::cli
