# SPDX-License-Identifier: BSD-3-Clause
"""raymap.Mapper from Python: options by the C++ names, integration from NumPy arrays at one
pose, deskewed by a pose table and as world rays, vectorised queries, height maps and costmaps,
save and load, every error path, and the GIL released while a scan integrates."""

import sys
import threading
import time

import numpy as np
import pytest

import raymap


def ring(n=720, radius=5.0, z=0.0):
    """n sensor-frame points on a horizontal circle of `radius` metres."""
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.stack([radius * np.cos(angles), radius * np.sin(angles), np.full(n, z)], axis=1)


def test_options_take_the_cpp_names_and_reach_the_map():
    mapper = raymap.Mapper(resolution=0.2, semantics="ray", mode="ndt-om", hit_probability=0.8,
                           max_range=30.0, threads=1, backend="cpu", max_memory="64MiB",
                           ndt={"sensor_noise": 0.03})
    options = mapper.map_options
    assert options.resolution == pytest.approx(0.2)
    assert options.semantics == "ray"
    assert options.mode == "ndt-om"
    assert options.ndt.sensor_noise == pytest.approx(0.03)
    assert options.max_memory_bytes == 64 << 20
    assert options.hit_probability == pytest.approx(0.8)
    assert mapper.backend == "cpu"


def test_a_yaml_file_written_for_raymapd_configures_the_mapper(tmp_path):
    config = tmp_path / "robot.yaml"
    config.write_text("map:\n  resolution: 0.25\n  semantics: per-scan\nbackend:\n  name: cpu\n")
    with pytest.warns(DeprecationWarning, match="per-scan is the old name"):
        mapper = raymap.Mapper(str(config), region_voxels=16)
    assert mapper.map_options.resolution == pytest.approx(0.25)
    assert mapper.map_options.semantics == "scan"
    assert mapper.map_options.region_voxels == 16


def test_points_at_one_pose_mark_their_voxels_and_the_space_before_them():
    mapper = raymap.Mapper(resolution=0.1)
    pose = np.eye(4)
    pose[:3, 3] = [1.0, 2.0, 0.5]
    mapper.integrate(ring().astype(np.float32), pose)
    mapper.flush()
    states = mapper.occupancy(np.array([[6.05, 2.05, 0.55], [3.55, 2.05, 0.55], [1.05, 9.05, 0.55]]))
    assert states.dtype == np.int8
    assert list(states) == [raymap.OCCUPIED, raymap.FREE, raymap.UNOBSERVED]
    log_odds = mapper.log_odds(np.array([[6.05, 2.05, 0.55], [1.05, 9.05, 0.55]]))
    assert log_odds[0] > 0 and np.isnan(log_odds[1])
    counters = mapper.counters()
    assert counters["rays_in"] == 720 and counters["rays_integrated"] == 720


def test_a_translation_and_quaternion_pose_is_the_matrix_pose():
    yaw = 0.3
    matrix = np.eye(4)
    matrix[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    matrix[:3, 3] = [0.5, -1.0, 0.2]
    quaternion = (0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2))  # x y z w
    a = raymap.Mapper()
    b = raymap.Mapper()
    a.integrate(ring(), matrix)
    b.integrate(ring(), ((0.5, -1.0, 0.2), quaternion))
    a.flush()
    b.flush()
    assert a.counts() == b.counts()
    grid = np.stack(np.meshgrid(np.arange(-6, 6, 0.1), np.arange(-7, 5, 0.1), [0.25]), -1)
    queries = grid.reshape(-1, 3)
    np.testing.assert_array_equal(a.occupancy(queries), b.occupancy(queries))


def test_the_voxels_of_a_state_are_listed_where_they_are():
    mapper = raymap.Mapper(resolution=0.1)
    mapper.integrate(ring(), np.eye(4))
    mapper.flush()
    occupied = mapper.voxels("occupied")
    free = mapper.voxels("free")
    keys = mapper.voxel_keys()
    assert occupied.shape == (mapper.counts()["voxels_occupied"], 3)
    assert free.shape == (mapper.counts()["voxels_free"], 3)
    assert keys.dtype == np.int32
    np.testing.assert_allclose(occupied, (keys + 0.5) * 0.1)
    assert np.all(mapper.occupancy(occupied) == raymap.OCCUPIED)
    assert np.all(mapper.occupancy(free) == raymap.FREE)
    radius = np.hypot(occupied[:, 0], occupied[:, 1])
    assert np.all(np.abs(radius - 5.0) < 0.15)  # on the ring
    with pytest.raises(raymap.InvalidArgument, match="not occupied or free"):
        mapper.voxels("unobserved")


