// SPDX-License-Identifier: BSD-3-Clause
// The diagnostics' levels and reasons: stale pipelines, drops by cause, another publisher of the
// height map, and rates over a window that does not depend on the report rate.
#include <cstdint>
#include <cstring>
#include <string>

#include "diagnostic_msgs.h"
#include <gtest/gtest.h>

#include "src/dds/diagnostics_message.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/service/diagnostics_reporter.hpp"
#include "src/service/service.hpp"
#include "tests/support/nanoseconds.hpp"

namespace raymap::service {
namespace {

using test::kMs;
constexpr std::int64_t kStart = 1000 * kMs;

/// The pipeline around a reporter, with the clock in the test's hands.
struct Rig {
  /// `startup_grace_s` 0: the staleness rule from start (the tests of other rules).
  explicit Rig(double report_rate_hz = 1.0, double startup_grace_s = 0.0)
      : mailbox(5, 16), poses(16) {
    ReporterSettings s;
    s.name = "raymapd";
    s.hardware_id = "host/raymapd";
    s.backend = "cpu";
    s.report_rate_hz = report_rate_hz;
    s.stale_after_s = 1.0;
    s.startup_grace_s = startup_grace_s;
    s.grid_map_topic = "rt/height_map";
    s.sensor_frames = {"lidar_typo"};
    reporter = std::make_unique<DiagnosticsReporter>(stats, mailbox, poses, s, kStart);
  }
  /// One report at kStart + `ms`, scans integrated up to then when `scans_flowing`.
  void report(std::int64_t ms, std::uint32_t other_publishers = 0) {
    reporter->update(kStart + ms * kMs, realtime, other_publishers);
  }
  std::string message() const { return reporter->pipelineMessage(); }
  /// The value of `key` in the pipeline status of the last message.
  std::string value(const char* key) {
    const auto* array =
        static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(reporter->message(0));
    const diagnostic_msgs_msg_dds__DiagnosticStatus_& pipeline = array->status._buffer[0];
    for (std::uint32_t i = 0; i < pipeline.values._length; ++i) {
      if (std::strcmp(pipeline.values._buffer[i].key, key) == 0) {
        return pipeline.values._buffer[i].value;
      }
    }
    ADD_FAILURE() << "no key " << key;
    return "";
  }

