// SPDX-License-Identifier: BSD-3-Clause
// raymapd's service: everything sized and created from the configuration at start-up, then the
// threads (DDS ingest, integrator, periodic height-map publisher, diagnostics) until stop().
#pragma once

#include <memory>
#include <string>

#include "raymap/error.hpp"

#include "src/service/daemon_config.hpp"

namespace raymap::service {

/// @brief What start-up found out about real-time scheduling, for the log, the systemd status
/// and diagnostics.
struct RealtimeReport {
  bool memory_locked = false;
  int memory_lock_errno = 0;
  std::string summary;    ///< one line, e.g. "SCHED_FIFO ingest 40, integrator 30, publisher 60"
  bool degraded = false;  ///< something requested was refused: running with normal scheduling
};

/// @brief The running service.
///
/// Design (threads; arrows are the only ways data crosses between them):
///
///   DDS ──> ingest ──ScanMailbox (drop oldest)──> integrator ──map (PiMutex)──> publisher ──> DDS
///              └────PoseQueue (SPSC)────────────────┘   └──ArrivalQueue──────────┘
///   diagnostics: reads the atomic counters and histograms once per period, publishes
///   DiagnosticArray, updates the systemd status and logs changes.
///
/// Every buffer is allocated in create(); after the first height-map cycle no thread allocates
/// on raymap's side (Cyclone DDS allocates its own serialized samples inside dds_take/dds_write).
/// Thread-safety: create/start/stop/wait from one (the main) thread.
class Service {
 public:
  /// @brief Creates the map, backend, generator, DDS entities and buffers; starts nothing.
  /// Errors name the configuration key at fault where there is one.
  static Result<std::unique_ptr<Service>> create(const DaemonConfig& config);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  /// @brief Starts the threads, then tells systemd READY=1 with the status line.
  void start();
  /// @brief Asks every thread to finish and joins them (shutdown within a cycle or two).
  void stop();
  /// @brief Writes the map to map.save_on_exit (atomically) when configured.
  Expected<void, Error> saveMapIfConfigured();

  const RealtimeReport& realtime() const noexcept;
  /// @brief One line for logs: backend, device, topics, rate.
  std::string describe() const;

  struct Impl;

 private:
  explicit Service(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::service
