// SPDX-License-Identifier: BSD-3-Clause
// raymapd: the real-time height-map service. Reads its configuration, starts the service and
// runs until SIGTERM or SIGINT (systemd stop, Ctrl-C). The only code of the service that exits.
#include <cstdio>
#include <ctime>
#include <exception>
#include <string>

#include "raymap/version.hpp"
#include <CLI/CLI.hpp>

#include "platform/clock.hpp"
#include "platform/memory.hpp"
#include "platform/signals.hpp"
#include "src/service/daemon_config.hpp"
#include "src/service/daemon_security.hpp"
#include "src/service/log.hpp"
#include "src/service/service.hpp"
#include "src/service/startup_checks.hpp"

namespace {

constexpr int kExitRuntime = 1;
constexpr int kExitConfig = 2;

int checkConfig(const std::string& path) {
  auto config = raymap::service::loadDaemonConfig(path);
  if (!config) {
    std::fprintf(stderr, "%s\n", config.error().message.c_str());
    return kExitConfig;
  }
  const raymap::service::DaemonConfig& c = config.value();
  for (const std::string& warning : c.warnings) {
    std::printf("warning: %s: %s\n", path.c_str(), warning.c_str());
  }
  if (auto ok = raymap::service::checkStartup(c, raymap::platform::availableMemory()); !ok) {
    std::fprintf(stderr, "%s\n", ok.error().message.c_str());
    return kExitConfig;
  }
  // DDS Security: the enclave's files checked as at start (Enforce refuses here too).
  auto secure = raymap::service::resolveDaemonSecurity(c, std::time(nullptr));
  if (!secure) {
    std::fprintf(stderr, "%s\n", secure.error().message.c_str());
    return kExitConfig;
  }
  std::printf("%s: ok (backend %s, %zu sensor%s, height map %g m at %g Hz on %s, domain %u)\n",
              path.c_str(), c.backend.name.c_str(), c.sensors.size(),
              c.sensors.size() == 1 ? "" : "s", c.heightmap.size_m, c.heightmap.rate_hz,
              c.dds.grid_map_topic.c_str(), c.dds.domain);
  std::printf("%s\n", secure->summary.c_str());
  if (!secure->warning.empty()) {
    std::printf("warning: %s\n", secure->warning.c_str());
  }
  return 0;
}

int run(const std::string& path) {
  using raymap::service::LogLevel;
  using raymap::service::logLine;
  // Block the shutdown signals before any thread starts: every thread inherits the mask and
  // only this one receives them (sigtimedwait below).
  raymap::platform::ShutdownSignals signals = raymap::platform::ShutdownSignals::install();
  auto config = raymap::service::loadDaemonConfig(path);
  if (!config) {
    logLine(LogLevel::kError, "%s", config.error().message.c_str());
    return kExitConfig;
  }
  for (const std::string& warning : config->warnings) {
    logLine(LogLevel::kWarning, "%s: %s", path.c_str(), warning.c_str());
  }
  // Every pool is sized before any is allocated: a configuration that cannot fit is refused
  // here, naming its key, instead of failing halfway (or being killed) later.
  if (auto ok = raymap::service::checkStartup(config.value(), raymap::platform::availableMemory());
      !ok) {
    logLine(LogLevel::kError, "%s", ok.error().message.c_str());
    return kExitConfig;
  }
  auto service = raymap::service::Service::create(config.value());
  if (!service) {
    logLine(LogLevel::kError, "%s", service.error().message.c_str());
    return kExitConfig;
  }
  service.value()->start();
  int signal = 0;
  while (signal == 0) {
    signal = signals.waitNs(1000000000);
  }
  const std::int64_t stop_started = raymap::platform::monotonicNowNs();
  logLine(LogLevel::kInfo, "signal %d: stopping", signal);
  service.value()->stop();
  if (auto saved = service.value()->saveMapIfConfigured(); !saved) {
    logLine(LogLevel::kError, "could not save the map: %s", saved.error().message.c_str());
    return kExitRuntime;
  }
  logLine(LogLevel::kInfo, "stopped in %.0f ms",
          static_cast<double>(raymap::platform::monotonicNowNs() - stop_started) / 1e6);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"raymapd: lidar point clouds in, robot-centric height maps out, over DDS"};
  std::string config_path;
  std::string check_path;
  app.add_option("--config", config_path, "configuration file (YAML), e.g. config/cpu.yaml");
  app.add_option("--check-config", check_path,
                 "validate a configuration file, print a summary and exit (0 = valid)");
  app.set_version_flag("--version", std::string("raymapd ") + RAYMAP_VERSION_STRING);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!check_path.empty()) {
      return checkConfig(check_path);
    }
    if (config_path.empty()) {
      std::fprintf(stderr, "raymapd: --config FILE is required (see --help)\n");
      return kExitConfig;
    }
    return run(config_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "raymapd: error: %s\n", e.what());
    return kExitRuntime;
  }
}