  pipeline::PipelineStats stats;
  pipeline::ScanMailbox mailbox;
  pipeline::PoseQueue poses;
  RealtimeReport realtime;
  std::unique_ptr<DiagnosticsReporter> reporter;
};

TEST(DiagnosticsReporter, NoScanSinceStartIsAnErrorOnceTheStaleTimeHasPassed) {
  Rig rig;
  rig.report(500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
  rig.report(1500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError);
  EXPECT_NE(rig.message().find("no scan integrated since start"), std::string::npos)
      << rig.message();
  EXPECT_NE(rig.message().find("no point cloud arrives at all"), std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.reporter->heightmapLevel(), msgs::kDiagnosticError) << "maps are withheld";
}

TEST(DiagnosticsReporter, BeforeTheFirstCloudTheServiceWaitsWithAWarningUntilTheGraceEnds) {
  Rig rig(1.0, /*startup_grace_s=*/3.0);
  rig.report(1500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn) << rig.message();
  EXPECT_NE(rig.message().find("waiting for the first point cloud, 1.5 s since start"),
            std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.reporter->heightmapLevel(), msgs::kDiagnosticWarn);
  rig.report(3500);  // the grace is over: the staleness rule
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError) << rig.message();
  EXPECT_NE(rig.message().find("no point cloud arrives at all"), std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.reporter->heightmapLevel(), msgs::kDiagnosticError);
}

TEST(DiagnosticsReporter, CloudsThatComeWithinTheGraceButAreNotIntegratedAreAnErrorAtOnce) {
  Rig rig(1.0, /*startup_grace_s=*/10.0);
  rig.stats.clouds_received.add(15);
  rig.stats.last_cloud_received_ns.store(kStart + 1400 * kMs);
  rig.report(1500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError) << rig.message();
  EXPECT_NE(rig.message().find("no scan integrated since start"), std::string::npos)
      << rig.message();
}

/// Scans every 100 ms up to `ms`, each offering `integrated` + `short_rays` rays of which
/// `short_rays` are shorter than min range.
void flowRays(Rig& rig, int from_ms, int to_ms, std::uint64_t integrated,
              std::uint64_t short_rays) {
  for (int ms = from_ms; ms <= to_ms; ms += 100) {
    rig.stats.clouds_received.add();
    rig.stats.last_cloud_received_ns.store(kStart + ms * kMs);
    rig.stats.rays_integrated.add(integrated);
    rig.stats.rays_rejected.add(short_rays);
    rig.stats.rays_too_short.add(short_rays);
    if (integrated > 0) {
      rig.stats.scans_integrated.add();
      rig.stats.last_scan_integrated_ns.store(kStart + ms * kMs);
    } else {
      rig.stats.scans_empty.add();
    }
  }
}

TEST(DiagnosticsReporter, ScansWhoseEveryRayIsRejectedAreAnErrorNamingTheReasonAndCounts) {
  Rig rig;
  flowRays(rig, 0, 1000, 1000, 0);
  rig.report(1000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
  EXPECT_EQ(rig.value("rays_integrated_fraction"), "1.000");
  flowRays(rig, 1100, 2000, 0, 1000);
  rig.report(2000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError) << rig.message();
  EXPECT_NE(rig.message().find("integrating 0 of 10000 rays (0 %) in 1.0 s: 10000 shorter than "
                               "the sensor's min_range"),
            std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.value("rays_integrated_fraction"), "0.000");
  EXPECT_EQ(rig.value("rays_rejected_too_short"), "10000");
  EXPECT_EQ(rig.value("scans_empty"), "10");
}

TEST(DiagnosticsReporter, ASmallFractionOfRaysIntegratedIsAWarningAndEnoughIsOk) {
  Rig rig;
  rig.report(0);  // the window's first base
  flowRays(rig, 0, 1000, 300, 700);
  rig.report(1000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn) << rig.message();
  EXPECT_NE(rig.message().find("integrating 3300 of 11000 rays (30 %) in 1.0 s: 7700 shorter"),
            std::string::npos)
      << rig.message();
  flowRays(rig, 1100, 2000, 700, 300);
  rig.report(2000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
}

TEST(DiagnosticsReporter, DepthBlocksNearerThanMinRangeCountAsRaysNotIntegrated) {
  Rig rig;
  rig.report(0);  // the window's first base
  for (int ms = 0; ms <= 1000; ms += 100) {
    rig.stats.clouds_received.add();
    rig.stats.last_cloud_received_ns.store(kStart + ms * kMs);
    rig.stats.points_too_near.add(4800);
    rig.stats.scans_empty.add();
  }
  rig.report(1000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError) << rig.message();
  EXPECT_NE(rig.message().find("52800 depth blocks nearer than the sensor's min_range"),
            std::string::npos)
      << rig.message();
}

TEST(DiagnosticsReporter, InputThatStopsTurnsThePipelineToErrorAfterTheStaleTime) {
  Rig rig;
  for (int ms = 0; ms <= 2000; ms += 100) {
    rig.stats.clouds_received.add();
    rig.stats.last_cloud_received_ns.store(kStart + ms * kMs);
    rig.stats.scans_integrated.add();
    rig.stats.last_scan_integrated_ns.store(kStart + ms * kMs);
  }
  rig.report(2000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
  EXPECT_EQ(rig.message(), "ok");
  rig.report(3000);  // 1.0 s without a scan: not yet beyond
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
  rig.report(3500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError);
  EXPECT_NE(rig.message().find("no scan integrated for 1.5 s"), std::string::npos) << rig.message();
  EXPECT_NE(rig.message().find("no point cloud arrives any more"), std::string::npos)
      << rig.message();
}

TEST(DiagnosticsReporter, InputThatStoppedIsNotReportedAsArrivingWhileTheWindowStillHoldsIt) {
  // Reports at 1 Hz, input at 10 Hz until 1.5 s: at 2.6 s the window (from the report at 1.0 s)
  // still holds clouds, but none came after the last scan went in.
  Rig rig;
  rig.report(0);
  for (int ms = 100; ms <= 1500; ms += 100) {
    if (ms == 1100) {
      rig.report(1000);
    }
    rig.stats.clouds_received.add();
    rig.stats.last_cloud_received_ns.store(kStart + ms * kMs);
    rig.stats.scans_integrated.add();
    rig.stats.last_scan_integrated_ns.store(kStart + ms * kMs);
  }
  rig.report(2000);
  rig.report(2600);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError);
  EXPECT_NE(rig.message().find("no scan integrated for 1.1 s (no point cloud arrives any more)"),
            std::string::npos)
      << rig.message();
}

TEST(DiagnosticsReporter, CloudsThatArriveButAreNotIntegratedAreReportedArriving) {
  // The integrator stops at 1.0 s; clouds keep arriving at 10 Hz.
  Rig rig;
  for (int ms = 0; ms <= 2500; ms += 100) {
    if (ms % 1000 == 0) {
      rig.report(ms);
    }
    rig.stats.clouds_received.add();
    rig.stats.last_cloud_received_ns.store(kStart + ms * kMs);
    if (ms <= 1000) {
      rig.stats.scans_integrated.add();
      rig.stats.last_scan_integrated_ns.store(kStart + ms * kMs);
    }
  }
  rig.report(2600);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError);
  EXPECT_NE(rig.message().find("no scan integrated for 1.6 s"), std::string::npos) << rig.message();
  EXPECT_NE(rig.message().find("clouds/s arrive)"), std::string::npos) << rig.message();
}

TEST(DiagnosticsReporter, CloudsInTheWrongFrameAreAWarningNamingBothFramesThenAnError) {
  Rig rig;
  std::strcpy(rig.stats.wrong_frame, "lidar");
  rig.stats.wrong_frame_sensor = 0;
  rig.stats.wrong_frame_seen.store(true);
  rig.report(0);
  rig.stats.clouds_received.add(5);
  rig.stats.clouds_unknown_frame.add(5);
  rig.report(600);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn) << rig.message();
  EXPECT_NE(rig.message().find("5 clouds in frame 'lidar', not sensors[0].frame 'lidar_typo'"),
            std::string::npos)
      << rig.message();
  rig.stats.clouds_received.add(5);
  rig.stats.clouds_unknown_frame.add(5);
  rig.stats.last_cloud_received_ns.store(kStart + 1100 * kMs);
  rig.report(1200);  // and nothing has been integrated since start
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError) << rig.message();
  EXPECT_NE(rig.message().find("clouds/s arrive"), std::string::npos) << rig.message();
  EXPECT_NE(rig.message().find("frame 'lidar'"), std::string::npos) << rig.message();
  EXPECT_EQ(rig.value("clouds_wrong_frame"), "10");
}

TEST(DiagnosticsReporter, MalformedCloudsAreCountedAndNamedPerReason) {
  Rig rig;
  rig.stats.last_scan_integrated_ns.store(kStart);
  rig.report(0);
  rig.stats.clouds_malformed.add(3);
  rig.stats.clouds_rejected_by[static_cast<std::size_t>(msgs::CloudError::kTruncated)].add(2);
  rig.stats.clouds_rejected_by[static_cast<std::size_t>(msgs::CloudError::kMissingXyz)].add(1);
  rig.stats.last_scan_integrated_ns.store(kStart + 500 * kMs);
  rig.report(500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn);
  EXPECT_NE(rig.message().find("3 malformed clouds (truncated 2, missing_xyz 1)"),
            std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.value("clouds_malformed_truncated"), "2");
  EXPECT_EQ(rig.value("clouds_malformed_missing_xyz"), "1");
  EXPECT_EQ(rig.value("clouds_malformed_bad_field_type"), "0");
}

TEST(DiagnosticsReporter, BadTimesAndSheddingAreWarningsNamedAsSuch) {
  Rig rig;
  rig.stats.last_scan_integrated_ns.store(kStart);
  rig.report(0);
  rig.stats.points_bad_time.add(200);
  rig.stats.scans_shed.add(2);
  rig.stats.points_shed.add(4096);
  rig.stats.last_scan_integrated_ns.store(kStart + 500 * kMs);
  rig.report(500);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn);
  EXPECT_NE(rig.message().find("200 points with a per-point time out of range"), std::string::npos)
      << rig.message();
  EXPECT_NE(rig.message().find("2 scans shed"), std::string::npos) << rig.message();
  EXPECT_NE(rig.message().find("4096 points shed"), std::string::npos) << rig.message();
}

