#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Samples a running raymapd once a second for a soak test (tools/soak.sh).

Each second it reads raymapd's resident set size from /proc, the GridMaps that arrived at an
independent subscriber (the JSON lines of `raymap echo /height_map --json`) and raymapd's latest
diagnostics (`raymap echo /diagnostics --json`), and appends a row to soak.csv. After --seconds it
creates the --sampled file (tools/soak.sh then stops the inputs), waits for --inputs-stopped,
reads raymapd's last reports, and writes summary.json (RSS spread after warm-up, publish rate at
the start and the end, drops, latency, and the checks: every cloud accounted for, no real-time
allocation after warm-up, RSS flat, reports true to what happened) and, when matplotlib is
installed, soak.png. Exit status 1 when a check fails. Standard library only, apart from the plot.
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
    "pose_publishers", "pipeline_level", "intruder", "realtime_allocations", "pose_time_resets",
    "pipeline_message",
]
# Every cloud raymapd takes ends in exactly one of these (docs/raymapd.md, Diagnostics).
OUTCOMES = (
    "scans_integrated", "scans_empty", "scans_dropped_no_pose", "scans_shed",
    "clouds_dropped_overflow", "clouds_malformed", "clouds_too_large", "clouds_wrong_frame",
    "clouds_rate_limited",
)
# RSS may move this much after warm-up and still count as flat (allocator noise, page cache).
RSS_FLAT_MIB = 2.0
RSS_FLAT_FRACTION = 0.02
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


def time_reset_mismatches(rows):
    """Rows without a second robot whose report does not say what happened to time: more than
    one reset in a second (a lap lasts longer), or a reset not named as the reason of a WARN."""
    bad = 0
    previous = None
    for r in rows:
        resets = r["pose_time_resets"]
        if previous is not None and resets == resets and previous == previous:
            step = resets - previous
            if r["intruder"] == 0 and step > 0 and (
                    step > 1 or r["pipeline_level"] < 1
                    or "went back" not in (r["pipeline_message"] or "")):
                bad += 1
        previous = resets
    return bad


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


def drain(args, diagnostics, latest):
    """After sampling: has the inputs stopped, then reads raymapd's reports until its counters
    stop moving (every queued scan taken), at most 30 s. Returns the last values."""
    if not args.sampled:
        return latest
    with open(args.sampled, "w", encoding="ascii"):
        pass
    deadline = time.monotonic() + 90.0  # a second robot's visit under way lasts up to 20 s
    while args.inputs_stopped and not os.path.exists(args.inputs_stopped):
        if time.monotonic() > deadline:
            print("soak: the inputs did not stop", file=sys.stderr)
            break
        time.sleep(0.5)
    still = 0
    previous = None
    deadline = time.monotonic() + 30.0
    while still < 3 and time.monotonic() < deadline:
        time.sleep(1.0)
        for report in diagnostics.read_new():
            for status in report.get("statuses", []):
                for key, value in status.get("values", {}).items():
                    latest[f"{status.get('name')}/{key}"] = value
        now = tuple(v if v == v else -1.0 for v in (
            number(latest, f"{PIPELINE}/{k}") for k in ("clouds_received",) + OUTCOMES))
        still = still + 1 if now == previous else 0
        previous = now
    return latest


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def intruder_clouds(intruder_log):
    """Clouds the second robot published, from its raymap-load reports (intruder-N.json)."""
    if not intruder_log:
        return 0
    folder = os.path.dirname(intruder_log)
    total = 0
    for name in sorted(os.listdir(folder)):
        if name.startswith("intruder-") and name.endswith(".json"):
            report = read_json(os.path.join(folder, name)) or {}
            total += int(report.get("scans_published_total", 0))
    return total


