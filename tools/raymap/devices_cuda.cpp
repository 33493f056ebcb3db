// SPDX-License-Identifier: BSD-3-Clause
// `raymap devices`, CUDA part: the CUDA devices and the one --backend cuda uses.
#include <cstdint>
#include <string>
#include <vector>

#include "tools/raymap/device_listing.hpp"

#if RAYMAP_HAVE_CUDA
#include "src/device/cuda/cuda_devices.hpp"
#include "tools/raymap/option_names.hpp"
#endif

namespace raymap::cli {
namespace {

#if RAYMAP_HAVE_CUDA

std::string capability(const cuda::DeviceInfo& d) {
  return std::to_string(d.compute_major) + "." + std::to_string(d.compute_minor);
}

Json deviceJson(const cuda::DeviceInfo& d) {
  return {
      {"index", d.index},
      {"name", d.name},
      {"compute_capability", capability(d)},
      {"multiprocessors", d.multiprocessors},
      {"global_mem_bytes", d.global_mem_bytes},
      {"integrated", d.integrated},
      {"can_map_host_memory", d.can_map_host_memory},
      {"pci_bus_id", d.pci_bus_id},
      {"default", d.index == 0},
  };
}

Json listJson(const std::vector<cuda::DeviceInfo>& devices) {
  Json items = Json::array();
  for (const cuda::DeviceInfo& d : devices) {
    items.push_back(deviceJson(d));
  }
  return {
      {"runtime_version", cuda::versionText(devices.front().runtime_version)},
      {"driver_version", cuda::versionText(devices.front().driver_version)},
      {"devices", items},
      {"default", 0},
  };
}

std::string listText(const std::vector<cuda::DeviceInfo>& devices) {
  std::string out;
  appendf(&out, "CUDA runtime %s, driver supports CUDA %s\n",
          cuda::versionText(devices.front().runtime_version).c_str(),
          cuda::versionText(devices.front().driver_version).c_str());
  for (const cuda::DeviceInfo& d : devices) {
    appendf(&out, "  device %d: %s%s\n", d.index, d.name.c_str(),
            d.index == 0 ? "  [default]" : "");
    appendf(&out, "    compute capability  %s\n", capability(d).c_str());
    appendf(&out, "    multiprocessors     %u\n", d.multiprocessors);
    appendf(&out, "    global memory       %s\n", sizeText(d.global_mem_bytes).c_str());
    appendf(&out, "    integrated          %s\n", d.integrated ? "yes (shares host memory)" : "no");
    appendf(&out, "    maps host memory    %s\n", d.can_map_host_memory ? "yes" : "no");
    if (!d.pci_bus_id.empty()) {
      appendf(&out, "    PCI bus             %s\n", d.pci_bus_id.c_str());
    }
  }
  appendf(&out, "default for --backend cuda: device 0 (%s)\n", devices.front().name.c_str());
  return out;
}

#endif

}  // namespace

DeviceListing listCudaDevices() {
  DeviceListing listing;
#if RAYMAP_HAVE_CUDA
  auto devices = cuda::listDevices();
  if (!devices) {
    listing.error = withCliFlags(devices.error().message);
    return listing;
  }
  listing.available = !devices->empty();
  if (listing.available) {
    listing.text = listText(*devices);
    listing.json = listJson(*devices);
  }
#else
  listing.error =
      "this build has no CUDA backend (it is built whenever CMake finds nvcc; install the CUDA "
      "toolkit, then configure again)";
#endif
  return listing;
}

}  // namespace raymap::cli