TEST(DiagnosticsReporter, WhatWasLostBeforeTheFirstReportIsThatReportsNews) {
  // raymapd stopped (or starved) 0.8 s after it started, before its first report, while its
  // socket overflowed: the first report is taken 1.5 s late. Its window starts at the start, so
  // the drops are named in it, not folded into a base no report is compared against.
  Rig rig;
  rig.stats.socket_drops.set(341);
  rig.stats.scans_no_pose.add(2);
  rig.stats.last_scan_integrated_ns.store(kStart + 800 * kMs);
  rig.report(1000);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticWarn) << rig.message();
  EXPECT_NE(rig.message().find("341 datagrams dropped by raymapd's full socket receive buffers"),
            std::string::npos)
      << rig.message();
  EXPECT_NE(rig.message().find("2 scans without a pose in time"), std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.value("socket_datagrams_dropped"), "341");
  rig.stats.last_scan_integrated_ns.store(kStart + 2000 * kMs);
  rig.report(2100);  // a window later: nothing new
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
}

TEST(DiagnosticsReporter, AnotherPublisherOfTheHeightMapIsAnError) {
  Rig rig;
  rig.stats.last_scan_integrated_ns.store(kStart + 400 * kMs);
  rig.report(500, 1);
  EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticError);
  EXPECT_NE(rig.message().find("1 other publisher of rt/height_map"), std::string::npos)
      << rig.message();
  EXPECT_EQ(rig.value("other_map_publishers"), "1");
}