def test_a_pose_table_deskews_a_moving_sweep():
    # The sensor moves 1 m along +x during the sweep; each point was measured where it was then.
    n = 720
    times = np.linspace(0.0, 0.1, n, endpoint=False)
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    sensor_x = 10.0 * times
    wall = 8.0
    # Points on the wall x = 8 seen from the moving sensor, in its own frame (no rotation).
    forward = np.abs(angles - np.pi) > np.pi / 2 + 0.3  # beams pointing at +x
    ranges = (wall - sensor_x[forward]) / np.cos(angles[forward])
    points = np.stack([ranges * np.cos(angles[forward]), ranges * np.sin(angles[forward]),
                       np.zeros(forward.sum())], axis=1)
    pose_times = np.array([0.0, 0.1])
    poses = np.stack([np.eye(4), np.eye(4)])
    poses[1, 0, 3] = 1.0
    deskewed = raymap.Mapper()
    deskewed.integrate(points, times=times[forward], pose_at=(pose_times, poses))
    deskewed.flush()
    wall_points = np.stack([np.full(5, wall - 0.05), np.linspace(-0.4, 0.4, 5), np.zeros(5)], 1)
    assert list(deskewed.occupancy(wall_points)) == [raymap.OCCUPIED] * 5
    assert deskewed.counters()["points_no_pose"] == 0


def test_world_rays_with_no_returns_only_clear_space():
    mapper = raymap.Mapper()
    origins = np.zeros((2, 3))
    ends = np.array([[4.0, 0.05, 0.05], [0.05, 4.0, 0.05]])
    mapper.integrate_rays(origins, ends, no_return=np.array([False, True]))
    mapper.flush()
    states = mapper.occupancy(np.array([[4.05, 0.05, 0.05], [0.05, 4.05, 0.05], [0.05, 2.05, 0.05]]))
    assert list(states) == [raymap.OCCUPIED, raymap.UNOBSERVED, raymap.FREE]
    assert mapper.counters()["rays_no_return"] == 1


def test_arrays_are_read_in_place_whatever_their_strides():
    points = ring()
    strided = np.asfortranarray(points)          # column-major
    every_other = np.repeat(points, 2, axis=0)[::2]  # a row stride of two rows
    a, b, c = raymap.Mapper(), raymap.Mapper(), raymap.Mapper()
    for mapper, array in ((a, points), (b, strided), (c, every_other)):
        mapper.integrate(array, np.eye(4))
        mapper.flush()
    assert a.counts() == b.counts() == c.counts()


def test_nan_points_are_counted_not_fatal():
    points = ring(10)
    points[3] = np.nan
    points[7, 1] = np.inf
    mapper = raymap.Mapper()
    mapper.integrate(points, np.eye(4))
    mapper.flush()
    counters = mapper.counters()
    assert counters["rays_invalid"] == 2
    assert counters["rays_integrated"] == 8


def test_a_height_map_has_each_layer_as_a_grid_map_array():
    mapper = raymap.Mapper()
    # A floor at z = 0 seen from 1 m above it.
    xs, ys = np.meshgrid(np.arange(-3, 3, 0.05), np.arange(-3, 3, 0.05))
    ends = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    mapper.integrate_rays(np.tile([0.0, 0.0, 1.0], (len(ends), 1)), ends)
    mapper.flush()
    height = mapper.heightmap(centre=(0.0, 0.0, 0.0), size=4.0)
    assert (height.cells_x, height.cells_y) == (40, 40)
    for layer, dtype in ((height.elevation, np.float32), (height.clearance, np.float32),
                         (height.kind, np.uint8), (height.observed_count, np.uint32)):
        assert layer.shape == (40, 40) and layer.dtype == dtype
        assert not layer.flags.writeable
    # [i, j]: i along -x, j along -y from the +x/+y corner.
    assert height.cell_centre(0, 0) == pytest.approx((1.95, 1.95))
    assert height.cell_centre(39, 0) == pytest.approx((-1.95, 1.95))
    surface = height.kind == 1
    assert surface.mean() > 0.9
    assert np.all(np.abs(height.elevation[surface]) < 0.1)
    costmap = mapper.costmap(centre=(0.0, 0.0, 0.0), size=4.0)
    assert costmap.cells.shape == (costmap.height, costmap.width) == (40, 40)
    assert costmap.cells.dtype == np.int8
    assert np.count_nonzero(costmap.cells == 0) > 1000  # a flat floor is free