def checks(rows, final, summary, replay, intruder_log, bag):
    """Pass/fail of what the soak must show, each with what was measured."""
    out = {}
    received = number(final, f"{PIPELINE}/clouds_received")
    outcomes = {k: number(final, f"{PIPELINE}/{k}") for k in OUTCOMES}
    outcomes = {k: (0 if v != v else int(v)) for k, v in outcomes.items()}
    if received == received:
        accounted = sum(outcomes.values())
        out["every_cloud_received_has_an_outcome"] = {
            "passed": int(received) == accounted,
            "detail": f"{int(received)} received, {accounted} integrated, empty or counted as "
                      f"dropped ({', '.join(f'{k} {v}' for k, v in outcomes.items() if v)})"}
    missing = number(final, f"{PIPELINE}/clouds_missing")
    missing = 0 if missing != missing else int(missing)
    if replay is not None and received == received:
        published = int(replay.get("clouds", 0)) + intruder_clouds(intruder_log)
        out["every_cloud_published_was_received_or_reported_missing"] = {
            "passed": published - int(received) == missing,
            "detail": f"{published} published (replay {replay.get('clouds')}, second robot "
                      f"{published - int(replay.get('clouds', 0))}), {int(received)} received, "
                      f"{missing} reported missing (clouds_missing), socket datagrams dropped "
                      f"{int(number(final, f'{PIPELINE}/socket_datagrams_dropped') or 0)}"}
    allocations = [r["realtime_allocations"] for r in rows
                   if r["elapsed_s"] >= summary["warmup_s"] and r["realtime_allocations"] ==
                   r["realtime_allocations"]]
    last_allocations = number(final, f"{PIPELINE}/realtime_allocations")
    if allocations and last_allocations == last_allocations:
        made = int(last_allocations - allocations[0])
        out["no_realtime_allocation_after_warmup"] = {
            "passed": made == 0,
            "detail": f"{made} heap allocations in the real-time loops after warm-up "
                      f"({int(last_allocations)} in all)"}
    else:
        out["no_realtime_allocation_after_warmup"] = {
            "passed": None, "detail": "not counted: run build/tests/raymapd_counted"}
    if summary["rss_mib_first_steady"] is not None:
        growth = summary["rss_mib_last"] - summary["rss_mib_first_steady"]
        allowed = max(RSS_FLAT_MIB, RSS_FLAT_FRACTION * summary["rss_mib_first_steady"])
        out["rss_flat_after_warmup"] = {
            "passed": growth <= allowed,
            "detail": f"{growth:+.2f} MiB from {summary['rss_mib_first_steady']} MiB "
                      f"(allowed {allowed:.2f})"}
    out["reports_true_to_the_second_robot"] = {
        "passed": summary["health_mismatches"] == 0,
        "detail": f"{summary['health_mismatches']} mismatches in {summary['intruder_rows']} "
                  f"rows with it"}
    if bag:
        resets = number(final, f"{PIPELINE}/pose_time_resets")
        passes = int(replay.get("passes", 0)) if replay else 0
        mismatches = time_reset_mismatches(rows)
        out["time_going_back_reset_and_reported"] = {
            "passed": resets == resets and resets >= passes and mismatches == 0,
            "detail": f"{int(resets) if resets == resets else 'no'} pose-history resets for "
                      f"{passes} laps done (at least one each), {mismatches} reports not "
                      f"naming a reset"}
    return out


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
    parser.add_argument("--replay-stats", default="",
                        help="raymap replay's --stats-json, for the count of clouds published")
    parser.add_argument("--sampled", default="",
                        help="file to create when sampling is done (the inputs are then stopped)")
    parser.add_argument("--inputs-stopped", default="",
                        help="file that appears once every input has stopped")
    parser.add_argument("--bag", action="store_true",
                        help="the replay loops a bag: time goes back every lap")
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
                    latest[f"{status.get('name')}/message"] = status.get("message", "")
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
                "realtime_allocations": number(latest, f"{PIPELINE}/realtime_allocations"),
                "pose_time_resets": number(latest, f"{PIPELINE}/pose_time_resets"),
                "pipeline_message": latest.get(f"{PIPELINE}/message", ""),
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
    final = drain(args, diagnostics, latest)
    summary = summarise(rows, warmup)
    summary["checks"] = checks(rows, final, summary, read_json(args.replay_stats)
                               if args.replay_stats else None, args.intruder_log, args.bag)
    summary["label"] = args.label
    summary["plot"] = plot(rows, os.path.join(args.out, "soak.png"), args.label)
    with open(os.path.join(args.out, "summary.json"), "w", encoding="ascii") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    print(json.dumps(summary, indent=2))
    failed = [name for name, c in summary["checks"].items() if c["passed"] is False]
    for name in failed:
        print(f"soak: FAILED {name}: {summary['checks'][name]['detail']}", file=sys.stderr)
    return 0 if rows and not failed else 1


if __name__ == "__main__":
    sys.exit(main())
