// SPDX-License-Identifier: BSD-3-Clause
// `raymap devices`, OpenCL part: the platforms and devices and the default pick.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "tools/raymap/device_listing.hpp"

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

Json deviceJson(const opencl::DeviceInfo& d, bool is_default) {
  return {
      {"index", d.device_index},
      {"name", d.device_name},
      {"vendor", d.vendor},
      {"type", d.type},
      {"version", d.device_version},
      {"driver_version", d.driver_version},
      {"opencl_c_version", d.opencl_c_version},
      {"compute_units", d.compute_units},
      {"global_mem_bytes", d.global_mem_bytes},
      {"max_alloc_bytes", d.max_alloc_bytes},
      {"max_work_group_size", std::uint64_t{d.max_work_group_size}},
      {"int64_atomics", d.int64_atomics},
      {"unified_memory", d.unified_memory},
      {"default", is_default},
  };
}

Json listJson(const std::vector<opencl::DeviceInfo>& devices, const opencl::DeviceInfo* pick) {
  Json platforms = Json::array();
  std::size_t i = 0;
  while (i < devices.size()) {
    const opencl::DeviceInfo& first = devices[i];
    Json items = Json::array();
    for (; i < devices.size() && devices[i].platform_index == first.platform_index; ++i) {
      items.push_back(deviceJson(devices[i], isDefault(devices[i], pick)));
    }
    platforms.push_back(Json{
        {"index", first.platform_index},
        {"name", first.platform_name},
        {"version", first.platform_version},
        {"devices", items},
    });
  }
  Json j = {{"platforms", platforms}};
  if (pick != nullptr) {
    j["default"] = {
        {"platform", pick->platform_index},
        {"device", pick->device_index},
        {"name", pick->device_name},
    };
  }
  return j;
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