def test_a_saved_map_loads_with_its_voxels(tmp_path):
    mapper = raymap.Mapper(resolution=0.2, mode="occupancy+decay")
    mapper.integrate(ring(), np.eye(4))
    mapper.flush()
    mapper.save(str(tmp_path / "ring.rmap"))
    loaded = raymap.Mapper.load(str(tmp_path / "ring.rmap"))
    assert loaded.counts() == mapper.counts()
    assert loaded.map_options.resolution == pytest.approx(0.2)
    assert loaded.map_options.mode == "occupancy+decay"
    queries = ring(50, radius=5.05)
    np.testing.assert_array_equal(loaded.occupancy(queries), mapper.occupancy(queries))


@pytest.mark.parametrize("options, message", [
    ({"resolution": -1.0}, "resolution"),
    ({"mode": "octree"}, "map.mode: 'octree' is not a mode"),
    ({"semantics": "ray-ish"}, "map.semantics"),
    ({"no_such_option": 1}, "no_such_option: not an option"),
    ({"ndt": {"noise": 0.1}}, "map.ndt.noise"),
    ({"mode": "tsdf", "semantics": "scan"}, "semantics"),
    ({"backend": "quantum"}, "quantum"),
    ({"max_memory": "lots"}, "lots"),
])
def test_bad_options_raise_the_library_message(options, message):
    with pytest.raises(raymap.InvalidArgument, match=message):
        raymap.Mapper(**options)


def test_bad_arrays_and_poses_raise_value_errors_naming_them():
    mapper = raymap.Mapper()
    with pytest.raises(ValueError, match=r"points must be an \(N, 3\) array, not \(4, 2\)"):
        mapper.integrate(np.zeros((4, 2)), np.eye(4))
    with pytest.raises(ValueError, match="points must be float32 or float64, not int64"):
        mapper.integrate(np.zeros((4, 3), dtype=np.int64), np.eye(4))
    with pytest.raises(ValueError, match=r"pose must be a \(4, 4\) matrix"):
        mapper.integrate(ring(), np.eye(3))
    skewed = np.eye(4)
    skewed[0, 1] = 0.5
    with pytest.raises(ValueError, match="not a rotation"):
        mapper.integrate(ring(), skewed)
    with pytest.raises(ValueError, match=r"times must be an \(720,\) array"):
        mapper.integrate(ring(), times=np.zeros(3), pose_at=(np.zeros(1), np.eye(4)[None]))
    with pytest.raises(ValueError, match="pose_times|increasing|pose"):
        mapper.integrate(ring(), times=np.zeros(720),
                         pose_at=(np.array([1.0, 0.0]), np.stack([np.eye(4)] * 2)))
    with pytest.raises(ValueError, match="same length"):
        mapper.integrate_rays(np.zeros((3, 3)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="either pose or pose_at"):
        mapper.integrate(ring())


def test_file_errors_name_the_file(tmp_path):
    with pytest.raises(raymap.IoError, match="missing.rmap"):
        raymap.Mapper.load(str(tmp_path / "missing.rmap"))
    (tmp_path / "bad.rmap").write_bytes(b"not a map at all")
    with pytest.raises(raymap.RaymapError, match="bad.rmap"):
        raymap.Mapper.load(str(tmp_path / "bad.rmap"))
    with pytest.raises(raymap.IoError, match="no_such_folder"):
        raymap.Mapper().save(str(tmp_path / "no_such_folder" / "map.rmap"))
    with pytest.raises(raymap.RaymapError, match="nothing.ply"):
        raymap.read_recording(str(tmp_path / "nothing.ply"))


def test_the_gil_is_released_while_a_scan_integrates():
    # With a long switch interval the interpreter never takes the GIL from a running thread: the
    # other thread runs during integrate() only if integrate() releases it.
    points = np.random.default_rng(1).uniform(-5, 5, (400_000, 3))
    mapper = raymap.Mapper()
    count = 0
    stop = threading.Event()

    def spin():
        nonlocal count
        while not stop.is_set():
            count += 1
            time.sleep(0)  # gives the GIL back each time

    previous = sys.getswitchinterval()
    sys.setswitchinterval(30.0)
    worker = threading.Thread(target=spin)
    try:
        worker.start()
        before = count
        mapper.integrate(points, np.eye(4))
        after = count
    finally:
        stop.set()
        worker.join()
        sys.setswitchinterval(previous)
    assert after > before


def test_two_threads_integrating_into_one_mapper_lose_nothing():
    mapper = raymap.Mapper(semantics="ray")
    scans = [ring(2000, radius=3.0 + k) for k in range(8)]
    threads = [threading.Thread(target=lambda s=s: mapper.integrate(s, np.eye(4))) for s in scans]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    mapper.flush()
    assert mapper.counters()["rays_integrated"] == 8 * 2000
