#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Samples a running raymapd once a second for a soak test (tools/soak.sh).

Each second it reads raymapd's resident set size from /proc, the GridMaps that arrived at an
independent subscriber (the JSON lines of `raymap echo /height_map --json`) and raymapd's latest
diagnostics (`raymap echo /diagnostics --json`), and appends a row to soak.csv. At the end it
writes summary.json (RSS spread after warm-up, publish rate at the start and the end, drops,
latency) and, when matplotlib is installed, soak.png. Standard library only, apart from the plot.
"""
import argparse
import csv
import json
import os
import statistics
import sys
import time

COLUMNS = [
    "elapsed_s", "rss_mib", "maps", "period_mean_ms", "period_max_ms", "latency_p50_ms",
    "latency_p99_ms", "clouds_received", "scans_integrated", "clouds_dropped", "rays_integrated",
    "pose_publishers", "pipeline_level", "intruder",
]
# A second robot's arrival or departure shows in the next report or two (discovery, then a report
# a second): rows this close to a change are not judged.
SETTLE_S = 3.0
PIPELINE = "raymapd: pipeline"
HEIGHT_MAP = "raymapd: height map"


class JsonLines:
    """Follows a file that another process appends JSON lines to."""

    def __init__(self, path):
        self.path = path
        self.offset = 0
        self.partial = ""

    def read_new(self):
        try:
            with open(self.path, encoding="utf-8") as f:
                f.seek(self.offset)
                text = f.read()
                self.offset = f.tell()
        except FileNotFoundError:
            return []
        text = self.partial + text
        lines = text.split("\n")
        self.partial = lines.pop()  # an unfinished last line waits for the next read
        out = []
        for line in lines:
            if line.strip():
                try:
                    out.append(json.loads(line))
                except json.JSONDecodeError:
                    pass
        return out


def rss_mib(pid):
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except FileNotFoundError:
        return None
    return None


def number(values, key):
    try:
        return float(values.get(key, "nan"))
    except ValueError:
        return float("nan")


def plot(rows, path, label):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("soak: matplotlib is not installed (apt-get install python3-matplotlib): no plot",
              file=sys.stderr)
        return False
    t = [r["elapsed_s"] / 60.0 for r in rows]
    fig, axes = plt.subplots(4, 1, figsize=(10, 11), sharex=True)
    axes[0].plot(t, [r["rss_mib"] for r in rows], color="tab:blue")
    axes[0].set_ylabel("raymapd RSS (MiB)")
    axes[1].plot(t, [r["period_mean_ms"] for r in rows], color="tab:green", label="mean")
    axes[1].plot(t, [r["period_max_ms"] for r in rows], color="tab:olive", alpha=0.6, label="max")
    axes[1].set_ylabel("GridMap period (ms)\nat the subscriber")
    axes[1].legend(loc="upper right")
    axes[2].plot(t, [r["latency_p50_ms"] for r in rows], color="tab:purple", label="p50")
    axes[2].plot(t, [r["latency_p99_ms"] for r in rows], color="tab:red", label="p99")
    axes[2].set_ylabel("scan -> GridMap\nlatency (ms)")
    axes[2].legend(loc="upper right")
    axes[3].plot(t, [r["clouds_dropped"] for r in rows], color="tab:red", label="dropped")
    axes[3].set_ylabel("clouds dropped\n(cumulative)")
    axes[3].set_xlabel("minutes")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"raymapd soak: {label}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return True


def intruder_intervals(path):
    """(join, leave) wall-clock intervals of the second robot (leave None while it is there)."""
    intervals = []
    if not path or not os.path.exists(path):
        return intervals
    with open(path, encoding="ascii") as f:
        for line in f:
            word, _, stamp = line.strip().partition(" ")
            if word == "join":
                intervals.append([float(stamp), None])
            elif word == "leave" and intervals:
                intervals[-1][1] = float(stamp)
    return intervals


def intruder_state(intervals, now):
    """1 while the second robot publishes, 0 when not, None within SETTLE_S of a change."""
    for join, leave in intervals:
        for change in (join, leave):
            if change is not None and abs(now - change) < SETTLE_S:
                return None
        if join <= now and (leave is None or now < leave):
            return 1
    return 0


def health_mismatches(rows):
    """Rows whose report does not say what happened: two pose sources present but not reported
    as two with an ERROR, or reported as two when there was one."""
    bad = 0
    for r in rows:
        if r["intruder"] == 1 and not (r["pose_publishers"] >= 2 and r["pipeline_level"] == 2):
            bad += 1
        elif r["intruder"] == 0 and r["pose_publishers"] >= 2:
            bad += 1
    return bad


def summarise(rows, warmup_s):
    steady = [r for r in rows if r["elapsed_s"] >= warmup_s and r["rss_mib"] is not None]
    rss = [r["rss_mib"] for r in steady]
    minutes = rows[-1]["elapsed_s"] / 60.0 if rows else 0.0
    window = max(1, min(len(rows) // 4, 300))  # first and last 5 min (a quarter of short runs)

    def rate(part):
        maps = sum(r["maps"] for r in part)
        return maps / len(part) if part else float("nan")

    steady_after = [r for r in rows if r["elapsed_s"] >= warmup_s]
    p99 = [r["latency_p99_ms"] for r in steady_after if r["latency_p99_ms"] == r["latency_p99_ms"]]
    last = rows[-1] if rows else {}
    return {
        "minutes": round(minutes, 2),
        "warmup_s": warmup_s,
        "rss_mib_min": round(min(rss), 2) if rss else None,
        "rss_mib_max": round(max(rss), 2) if rss else None,
        "rss_spread_percent": round(100.0 * (max(rss) - min(rss)) / statistics.mean(rss), 3)
        if rss else None,
        "rss_mib_first_steady": round(rss[0], 2) if rss else None,
        "rss_mib_last": round(rss[-1], 2) if rss else None,
        "publish_rate_hz_first": round(rate(rows[:window]), 3),
        "publish_rate_hz_last": round(rate(rows[-window:]), 3),
        "maps_received": sum(r["maps"] for r in rows),
        "period_max_ms": round(max((r["period_max_ms"] for r in steady_after
                                    if r["period_max_ms"] == r["period_max_ms"]), default=0.0), 2),
        "latency_p99_ms_median": round(statistics.median(p99), 1) if p99 else None,
        "latency_p99_ms_max": round(max(p99), 1) if p99 else None,
        "clouds_received": last.get("clouds_received"),
        "scans_integrated": last.get("scans_integrated"),
        "clouds_dropped": last.get("clouds_dropped"),
        "intruder_rows": sum(1 for r in rows if r["intruder"] == 1),
        "health_mismatches": health_mismatches(rows),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pid", type=int, required=True, help="raymapd's process id")
    parser.add_argument("--maps", required=True, help="JSON lines of raymap echo /height_map")
    parser.add_argument("--diagnostics", required=True, help="JSON lines of raymap echo /diagnostics")
    parser.add_argument("--seconds", type=int, required=True)
    parser.add_argument("--out", required=True, help="folder for soak.csv, soak.png, summary.json")
    parser.add_argument("--warmup", type=float, default=None,
                        help="seconds excluded from the RSS figures (default: 2 min, or 10 %% "
                             "of runs shorter than 20 min)")
    parser.add_argument("--label", default="", help="title of the plot")
    parser.add_argument("--intruder-log", default="",
                        help="join/leave times of a second robot (tools/soak.sh SOAK_INTRUDER=1)")
    args = parser.parse_args()
    warmup = args.warmup if args.warmup is not None else min(120.0, 0.1 * args.seconds)

    maps = JsonLines(args.maps)
    diagnostics = JsonLines(args.diagnostics)
    latest = {}  # "status/key" -> value of the newest diagnostics report
    rows = []
    previous_arrival = None
    start = time.monotonic()
    next_sample = start + 1.0
    with open(os.path.join(args.out, "soak.csv"), "w", newline="", encoding="ascii") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        while next_sample - start <= args.seconds:
            time.sleep(max(0.0, next_sample - time.monotonic()))
            next_sample += 1.0
            periods = []
            arrived = maps.read_new()
            for m in arrived:
                arrival = m.get("arrival_monotonic_ns")
                if previous_arrival is not None and arrival is not None:
                    periods.append((arrival - previous_arrival) * 1e-6)
                previous_arrival = arrival
            for report in diagnostics.read_new():
                for status in report.get("statuses", []):
                    latest[f"{status.get('name')}/level"] = status.get("level")
                    for key, value in status.get("values", {}).items():
                        latest[f"{status.get('name')}/{key}"] = value
            dropped = sum(number(latest, f"{PIPELINE}/{k}") for k in (
                "clouds_dropped_overflow", "scans_dropped_no_pose", "clouds_malformed",
                "clouds_too_large"))
            row = {
                "elapsed_s": round(time.monotonic() - start, 1),
                "rss_mib": rss_mib(args.pid),
                "maps": len(arrived),
                "period_mean_ms": round(statistics.mean(periods), 3) if periods else float("nan"),
                "period_max_ms": round(max(periods), 3) if periods else float("nan"),
                "latency_p50_ms": number(latest, f"{HEIGHT_MAP}/latency_p50_ms"),
                "latency_p99_ms": number(latest, f"{HEIGHT_MAP}/latency_p99_ms"),
                "clouds_received": number(latest, f"{PIPELINE}/clouds_received"),
                "scans_integrated": number(latest, f"{PIPELINE}/scans_integrated"),
                "clouds_dropped": dropped,
                "rays_integrated": number(latest, f"{PIPELINE}/rays_integrated"),
                "pose_publishers": number(latest, f"{PIPELINE}/pose_publishers"),
                "pipeline_level": number(latest, f"{PIPELINE}/level"),
                "intruder": intruder_state(intruder_intervals(args.intruder_log), time.time()),
            }
            if row["rss_mib"] is None:
                print("soak: raymapd is gone", file=sys.stderr)
                break
            rows.append(row)
            writer.writerow(row)
            f.flush()
            if len(rows) % 60 == 0:
                print(f"soak: {len(rows) // 60} min: RSS {row['rss_mib']:.1f} MiB, "
                      f"{row['maps']} maps/s, latency p99 {row['latency_p99_ms']:.0f} ms, "
                      f"{row['clouds_dropped']:.0f} dropped", flush=True)
    summary = summarise(rows, warmup)
    summary["label"] = args.label
    summary["plot"] = plot(rows, os.path.join(args.out, "soak.png"), args.label)
    with open(os.path.join(args.out, "summary.json"), "w", encoding="ascii") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    print(json.dumps(summary, indent=2))
    return 0 if rows else 1


if __name__ == "__main__":
    sys.exit(main())
