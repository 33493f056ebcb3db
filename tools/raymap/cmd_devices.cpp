// SPDX-License-Identifier: BSD-3-Clause
// `raymap devices`: the OpenCL and CUDA devices this machine offers, and the default picks.
#include <algorithm>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tools/raymap/commands.hpp"
#include "tools/raymap/device_listing.hpp"
#include "tools/raymap/json_output.hpp"

namespace raymap::cli {

void appendf(std::string* out, const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buffer, sizeof(buffer), format, args);
  va_end(args);
  if (n > 0) {
    out->append(buffer, std::min(static_cast<std::size_t>(n), sizeof(buffer) - 1));
  }
}

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

namespace {

struct DevicesFlags {
  bool json = false;
};

/// A section's JSON: its listing, or {"error": "..."}.
Json sectionJson(const DeviceListing& listing) {
  if (listing.available) {
    return listing.json;
  }
  return {{"error", listing.error}};
}

/// A section's text: its listing, or "  none: <why>".
std::string sectionText(const DeviceListing& listing) {
  return listing.available ? listing.text : "  none: " + listing.error + "\n";
}

/// Exit status: success when any API has a device; each API without one says why.
int runDevices(const DevicesFlags& f) {
  const DeviceListing opencl = listOpenClDevices();
  const DeviceListing cuda = listCudaDevices();
  if (f.json) {
    const Json j = {{"opencl", sectionJson(opencl)}, {"cuda", sectionJson(cuda)}};
    std::printf("%s\n", dumpJson(j).c_str());
  } else {
    std::printf("OpenCL\n%s", sectionText(opencl).c_str());
    std::printf("\nCUDA\n%s", sectionText(cuda).c_str());
  }
  if (!opencl.available && !cuda.available) {
    printError("devices", "no OpenCL or CUDA device: --backend cpu is what this machine can run");
  }
  return opencl.available || cuda.available ? kExitOk : kExitFailure;
}

}  // namespace

void addDevicesCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<DevicesFlags>();
  CLI::App* c = app.add_subcommand("devices", "List the OpenCL and CUDA devices");
  c->add_flag("--json", flags->json, "Print JSON");
  c->callback([flags, exit_code] { *exit_code = runDevices(*flags); });
}

}  // namespace raymap::cli