TEST(DiagnosticsReporter, RatesAtTenReportsASecondAreTakenOverASecondNotOneInterval) {
  Rig rig(10.0);
  // Clouds arrive at 5 Hz: one every other 100 ms report. Rates per interval would alternate
  // between 0 and 10 Hz; over the one-second window they read 5.
  for (int k = 0; k <= 40; ++k) {
    if (k % 2 == 0) {
      rig.stats.clouds_received.add();
      rig.stats.scans_integrated.add();
      rig.stats.last_scan_integrated_ns.store(kStart + k * 100 * kMs);
    }
    rig.report(k * 100);
    if (k >= 12) {
      EXPECT_EQ(rig.value("cloud_rate_hz"), "5.00") << "report " << k;
      EXPECT_EQ(rig.reporter->pipelineLevel(), msgs::kDiagnosticOk) << rig.message();
    }
  }
}

TEST(DiagnosticsReporter, ADropStaysAWarningForTheWholeWindowAtHighReportRates) {
  Rig rig(10.0);
  for (int k = 0; k <= 30; ++k) {
    rig.stats.last_scan_integrated_ns.store(kStart + k * 100 * kMs);
    if (k == 10) {
      rig.stats.scans_no_pose.add();
    }
    rig.report(k * 100);
    const bool within = k >= 10 && k < 20;
    EXPECT_EQ(rig.reporter->pipelineLevel(), within ? msgs::kDiagnosticWarn : msgs::kDiagnosticOk)
        << "report " << k << ": " << rig.message();
  }
}

}  // namespace
}  // namespace raymap::service
