# SPDX-License-Identifier: BSD-3-Clause
"""The Python module against the command line of the same build: the same rays make the same
map as `raymap populate` (the saved region blocks and the exported voxels byte for byte, its
counts, every field of `raymap info` but the provenance the command line records), the height
map's arrays are `raymap heightmap`'s CSV, a bag's scans are what `raymap info` counts and
`raymap populate` maps, its clouds come in the sensor's frame with the poses populate maps them
with, and depth images map as populate maps their bag."""

import base64
import csv
import json
import math

import numpy as np
import pytest

import raymap
from conftest import run

# `raymap info` lines that describe how a file was made, not the map: the command line records
# its input and filters; the library records none.
PROVENANCE = ("map ", "source ", "created_by ", "rays_in ", "rays_integrated ", "min_range_m ",
              "max_range_m ", "segment_length_m ", "walk ")


def map_description(cli, path):
    lines = run([cli, "info", path]).stdout.splitlines()
    return [line for line in lines if not line.startswith(PROVENANCE)]


def exported_voxels(cli, path, out):
    run([cli, "export", path, "--ply", out, "--quiet"])
    data = out.read_bytes()
    assert len(data) > 1000, f"{out}: an export of {len(data)} bytes has no voxels"
    return data


def region_blocks(path):
    """The bytes of a saved map's region blocks (docs/map-format.md): every region's block
    header and compressed layers, from the end of the header to the region index. They do not
    depend on the header's info strings (the provenance), which only move them in the file."""
    data = path.read_bytes()
    assert data[:8] == b"RMAP\r\n\x1a\n" and data[-24:-20] == b"REND"
    header_body = int.from_bytes(data[12:16], "little")
    index_offset = int.from_bytes(data[-12:-4], "little")
    blocks = data[16 + header_body + 4:index_offset]
    assert blocks[:4] == b"RREG" and data[index_offset:index_offset + 4] == b"RIDX"
    return blocks


def map_with_python(recording, out, **options):
    mapper = raymap.Mapper(**options)
    scans = 0
    for scan in recording:
        mapper.integrate_rays(scan.origins, scan.ends, intensities=scan.intensities,
                              no_return=scan.no_return)
        scans += 1
    mapper.flush()
    mapper.save(str(out))
    return mapper, scans


def test_a_scan_integrated_in_place_is_the_scan_integrated_from_its_arrays(room_rays, tmp_path):
    by_arrays = raymap.Mapper()
    in_place = raymap.Mapper()
    for scan in raymap.read_recording(str(room_rays)):
        by_arrays.integrate_rays(scan.origins, scan.ends, intensities=scan.intensities,
                                 no_return=scan.no_return)
        in_place.integrate_scan(scan)
    by_arrays.flush()
    in_place.flush()
    by_arrays.save(str(tmp_path / "arrays.rmap"))
    in_place.save(str(tmp_path / "in_place.rmap"))
    assert (tmp_path / "arrays.rmap").read_bytes() == (tmp_path / "in_place.rmap").read_bytes()
    assert in_place.counters() == by_arrays.counters()
    with pytest.raises(raymap.InvalidArgument, match="read_recording"):
        in_place.integrate_scan("not a scan")
    with pytest.raises(raymap.InvalidArgument, match="read_recording"):
        in_place._mapper.integrate_scan(np.zeros(3))


@pytest.mark.parametrize("semantics", ["ray", "scan"])
def test_the_room_maps_as_raymap_populate_maps_it(cli, room_rays, tmp_path, semantics):
    stats = tmp_path / "stats.json"
    run([cli, "populate", room_rays, "-o", tmp_path / "cli.rmap", "--semantics", semantics,
         "--stats-json", stats, "--quiet"])
    mapper, scans = map_with_python(raymap.read_recording(str(room_rays)), tmp_path / "py.rmap",
                                    semantics=semantics)
    populate = json.loads(stats.read_text())
    assert scans == 25
    assert mapper.counts()["voxels_occupied"] == populate["voxels_occupied"]
    assert mapper.counts()["voxels_free"] == populate["voxels_free"]
    assert mapper.counters()["rays_integrated"] == populate["rays_integrated"]
    assert exported_voxels(cli, tmp_path / "py.rmap", tmp_path / "py.ply") == \
        exported_voxels(cli, tmp_path / "cli.rmap", tmp_path / "cli.ply")
    assert map_description(cli, tmp_path / "py.rmap") == map_description(cli, tmp_path / "cli.rmap")
    # The saved maps byte for byte, all but the provenance the command line records.
    assert region_blocks(tmp_path / "py.rmap") == region_blocks(tmp_path / "cli.rmap")


