// SPDX-License-Identifier: BSD-3-Clause
// `raymap devices`, OpenCL part: the platforms and devices and the default pick.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "tools/raymap/device_listing.hpp"
#include "tools/raymap/json_writer.hpp"

#if RAYMAP_HAVE_OPENCL
#include "src/device/opencl/cl_runtime.hpp"
#include "tools/raymap/option_names.hpp"
#endif

namespace raymap::cli {
namespace {

#if RAYMAP_HAVE_OPENCL

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

std::string listJson(const std::vector<opencl::DeviceInfo>& devices,
                     const opencl::DeviceInfo* pick) {
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
  return j.str();
}

std::string listText(const std::vector<opencl::DeviceInfo>& devices,
                     const opencl::DeviceInfo* pick) {
  std::string out;
  std::uint32_t platform = 0xFFFFFFFFu;
  for (const opencl::DeviceInfo& d : devices) {
    if (d.platform_index != platform) {
      platform = d.platform_index;
      appendf(&out, "platform %u: %s (%s)\n", d.platform_index, d.platform_name.c_str(),
              d.platform_version.c_str());
    }
    appendf(&out, "  device %u: %s%s\n", d.device_index, d.device_name.c_str(),
            isDefault(d, pick) ? "  [default]" : "");
    appendf(&out, "    type             %s (%s)\n", d.type.c_str(), d.vendor.c_str());
    appendf(&out, "    version          %s, driver %s\n", d.device_version.c_str(),
            d.driver_version.c_str());
    appendf(&out, "    OpenCL C         %s\n", d.opencl_c_version.c_str());
    appendf(&out, "    compute units    %u\n", d.compute_units);
    appendf(&out, "    global memory    %s\n", sizeText(d.global_mem_bytes).c_str());
    appendf(&out, "    max allocation   %s\n", sizeText(d.max_alloc_bytes).c_str());
    appendf(&out, "    work-group size  %zu\n", d.max_work_group_size);
    appendf(&out, "    int64 atomics    %s\n", d.int64_atomics ? "yes" : "no");
    appendf(&out, "    unified memory   %s\n", d.unified_memory ? "yes" : "no");
  }
  if (pick != nullptr) {
    appendf(&out, "default for --backend opencl: platform %u device %u (%s)\n",
            pick->platform_index, pick->device_index, pick->device_name.c_str());
  }
  return out;
}
#endif

}  // namespace

DeviceListing listOpenClDevices() {
  DeviceListing listing;
#if RAYMAP_HAVE_OPENCL
  auto devices = opencl::listDevices();
  if (!devices) {
    listing.error = withCliFlags(devices.error().message);
    return listing;
  }
  // The same rule as the backend's default selection, so what is shown is what will run.
  auto pick = opencl::selectDevice(*devices, opencl::DeviceSelector{});
  const opencl::DeviceInfo* chosen = pick ? &*pick : nullptr;
  listing.available = !devices->empty();
  listing.text = listText(*devices, chosen);
  listing.json = listJson(*devices, chosen);
#else
  listing.error =
      "this build has no OpenCL backend (install ocl-icd-opencl-dev and opencl-headers, then "
      "configure again)";
#endif
  return listing;
}

}  // namespace raymap::cli
