#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The Python module's integration rate, the counterpart of raymap-mapper-bench (the same
recording read into memory first, then per repetition a fresh raymap.Mapper that integrates
every scan and flushes). Prints one JSON object like the C++ program's. By default the scans go
in as arrays (integrate_rays(), one conversion into the library's rays per scan); with
--in-place as the recording's own buffers (integrate_scan(), no conversion).

    PYTHONPATH=build/release/python tools/bench/python_mapper_bench.py RECORDING [--repeat N]
        [--semantics ray|scan] [--threads N] [--in-place]
"""

import argparse
import json
import statistics
import time

import raymap


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--semantics", choices=["ray", "scan"], default="ray")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--in-place", action="store_true",
                        help="integrate_scan() the recording's buffers instead of the arrays")
    args = parser.parse_args()
    scans = list(raymap.read_recording(args.recording))
    rays = sum(len(scan) for scan in scans)
    seconds = []
    for _ in range(max(1, args.repeat)):
        mapper = raymap.Mapper(semantics=args.semantics, threads=args.threads)
        start = time.perf_counter()
        for scan in scans:
            if args.in_place:
                mapper.integrate_scan(scan)
            else:
                mapper.integrate_rays(scan.origins, scan.ends, intensities=scan.intensities,
                                      no_return=scan.no_return)
        mapper.flush()
        seconds.append(time.perf_counter() - start)
    median = sorted(seconds)[len(seconds) // 2]
    print(json.dumps({"api": "python in place" if args.in_place else "python arrays", "recording": args.recording, "scans": len(scans),
                      "rays": rays, "semantics": args.semantics, "repeat": args.repeat,
                      "median_s": round(median, 6), "rays_per_s": round(rays / median),
                      "spread_s": round(statistics.pstdev(seconds), 6)}))


if __name__ == "__main__":
    main()