@pytest.mark.parametrize("mode, kind, options", [
    ("occupancy", "occupied", []),
    ("occupancy", "free", []),
    ("ndt-om", "ndt", ["--sigmas", "3"]),
    ("tsdf", "tsdf-mesh", []),
])
def test_an_export_is_raymap_exports_byte_for_byte(cli, room_rays, tmp_path, mode, kind, options):
    run([cli, "populate", room_rays, "-o", tmp_path / "room.rmap", "--mode", mode, "--quiet"])
    run([cli, "export", tmp_path / "room.rmap", "--mode", kind, *options, "--ply",
         tmp_path / "cli.ply", "--quiet"])
    keywords = {"ndt_sigmas": 3.0} if options else {}
    counts = raymap.Mapper.load(str(tmp_path / "room.rmap")).export_ply(
        str(tmp_path / "py.ply"), kind, **keywords)
    assert counts["items"] > 0
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()


def test_an_export_option_of_another_kind_is_refused_naming_it(tmp_path):
    mapper = raymap.Mapper()
    with pytest.raises(raymap.InvalidArgument, match="export.mode: 'cloud'"):
        mapper.export_ply(str(tmp_path / "a.ply"), "cloud")
    with pytest.raises(raymap.InvalidArgument, match="export.sigmas applies only to"):
        mapper.export_ply(str(tmp_path / "a.ply"), "occupied", ndt_sigmas=2.0)
    assert not (tmp_path / "a.ply").exists()


