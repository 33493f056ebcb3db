#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Renders the README's side-by-side picture of occupancy, NDT-OM and NDT-TM maps of the same data.

A side view (looking along +y, or +x with --along x; world frame, metres) of a slab of the maps: occupied voxels of the
occupancy map as voxel squares coloured by height, and the NDT ellipsoids that `raymap export
--mode ndt --ply` writes, NDT-OM coloured by height and NDT-TM by permeability (the exporter's
colours). Needs python3-matplotlib (and numpy).

  tools/render_ndt_pictures.py OCCUPIED.ply NDT_OM.ply NDT_TM.ply OUT.png \
      --along x --at 0.0 --half-width 1.0 --h -18 18 --z -3 6
"""

import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

PLY_TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
             "uchar": "u1", "uint8": "u1", "char": "i1", "int8": "i1", "ushort": "<u2",
             "short": "<i2", "uint": "<u4", "uint32": "<u4", "int": "<i4", "int32": "<i4"}
VERTICES_PER_ELLIPSOID = 42  # the exporter's 8 x 6 UV sphere (src/io/ndt_export.cpp)
FACES_PER_ELLIPSOID = 80


def read_ply(path):
    """Returns (vertex record array, first faces as an (n, 3) index array or None)."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            sys.exit(f"{path}: not a PLY file")
        elements = []
        while True:
            line = f.readline().decode("ascii").strip()
            if line == "end_header":
                break
            words = line.split()
            if words[0] == "format" and words[1] != "binary_little_endian":
                sys.exit(f"{path}: only binary little-endian PLY is read here")
            if words[0] == "element":
                elements.append([words[1], int(words[2]), []])
            elif words[0] == "property":
                elements[-1][2].append(words[1:])
        vertices = None
        faces = None
        for name, count, props in elements:
            if name == "vertex":
                dtype = np.dtype([(p[1], PLY_TYPES[p[0]]) for p in props])
                vertices = np.frombuffer(f.read(count * dtype.itemsize), dtype=dtype, count=count)
            elif name == "face" and count > 0:
                # Triangles only: a uchar 3 then three int32 indices (13 bytes each); the first
                # ellipsoid's faces are the template of every one.
                n = min(count, FACES_PER_ELLIPSOID)
                raw = np.frombuffer(f.read(n * 13), dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]))
                faces = raw["i"].copy()
                break
    return vertices, faces


def voxel_squares(ax, path, args, resolution):
    v, _ = read_ply(path)
    d, h = ("x", "y") if args.along == "x" else ("y", "x")
    keep = (np.abs(v[d] - args.at) < args.half_width) & (v[h] >= args.h[0]) & \
        (v[h] <= args.h[1]) & (v["z"] >= args.z[0]) & (v["z"] <= args.z[1])
    v = v[keep]
    order = np.argsort(-v[d])  # far first, near last
    v = v[order]
    x0 = np.floor(v[h] / resolution) * resolution
    z0 = np.floor(v["z"] / resolution) * resolution
    squares = np.stack([np.stack([x0, z0], 1), np.stack([x0 + resolution, z0], 1),
                        np.stack([x0 + resolution, z0 + resolution], 1),
                        np.stack([x0, z0 + resolution], 1)], 1)
    colours = plt.get_cmap("jet")(np.clip((v["z"] - args.z[0]) / (args.z[1] - args.z[0]), 0, 1))
    ax.add_collection(PolyCollection(squares, facecolors=colours, edgecolors="none"))
    return len(v)


def ellipsoids(ax, path, args):
    v, faces = read_ply(path)
    count = len(v) // VERTICES_PER_ELLIPSOID
    xyz = np.stack([v["x"], v["y"], v["z"]], 1).reshape(count, VERTICES_PER_ELLIPSOID, 3)
    rgb = np.stack([v["red"], v["green"], v["blue"]], 1).reshape(
        count, VERTICES_PER_ELLIPSOID, 3)[:, 0, :] / 255.0
    centre = xyz.mean(axis=1)
    d, h = (0, 1) if args.along == "x" else (1, 0)
    keep = (np.abs(centre[:, d] - args.at) < args.half_width) & (centre[:, h] >= args.h[0]) & \
        (centre[:, h] <= args.h[1]) & (centre[:, 2] >= args.z[0]) & (centre[:, 2] <= args.z[1])
    xyz, rgb, centre = xyz[keep], rgb[keep], centre[keep]
    order = np.argsort(-centre[:, d])  # far first, near last
    xyz, rgb = xyz[order], rgb[order]
    local = faces - faces.min()
    triangles = xyz[:, local, :][:, :, :, [h, 2]].reshape(-1, 3, 2)  # h, z of each triangle
    colours = np.repeat(rgb, len(local), axis=0)
    ax.add_collection(PolyCollection(triangles, facecolors=colours, edgecolors="none"))
    return len(xyz)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("occupied")
    parser.add_argument("ndt_om")
    parser.add_argument("ndt_tm")
    parser.add_argument("out")
    parser.add_argument("--along", choices=["x", "y"], default="y", help="viewing direction")
    parser.add_argument("--at", type=float, default=0.0, help="slab centre on that axis, metres")
    parser.add_argument("--half-width", type=float, default=1.0, help="slab half width, metres")
    parser.add_argument("--h", type=float, nargs=2, default=[-12.0, 12.0],
                        help="horizontal range of the picture, metres")
    parser.add_argument("--z", type=float, nargs=2, default=[-2.0, 4.0])
    parser.add_argument("--resolution", type=float, default=0.1)
    parser.add_argument("--title", default="")
    parser.add_argument("--columns", action="store_true", help="panels side by side")
    args = parser.parse_args()

    width = args.h[1] - args.h[0]
    height = args.z[1] - args.z[0]
    if args.columns:  # side by side, for tall crops
        fig, axes = plt.subplots(1, 3, figsize=(15, 5 * height / width + 1.0), dpi=110)
    else:
        fig, axes = plt.subplots(3, 1, figsize=(12, 3 * 12 * height / width + 1.2), dpi=110)
    panels = [
        ("occupancy: occupied voxels,\ncoloured by height", None),
        ("NDT-OM: a 2-sigma ellipsoid per\noccupied voxel, coloured by height", args.ndt_om),
        ("NDT-TM: the same ellipsoids, coloured\nby permeability (blue 0 - red 1)", args.ndt_tm),
    ]
    for ax, (title, path) in zip(axes, panels):
        n = voxel_squares(ax, args.occupied, args, args.resolution) if path is None else \
            ellipsoids(ax, path, args)
        ax.set_title(f"{title} ({n:,})", fontsize=10)
        ax.set_xlim(*args.h)
        ax.set_ylim(*args.z)
        ax.set_aspect("equal")
        ax.set_facecolor("white")
        ax.tick_params(labelsize=8)
        ax.set_ylabel("z (m)", fontsize=8)
    other = "y" if args.along == "x" else "x"
    for ax in axes if args.columns else axes[-1:]:
        ax.set_xlabel(f"{other} (m), looking along +{args.along}", fontsize=8)
    if args.title:
        fig.suptitle(args.title, fontsize=11)
    fig.tight_layout()
    fig.savefig(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
