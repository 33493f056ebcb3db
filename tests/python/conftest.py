# SPDX-License-Identifier: BSD-3-Clause
"""Fixtures of the Python module's tests (ctest -L python runs them with the build's package on
PYTHONPATH). The comparisons with the command line need RAYMAP_CLI (the build's `raymap`); the
bag tests need the Node.js harness (tools/setup-node.sh) and skip without it unless
RAYMAP_REQUIRE_NODE_HARNESS=1 (CI), where its absence fails them."""

import os
import pathlib
import shutil
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]


def run(args, **kwargs):
    """Runs a command; fails the test with its output when it fails."""
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        pytest.fail(f"{' '.join(map(str, args))} exited {result.returncode}:\n"
                    f"{result.stdout}\n{result.stderr}")
    return result


@pytest.fixture(scope="session")
def cli():
    """The `raymap` command of the same build."""
    path = os.environ.get("RAYMAP_CLI", "")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("RAYMAP_CLI is not set to a built raymap (a build without the command line)")
    return pathlib.Path(path)


@pytest.fixture(scope="session")
def room_rays(cli, tmp_path_factory):
    """A ray-cloud PLY of the room scene (25 lidar scans), made by `raymap simulate`."""
    path = tmp_path_factory.mktemp("room") / "room.ply"
    run([cli, "simulate", SOURCE_DIR / "config/scenes/room.yaml", "--rays", path, "--quiet"])
    return path


@pytest.fixture(scope="session")
def write_bag():
    """write_bag(spec_lines, out, *options): a rosbag2 bag written by Foxglove's libraries."""
    harness = SOURCE_DIR / "tests/rosbag/node"
    node = shutil.which("node")
    if node is None or not (harness / "node_modules").is_dir():
        if os.environ.get("RAYMAP_REQUIRE_NODE_HARNESS") == "1":
            pytest.fail("the Node.js bag harness is required here: run tools/setup-node.sh")
        pytest.skip("no Node.js bag harness (tools/setup-node.sh)")

    def write(spec_lines, out, *options):
        run([node, harness / "write_bag.mjs", "-", out, *options], input="\n".join(spec_lines))
        return out

    return write