def test_the_height_map_arrays_are_raymap_heightmaps_csv(cli, room_rays, tmp_path):
    run([cli, "populate", room_rays, "-o", tmp_path / "room.rmap", "--quiet"])
    run([cli, "heightmap", tmp_path / "room.rmap", "--center", "0.3,-0.2,0", "--size", "6",
         "--min-clearance", "0.4", "--csv", tmp_path / "hm.csv", "--quiet"])
    height = raymap.Mapper.load(str(tmp_path / "room.rmap")).heightmap(
        centre=(0.3, -0.2, 0.0), size=6.0, min_clearance=0.4)
    kinds = {"unknown": 0, "surface": 1, "virtual": 2, "vacant": 3}
    with open(tmp_path / "hm.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == height.cells_x * height.cells_y
    surfaces = 0
    for k, row in enumerate(rows):
        i, j = k % height.cells_x, k // height.cells_x  # the CSV walks grid_map's index order
        x, y = height.cell_centre(i, j)
        assert (round(x, 4), round(y, 4)) == (float(row["x"]), float(row["y"]))
        for layer in ("elevation", "clearance"):
            ours = float(getattr(height, layer)[i, j])
            theirs = float(row[layer])
            assert (math.isnan(ours) and math.isnan(theirs)) or \
                f"{ours:.4f}" == row[layer] or ours == theirs, (k, layer, ours, row[layer])
        assert height.kind[i, j] == kinds[row["kind"].split("-")[0]], (k, row["kind"])
        surfaces += row["kind"] == "surface"
    assert surfaces > 1000


def cloud_message(stamp_ns, points, frame="base_link"):
    """A sensor_msgs/PointCloud2 (x y z float32, t uint32 ns after the stamp) for write_bag.mjs."""
    n = len(points)
    record = np.zeros(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("t", "<u4")])
    record["x"], record["y"], record["z"] = points[:, 0], points[:, 1], points[:, 2]
    record["t"] = (np.arange(n) * (100_000_000 // n)).astype(np.uint32)
    fields = [{"name": name, "offset": 4 * k, "datatype": 7 if k < 3 else 6, "count": 1}
              for k, name in enumerate("xyzt")]
    return {
        "header": {"stamp": {"sec": stamp_ns // 10**9, "nanosec": stamp_ns % 10**9},
                   "frame_id": frame},
        "height": 1, "width": n, "fields": fields, "is_bigendian": False, "point_step": 16,
        "row_step": 16 * n, "data": {"base64": base64.b64encode(record.tobytes()).decode()},
        "is_dense": True,
    }


def odometry_message(stamp_ns, x):
    return {
        "header": {"stamp": {"sec": stamp_ns // 10**9, "nanosec": stamp_ns % 10**9},
                   "frame_id": "odom"},
        "child_frame_id": "base_link",
        "pose": {"pose": {"position": {"x": x, "y": 0.0, "z": 0.0}}},
    }


def drive_spec(scans):
    """A robot driving along +x at 1 m/s in a 6 m ring of walls: odometry at 50 Hz, a 10 Hz
    sweep of 720 points in base_link (each at its own time)."""
    t0 = 1_700_000_000_000_000_000
    lines = [json.dumps({"op": "channel", "topic": "/odom", "type": "nav_msgs/msg/Odometry"}),
             json.dumps({"op": "channel", "topic": "/points",
                         "type": "sensor_msgs/msg/PointCloud2"})]
    angles = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    for k in range(5 * scans + 10):
        stamp = t0 + k * 20_000_000
        lines.append(json.dumps({"op": "message", "topic": "/odom", "log_time_ns": str(stamp),
                                 "msg": odometry_message(stamp, (stamp - t0) * 1e-9)}))
        if k % 5 == 0 and k // 5 < scans:
            ring = np.stack([6 * np.cos(angles), 6 * np.sin(angles), np.zeros(720)], axis=1)
            lines.append(json.dumps({"op": "message", "topic": "/points",
                                     "log_time_ns": str(stamp + 1000),
                                     "msg": cloud_message(stamp, ring)}))
    return lines


def test_a_bags_scans_are_what_raymap_info_counts_and_map_as_populate(cli, write_bag, tmp_path):
    bag = write_bag(drive_spec(8), tmp_path / "drive")
    info = json.loads(run([cli, "info", bag, "--json"]).stdout)
    clouds = next(t["messages"] for t in info["topics"] if t["name"] == "/points")
    run([cli, "populate", bag, "-o", tmp_path / "cli.rmap", "--quiet"])
    recording = raymap.read_recording(str(bag))
    mapper, scans = map_with_python(recording, tmp_path / "py.rmap")
    report = recording.report()
    assert recording.is_bag
    assert clouds == 8
    assert report["clouds"] == clouds
    assert report["messages"] == info["messages"]
    assert report["topics"] == ["/points"]
    assert report["pose_source"] == "odometry /odom"
    assert scans + report["scans_no_pose"] == clouds and scans >= 7
    assert mapper.counters()["rays_integrated"] > 0
    assert exported_voxels(cli, tmp_path / "py.rmap", tmp_path / "py.ply") == \
        exported_voxels(cli, tmp_path / "cli.rmap", tmp_path / "cli.ply")
    assert region_blocks(tmp_path / "py.rmap") == region_blocks(tmp_path / "cli.rmap")


def test_a_bags_clouds_come_in_the_sensor_frame_with_the_poses_populate_maps_them_with(
        cli, write_bag, tmp_path):
    bag = write_bag(drive_spec(8), tmp_path / "drive")
    run([cli, "populate", bag, "-o", tmp_path / "cli.rmap", "--quiet"])
    scans = list(raymap.read_recording(str(bag)))
    recording = raymap.read_clouds(str(bag))
    clouds = list(recording)
    assert len(clouds) == len(scans) >= 7
    assert recording.report()["scans"] == len(clouds)
    angles = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ring = np.stack([6 * np.cos(angles), 6 * np.sin(angles), np.zeros(720)], axis=1)
    t0 = 1_700_000_000_000_000_000
    for cloud, scan in zip(clouds, scans):
        assert (cloud.topic, cloud.frame_id) == ("/points", "base_link")
        # The points as the message holds them (float32), in the sensor's frame.
        np.testing.assert_array_equal(cloud.points, ring.astype(np.float32).astype(np.float64))
        # Times as the decoder keeps them (float32 seconds: within a few nanoseconds).
        np.testing.assert_allclose(cloud.times, np.arange(720) * (100_000_000 // 720) * 1e-9,
                                   rtol=0, atol=1e-8)
        np.testing.assert_array_equal(cloud.sensor_to_base, np.eye(4))
        # One pose per point time: the odometry's (x = 1 m/s since t0) at that time, where the
        # odometry read so far covers it (the last 20 ms may hold its newest pose, as raymapd).
        np.testing.assert_array_equal(cloud.pose_times, cloud.times)
        assert cloud.poses.shape == (720, 4, 4)
        covered = cloud.pose_times <= 0.08
        np.testing.assert_allclose(cloud.poses[covered, 0, 3],
                                   (cloud.stamp_ns - t0) * 1e-9 + cloud.pose_times[covered],
                                   rtol=0, atol=1e-7)
        # Each point through its pose is the end of populate's ray, the pose its origin.
        ends = np.einsum("kij,kj->ki", cloud.poses[:, :3, :3], cloud.points) + cloud.poses[:, :3, 3]
        np.testing.assert_allclose(ends, scan.ends, atol=1e-9)
        np.testing.assert_allclose(cloud.poses[:, :3, 3], scan.origins, atol=1e-9)
    # Mapped as they are, or from their arrays: populate's map.
    in_place = raymap.Mapper()
    by_arrays = raymap.Mapper()
    for cloud in clouds:
        in_place.integrate_cloud(cloud)
        by_arrays.integrate(cloud.points, times=cloud.times, pose_at=(cloud.pose_times, cloud.poses))
    for mapper, name in ((in_place, "in_place"), (by_arrays, "arrays")):
        mapper.flush()
        mapper.save(str(tmp_path / f"{name}.rmap"))
    assert (tmp_path / "in_place.rmap").read_bytes() == (tmp_path / "arrays.rmap").read_bytes()
    assert exported_voxels(cli, tmp_path / "in_place.rmap", tmp_path / "py.ply") == \
        exported_voxels(cli, tmp_path / "cli.rmap", tmp_path / "cli.ply")
    assert region_blocks(tmp_path / "in_place.rmap") == region_blocks(tmp_path / "cli.rmap")


def test_clouds_are_read_from_bags_only(room_rays):
    with pytest.raises(raymap.UnsupportedError, match="world frame"):
        next(iter(raymap.read_clouds(str(room_rays))))
    with pytest.raises(raymap.InvalidArgument, match="read_clouds"):
        raymap.Mapper().integrate_cloud(next(iter(raymap.read_recording(str(room_rays)))))


def depth_frames(count):
    """A 64 x 48 depth camera (its optical frame is base_link) 0.5 m up at (1, 2): a wall 2.5 m
    ahead with a 1.2 m box in front of it and a band of pixels without depth (NaN), in uint16
    millimetres; the robot still (odometry at 50 Hz, frames at 5 Hz on odometry stamps)."""
    v, u = np.mgrid[0:48, 0:64]
    depth = np.full((48, 64), 2.5, dtype=np.float32)
    depth[(abs(u - 20) < 8) & (abs(v - 30) < 10)] = 1.2
    depth[:, 50:54] = np.nan
    millimetres = np.nan_to_num(np.round(depth * 1000), nan=0).astype(np.uint16)
    camera = {"width": 64, "height": 48, "fx": 40.0, "fy": 40.0, "cx": 31.5, "cy": 23.5}
    return [(1_700_000_000_000_000_000 + k * 200_000_000, millimetres) for k in range(count)], \
        camera


def depth_spec(frames, camera):
    def header(stamp, frame):
        return {"stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9}, "frame_id": frame}
    lines = [json.dumps({"op": "channel", "topic": t, "type": ty}) for t, ty in (
        ("/odom", "nav_msgs/msg/Odometry"), ("/cam/depth", "sensor_msgs/msg/Image"),
        ("/cam/camera_info", "sensor_msgs/msg/CameraInfo"))]
    t0, end = frames[0][0], frames[-1][0] + 200_000_000
    for stamp in range(t0 - 100_000_000, end, 20_000_000):
        odom = {"header": header(stamp, "odom"), "child_frame_id": "base_link",
                "pose": {"pose": {"position": {"x": 1.0, "y": 2.0, "z": 0.5}}}}
        lines.append(json.dumps({"op": "message", "topic": "/odom", "log_time_ns": str(stamp),
                                 "msg": odom}))
    fx, fy, cx, cy = camera["fx"], camera["fy"], camera["cx"], camera["cy"]
    for stamp, image in frames:
        info = {"header": header(stamp, "base_link"), "height": 48, "width": 64,
                "distortion_model": "", "d": [0.0] * 5,
                "k": [fx, 0, cx, 0, fy, cy, 0, 0, 1], "r": [1, 0, 0, 0, 1, 0, 0, 0, 1],
                "p": [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0]}
        msg = {"header": header(stamp, "base_link"), "height": 48, "width": 64,
               "encoding": "16UC1", "is_bigendian": 0, "step": 128,
               "data": {"base64": base64.b64encode(image.astype("<u2").tobytes()).decode()}}
        for topic, m in (("/cam/camera_info", info), ("/cam/depth", msg)):
            lines.append(json.dumps({"op": "message", "topic": topic,
                                     "log_time_ns": str(stamp + 1000), "msg": m}))
    return lines


def test_depth_images_map_as_populate_maps_their_bag(cli, write_bag, tmp_path):
    frames, camera = depth_frames(4)
    bag = write_bag(depth_spec(frames, camera), tmp_path / "depth")
    run([cli, "populate", bag, "-o", tmp_path / "cli.rmap", "--quiet", "--downsample", "2",
         "--max-range", "3", "--invalid-as-free"])
    pose = np.eye(4)
    pose[:3, 3] = (1.0, 2.0, 0.5)
    images = raymap.Mapper(max_range=3.0)
    for _, image in frames:
        images.integrate_depth(image, camera, pose, downsample=2, max_range=3.0,
                               invalid_as_free=True)
    clouds = raymap.Mapper(max_range=3.0)
    for cloud in raymap.read_clouds(str(bag), downsample=2, depth_max_range=3.0,
                                    invalid_as_free=True):
        assert cloud.no_return.sum() == 24 * 2  # the band's blocks: free space only
        clouds.integrate_cloud(cloud)
    assert images.counters()["scans"] == clouds.counters()["scans"] == 4
    for mapper, name in ((images, "images"), (clouds, "clouds")):
        mapper.flush()
        mapper.save(str(tmp_path / f"{name}.rmap"))
        assert exported_voxels(cli, tmp_path / f"{name}.rmap", tmp_path / f"{name}.ply") == \
            exported_voxels(cli, tmp_path / "cli.rmap", tmp_path / "cli.ply")
        assert map_description(cli, tmp_path / f"{name}.rmap") == \
            map_description(cli, tmp_path / "cli.rmap")
        assert region_blocks(tmp_path / f"{name}.rmap") == region_blocks(tmp_path / "cli.rmap")
    # The same image in float32 metres, big-endian, or a crop of rows read in place.
    metres = np.where(frames[0][1] == 0, np.nan, frames[0][1] / 1000).astype(np.float32)
    one = raymap.Mapper(max_range=3.0)
    one.integrate_depth(metres.astype(">f4"), camera, pose)
    assert one.counters()["rays_integrated"] == 64 * 48 - 4 * 48
    padded = np.zeros((48, 80), dtype=np.uint16)
    padded[:, :64] = frames[0][1]
    two = raymap.Mapper(max_range=3.0)
    two.integrate_depth(padded[:, :64], camera, pose)
    assert two.counters()["rays_integrated"] == one.counters()["rays_integrated"]


def test_a_bad_depth_image_or_camera_is_named(tmp_path):
    frames, camera = depth_frames(1)
    image = frames[0][1]
    mapper = raymap.Mapper()
    with pytest.raises(raymap.InvalidArgument, match="uint16 .* or float32"):
        mapper.integrate_depth(image.astype(np.int32), camera, np.eye(4))
    with pytest.raises(raymap.InvalidArgument, match="next to each other"):
        mapper.integrate_depth(image[:, ::2], dict(camera, width=32), np.eye(4))
    with pytest.raises(raymap.InvalidArgument, match="width"):
        mapper.integrate_depth(image, dict(camera, width=65), np.eye(4))
    with pytest.raises(raymap.InvalidArgument, match="fx"):
        mapper.integrate_depth(image, dict(camera, fx=-1.0), np.eye(4))
    with pytest.raises(raymap.InvalidArgument, match="camera.focal"):
        mapper.integrate_depth(image, dict(camera, focal=1.0), np.eye(4))
    with pytest.raises(raymap.InvalidArgument, match="max_range"):
        mapper.integrate_depth(image, camera, np.eye(4), invalid_as_free=True)
    assert mapper.counters()["scans"] == 0
