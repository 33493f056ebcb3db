#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# raymapd on a busy machine: a second process keeps one core busy throughout, and raymap-load (a
# simulated Ouster OS-1-128, 128 x 1024 points per scan, PointCloud2 + odometry over loopback DDS,
# GridMap and diagnostics subscriber) drives raymapd at 1, 2, 5, 10 and 20 times the sensor's
# 10 Hz (20x is about as fast as raymap-load publishes on a 2-core machine: the "--rate max").
# Each rate runs under three policies of the same binary: "bounded" (the shipped defaults: the
# map lock given up every 5 ms, the adaptive publish lead, the latency bound while the integrator
# is saturated), "always" (the same with queues.shed_when: always) and "unbounded" (the behaviour
# before them: max_lock_hold_s 1, publish_lead_max_s = publish_lead_s, max_latency_s 0). A fourth,
# "unpaced" (not in the default list), is "bounded" with dds.repair_burst_kb: 0: Cyclone's own
# repairs, up to 1 MiB at once, as before issue 53.
# Prints one JSON object per run (raymap-load's output plus rate and policy, with the CPU seconds of
# each raymapd thread: thread_cpu_s) to stdout.
#   tools/bench/run-overload-benchmarks.sh [BUILD_DIR] [SECONDS]
# defaults: build/release, 20 (after a 3 s warm-up). RATES (scans/s, default "10 20 50 100 200") and
# POLICIES (default "bounded always unbounded") select runs. SUBSCRIBER_PRIORITY=50 makes raymap-load
# a real-time subscriber: its GridMap thread at SCHED_FIFO 50 and its Cyclone receive path at 50
# too (config/cyclonedds-realtime-receive.xml), as a planner that needs the maps on time runs.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/release}
duration=${2:-20}
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
source tools/bench/bench-lib.sh
work=$(mktemp -d)
colo=""
cleanup() {
  [ -z "$colo" ] || kill "$colo" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
# The co-load: one core kept busy for the whole run, as other software on a robot does.
(while :; do :; done) &
colo=$!
domain=80
for rate in ${RATES:-10 20 50 100 200}; do
  for policy in ${POLICIES:-bounded always unbounded}; do
    domain=$((domain + 1))
    extra=()
    if [ "$policy" = always ]; then
      extra=(-e "s/^  shed_when: [a-z]*/  shed_when: always/")
    elif [ "$policy" = unpaced ]; then
      extra=(-e "s/^  repair_burst_kb: [0-9]*/  repair_burst_kb: 0/")
    elif [ "$policy" = unbounded ]; then
      extra=(-e "s/^  max_lock_hold_s: [0-9.]*/  max_lock_hold_s: 1/"
        -e "s/^  publish_lead_max_s: [0-9.]*/  publish_lead_max_s: 0.015/"
        -e "s/^  max_latency_s: [0-9.]*/  max_latency_s: 0/")
    fi
    sed -e "s/^  domain: 0 /  domain: $domain /" -e "s/^  voxels_topic: .*/  voxels_topic: \"\"/" \
      "${extra[@]}" config/cpu.yaml > "$work/raymapd.yaml"
    printf '{"rate_hz": %s, "policy": "%s", "result": %s}\n' "$rate" "$policy" \
      "$(daemon_under_load "$build" "$work/raymapd.yaml" "$domain" "$rate" "$duration")"
  done
done
