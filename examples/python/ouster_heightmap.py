#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Maps a ray-cloud recording (the shared Ouster OS-1-128 data, or any ray-cloud PLY) with the
raymap Python module and draws the height map around the sensor's first position as a PNG with
Matplotlib (optional: without it, the layers are saved as NumPy arrays instead).

    PYTHONPATH=build/release/python examples/python/ouster_heightmap.py \\
        ../shared/data/ouster/ouster_os1_lb_n3_raycloud.ply.gz heightmap.png
"""

import argparse
import sys

import numpy as np

import raymap


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", help="a ray-cloud PLY (.ply or .ply.gz) or a rosbag2 bag")
    parser.add_argument("output", help="the PNG to write (.npz without Matplotlib)")
    parser.add_argument("--resolution", type=float, default=0.1)
    parser.add_argument("--size", type=float, default=30.0, help="height map side, metres")
    args = parser.parse_args()

    mapper = raymap.Mapper(resolution=args.resolution, semantics="ray")
    first_origin = None
    for scan in raymap.read_recording(args.recording):
        if first_origin is None and len(scan):
            first_origin = scan.origins[0].copy()
        mapper.integrate_rays(scan.origins, scan.ends, intensities=scan.intensities,
                              no_return=scan.no_return)
    mapper.flush()
    if first_origin is None:
        sys.exit(f"{args.recording}: no rays")
    counts = mapper.counts()
    print(f"{mapper.counters()['rays_integrated']:,} rays: {counts['voxels_occupied']:,} "
          f"occupied, {counts['voxels_free']:,} free voxels")

    # The ground around the sensor's first position: searched 3 m below and above the sensor.
    height = mapper.heightmap(centre=first_origin, size=args.size, floor_depth=3.0,
                              ceiling_height=3.0)
    surface = height.kind == 1
    print(f"height map {height.cells_x} x {height.cells_y} cells: {surface.sum():,} surface "
          f"cells, elevation {np.nanmin(height.elevation):.2f} to "
          f"{np.nanmax(height.elevation):.2f} m")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        np.savez(args.output, elevation=height.elevation, kind=height.kind,
                 clearance=height.clearance)
        print(f"no Matplotlib (apt-get install python3-matplotlib): wrote the layers to "
              f"{args.output}")
        return
    # grid_map's layout: [i, j] runs along -x and -y from the +x/+y corner. Transposed and
    # flipped, +x points right and +y up as on a map.
    image = np.flip(height.elevation.T, axis=(0, 1))
    half = args.size / 2
    cx, cy = height.centre
    fig, ax = plt.subplots(figsize=(7, 6))
    shown = ax.imshow(image, origin="lower", cmap="viridis",
                      extent=(cx - half, cx + half, cy - half, cy + half))
    fig.colorbar(shown, ax=ax, label="elevation (m)")
    ax.plot(*first_origin[:2], "r+", markersize=12, label="sensor")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"raymap height map, {args.resolution} m cells")
    ax.legend(loc="upper right")
    fig.savefig(args.output, dpi=100)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
