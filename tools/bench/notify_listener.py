#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""systemd's side of NOTIFY_SOCKET for the daemon benchmarks (tools/bench/bench-lib.sh).

Binds an AF_UNIX datagram socket at PATH (pass it to raymapd as NOTIFY_SOCKET), notes when
READY=1, each WATCHDOG=1 and STOPPING=1 arrive, and once STOPPING=1 has come (or on SIGTERM, or
after --timeout seconds) prints one JSON object on one line:

  ready_unix_ns        when READY=1 arrived (wall clock, to set against the script's start time)
  watchdog_pings       WATCHDOG=1 messages between READY=1 and STOPPING=1
  watchdog_gap_max_ms  the longest silence between them (from READY=1 to STOPPING=1, ends
                       included): what WatchdogSec must exceed; raymapd pings every publish cycle
  watchdog_gap_p99_ms  the 99th percentile of the gaps between consecutive pings

The tests only check that the watchdog is fed within WatchdogSec; this records how evenly.

usage: notify_listener.py PATH [--timeout SECONDS]
"""
import argparse
import json
import math
import os
import signal
import socket
import sys
import time


def percentile(values, q):
    if not values:
        return -1.0
    ordered = sorted(values)
    rank = max(1, math.ceil(q * len(ordered)))
    return ordered[rank - 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path")
    parser.add_argument("--timeout", type=float, default=3600.0)
    args = parser.parse_args()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    if os.path.exists(args.path):
        os.unlink(args.path)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(args.path)
    # The script waits for the socket to exist before it starts raymapd.
    sock.settimeout(0.2)

    ready_unix_ns = -1
    ready_mono = None
    stopping_mono = None
    pings = []  # monotonic seconds of each WATCHDOG=1 after READY=1
    end = time.monotonic() + args.timeout

    def take(data):
        nonlocal ready_unix_ns, ready_mono, stopping_mono
        now = time.monotonic()
        lines = data.decode("utf-8", "replace").split("\n")
        if "READY=1" in lines and ready_mono is None:
            ready_unix_ns = time.time_ns()
            ready_mono = now
        if "WATCHDOG=1" in lines and ready_mono is not None and stopping_mono is None:
            pings.append(now)
        if "STOPPING=1" in lines and stopping_mono is None:
            stopping_mono = now

    while stopping_mono is None and not stop and time.monotonic() < end:
        try:
            take(sock.recv(4096))
        except socket.timeout:
            continue
        except InterruptedError:
            continue
    # What arrived before the signal (STOPPING=1 may be waiting in the socket).
    sock.setblocking(False)
    while True:
        try:
            take(sock.recv(4096))
        except (BlockingIOError, InterruptedError):
            break
    sock.close()
    os.unlink(args.path)

    marks = []
    if ready_mono is not None:
        marks = [ready_mono] + pings + ([stopping_mono] if stopping_mono is not None else [])
    silences = [(b - a) * 1e3 for a, b in zip(marks, marks[1:])]
    between_pings = [(b - a) * 1e3 for a, b in zip(pings, pings[1:])]
    json.dump({"ready_unix_ns": ready_unix_ns,
               "watchdog_pings": len(pings),
               "watchdog_gap_max_ms": round(max(silences), 1) if silences else -1.0,
               "watchdog_gap_p99_ms": round(percentile(between_pings, 0.99), 1)},
              sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
