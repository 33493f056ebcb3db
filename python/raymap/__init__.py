# SPDX-License-Identifier: BSD-3-Clause
"""raymap: 3D occupancy mapping of lidar and depth-camera rays, from Python.

The C++ library (raymap::Mapper) with NumPy arrays in and out::

    import numpy as np
    import raymap

    mapper = raymap.Mapper(resolution=0.1, mode="occupancy", semantics="ray")
    mapper.integrate(points, pose)            # (N, 3) sensor-frame points, a 4 x 4 pose
    mapper.flush()
    states = mapper.occupancy(queries)        # (M,) int8: UNOBSERVED, FREE, OCCUPIED
    height = mapper.heightmap(centre=(0, 0, 0), size=20.0)
    mapper.save("map.rmap")                   # what `raymap populate` writes

Options carry the C++ configuration's names (raymap::MapperConfig: map, rays and backend
fields, docs/library.md); errors are the library's messages, raised as the exceptions below.
docs/python.md has the whole guide.
"""

from __future__ import annotations

from typing import Any, Iterator, Optional, Sequence, Tuple, Union

import numpy as np

from . import _raymap
from ._raymap import (
    BackendOptions,
    BagOptions,
    CameraIntrinsics,
    Costmap,
    CostmapOptions,
    DepthOptions,
    HeightMap,
    HeightmapRequest,
    MapOptions,
    MapperConfig,
    NdtOptions,
    RayOptions,
    RecordingOptions,
    TierOptions,
    TsdfOptions,
    parse_byte_size,
)

__version__ = _raymap.__version__

__all__ = [
    "Mapper", "read_recording", "read_clouds", "Scan", "Cloud", "Recording", "HeightMap",
    "HeightmapRequest", "Costmap", "CostmapOptions", "CameraIntrinsics", "DepthOptions",
    "MapperConfig", "MapOptions", "RayOptions", "BackendOptions", "NdtOptions", "TsdfOptions",
    "TierOptions", "RecordingOptions", "BagOptions", "parse_byte_size", "RaymapError",
    "InvalidArgument", "IoError", "FormatError", "CapacityError", "UnsupportedError",
    "UNOBSERVED", "FREE", "OCCUPIED",
]

#: Voxel states as Mapper.occupancy() returns them.
UNOBSERVED, FREE, OCCUPIED = 0, 1, 2


class RaymapError(Exception):
    """An error of the raymap library; str() is its message (the option, file or key and why)."""


class InvalidArgument(RaymapError, ValueError):
    """An option out of range or inconsistent, or an array of the wrong shape or type."""


class IoError(RaymapError, OSError):
    """The operating system refused to open, read, write or rename a file."""


class FormatError(RaymapError, ValueError):
    """A file is not in the expected format, ends early, or fails a checksum."""


class CapacityError(RaymapError, MemoryError):
    """A fixed-size store is full (raise max_memory, or turn the tiers on)."""


class UnsupportedError(RaymapError, NotImplementedError):
    """Valid input this build cannot handle (a backend it was built without)."""


_raymap._set_error_types({
    "invalid-argument": InvalidArgument,
    "io": IoError,
    "format": FormatError,
    "truncated": FormatError,
    "corrupt": FormatError,
    "capacity": CapacityError,
    "unsupported": UnsupportedError,
})

PoseLike = Union[np.ndarray, Sequence[Sequence[float]], Tuple[Sequence[float], Sequence[float]]]


def _pose_matrix(pose: PoseLike, what: str = "pose") -> np.ndarray:
    """A 4 x 4 float64 matrix from a 4 x 4 array or (translation, quaternion x y z w)."""
    if isinstance(pose, tuple) and len(pose) == 2:
        translation = np.asarray(pose[0], dtype=np.float64)
        quaternion = np.asarray(pose[1], dtype=np.float64)
        if translation.shape != (3,) or quaternion.shape != (4,):
            raise InvalidArgument(
                f"{what}: (translation, quaternion) must be 3 and 4 numbers (x y z w), "
                f"not {translation.shape} and {quaternion.shape}")
        return _raymap._pose_matrix(translation, quaternion)
    return np.asarray(pose, dtype=np.float64)


def _set_option(config: MapperConfig, name: str, value: Any) -> None:
    """Sets one keyword option: a field of config.map, config.rays or config.backend by its
    C++ name, or one of the short forms (backend, max_memory, compressed_memory, ndt, tsdf)."""
    if name == "backend":
        config.backend.name = value
    elif name in ("max_memory", "compressed_memory"):
        size = parse_byte_size(value) if isinstance(value, str) else int(value)
        if name == "max_memory":
            config.map.max_memory_bytes = size
        else:
            config.map.tiers.compressed_memory_bytes = size
    elif name == "tiers" and isinstance(value, bool):
        config.map.tiers.enabled = value
    elif name == "spill_dir":
        config.map.tiers.spill_dir = value
    elif name in ("ndt", "tsdf") and isinstance(value, dict):
        target = getattr(config.map, name)
        for key, item in value.items():
            if not hasattr(target, key):
                raise InvalidArgument(f"map.{name}.{key}: not an option of map.{name}")
            setattr(target, key, item)
        setattr(config.map, name, target)
    else:
        for section in ("map", "rays", "backend"):
            part = getattr(config, section)
            if hasattr(part, name) and not name.startswith("_"):
                setattr(part, name, value)
                setattr(config, section, part)
                return
        raise InvalidArgument(
            f"{name}: not an option (the fields of MapOptions, RayOptions and BackendOptions, "
            "and backend, max_memory, compressed_memory, tiers, spill_dir)")


def make_config(config: Union[None, str, MapperConfig] = None, **options: Any) -> MapperConfig:
    """A MapperConfig: `config` (a MapperConfig, or a YAML file whose map: and backend: sections
    are read as raymapd reads them), then each keyword option over it."""
    if isinstance(config, MapperConfig):
        result = config
    else:
        result = MapperConfig()
        if config is not None:
            result, warnings = _raymap.load_config(str(config), result)
            for warning in warnings:
                import warnings as _warnings
                _warnings.warn(warning, DeprecationWarning, stacklevel=3)
    for name, value in options.items():
        try:
            _set_option(result, name, value)
        except TypeError as error:  # pybind11's message for a value of the wrong type
            raise InvalidArgument(f"{name}: {error}") from None
    return result


def _heightmap_request(centre: Sequence[float], size: float, options: dict) -> HeightmapRequest:
    request = HeightmapRequest()
    request.centre = tuple(float(v) for v in centre)
    request.size = size
    for name, value in options.items():
        if name.startswith("_") or not hasattr(request, name):
            raise InvalidArgument(f"{name}: not an option of a height map (HeightmapRequest)")
        setattr(request, name, value)
    return request


class Mapper:
    """A 3D map and its integration backend (raymap::Mapper).

    Mapper(config=None, **options): `config` is a MapperConfig or the path of a YAML file with
    raymapd's map: and backend: sections; the keyword options are the C++ configuration's
    fields by name (resolution, region_voxels, semantics "ray"/"scan", mode "occupancy",
    "ndt-om", "ndt-tm", "tsdf", "decay" or "<mode>+decay", hit_probability, miss_probability,
    clamp_min_probability, clamp_max_probability, occupied_threshold, voxel_mean, decay_rate,
    window, min_range, max_range, max_ray_length, segment_length, walk, threads, fallback_cpu,
    gpu_memory, batch_rays …) plus backend="cpu"/"opencl"/"cuda", max_memory="4GiB",
    tiers=True, compressed_memory="1GiB", spill_dir, ndt={...} and tsdf={...}.

    Thread-safety: one mapper may be used from several Python threads; calls on it run one at
    a time, with the GIL released while the map integrates or answers.
    """

    def __init__(self, config: Union[None, str, MapperConfig] = None, **options: Any) -> None:
        self._mapper = _raymap._Mapper.create(make_config(config, **options))

    @classmethod
    def load(cls, path: str, rays: Optional[RayOptions] = None,
             backend: Union[None, str, BackendOptions] = None) -> "Mapper":
        """Loads a map saved by save() or `raymap populate` (its geometry and mode come from
        the file); `rays` applies to what is integrated next; `backend` is a name or options."""
        if isinstance(backend, str):
            name, backend = backend, BackendOptions()
            backend.name = name
        self = cls.__new__(cls)
        self._mapper = _raymap._Mapper.load(str(path), rays or RayOptions(),
                                            backend or BackendOptions())
        return self

    def integrate(self, points: np.ndarray, pose: Optional[PoseLike] = None, *,
                  times: Optional[np.ndarray] = None,
                  pose_at: Optional[Tuple[np.ndarray, np.ndarray]] = None,
                  intensities: Optional[np.ndarray] = None) -> None:
        """Integrates one scan of sensor-frame points, (N, 3) float32 or float64, metres.

        Either at one pose (`pose`: a 4 x 4 sensor-to-world matrix, or (translation,
        quaternion x y z w)), or deskewed: `times` (N,) seconds per point and `pose_at` =
        (pose_times (M,), poses (M, 4, 4)), a table of the sensor's poses whose times increase.
        Points with NaN or infinite coordinates are counted (counters()["rays_invalid"]), not
        errors. The arrays are read in place; the GIL is released while the scan integrates.
        """
        if (pose is None) == (pose_at is None):
            raise InvalidArgument("integrate: give either pose or pose_at (with times)")
        if pose is not None:
            if times is not None:
                raise InvalidArgument("integrate: times go with pose_at, not with one pose")
            self._mapper.integrate_points(points, _pose_matrix(pose), intensities)
            return
        if times is None:
            raise InvalidArgument("integrate: pose_at needs the points' times")
        if not isinstance(pose_at, tuple) or len(pose_at) != 2:
            raise InvalidArgument("pose_at must be (pose_times (M,), poses (M, 4, 4))")
        pose_times, poses = pose_at
        self._mapper.integrate_deskewed(points, times, np.asarray(pose_times),
                                        np.asarray(poses), intensities)

    def integrate_depth(self, image: np.ndarray, camera: Any, pose: PoseLike, *,
                        downsample: int = 1, min_range: float = 0.0, max_range: float = 0.0,
                        invalid_as_free: bool = False) -> None:
        """Integrates one depth image as one scan, as raymapd and `raymap populate` do.

        image: (height, width) uint16 millimetres (16UC1; 0 = no depth) or float32 metres
        (32FC1; 0, NaN, +inf = no depth), either byte order, rows of adjacent pixels (a crop of
        rows is read in place). camera: a CameraIntrinsics, or a dict of its fields (width,
        height, fx, fy, cx, cy, distortion "none"/"plumb_bob", k1 k2 p1 p2 k3). pose: the
        camera's optical frame (x right, y down, z forward) in the world, as for integrate().
        downsample N: each N x N block gives its nearest depth; min_range: nearer depths are the
        robot itself; invalid_as_free: a block without depth clears max_range metres of free
        space along its ray (needs max_range). Errors name the field (an image whose size is not
        the camera's, a camera that cannot be used).
        """
        options = _raymap.DepthOptions()
        options.downsample = downsample
        options.min_range = min_range
        options.max_range = max_range
        options.invalid_as_free = invalid_as_free
        self._mapper.integrate_depth(image, _camera(camera), _pose_matrix(pose), options)

    def integrate_rays(self, origins: np.ndarray, ends: np.ndarray, *,
                       intensities: Optional[np.ndarray] = None,
                       no_return: Optional[np.ndarray] = None) -> None:
        """Integrates world-frame rays: origins and ends (N, 3), metres; no_return (N,) bool
        marks rays that only clear free space to their end."""
        self._mapper.integrate_rays(origins, ends, intensities, no_return)

    def integrate_scan(self, scan: "Scan") -> None:
        """Integrates a scan of read_recording() as it is: its buffer is already the library's
        ray layout, so nothing is converted or copied (integrate_rays() of its arrays gives the
        same map)."""
        if not isinstance(scan, Scan):
            raise InvalidArgument("integrate_scan: expected a raymap.Scan from read_recording()")
        self._mapper.integrate_scan(scan._rays)

    def integrate_cloud(self, cloud: "Cloud") -> None:
        """Integrates a cloud of read_clouds() as it is, deskewed by its own poses (its points
        and pose table are already the library's layout: nothing is converted or copied)."""
        if not isinstance(cloud, Cloud):
            raise InvalidArgument("integrate_cloud: expected a raymap.Cloud from read_clouds()")
        self._mapper.integrate_cloud(cloud._cloud)

    def flush(self) -> None:
        """Integrates what waits in the batch, so that queries see every ray given so far."""
        self._mapper.flush()

    def move_window(self, centre: Sequence[float]) -> int:
        """Centres a rolling window (window=(x, y, z) regions) on `centre`; regions recycled."""
        return self._mapper.move_window(np.asarray(centre, dtype=np.float64))

    def occupancy(self, points: np.ndarray) -> np.ndarray:
        """The state of the voxel holding each point (N, 3): (N,) int8 of UNOBSERVED (0),
        FREE (1), OCCUPIED (2). Sees what was integrated up to the last flush()."""
        return self._mapper.occupancy(points)

    def log_odds(self, points: np.ndarray) -> np.ndarray:
        """Occupancy log-odds of the voxel holding each point: (N,) float32, NaN where
        unobserved."""
        return self._mapper.log_odds(points)

    def voxels(self, state: str = "occupied") -> np.ndarray:
        """The centres of every voxel in `state` ("occupied" or "free"): (N, 3) float64, metres,
        in a fixed order. Counts match counts()."""
        return self._mapper.voxels(state)

    def voxel_keys(self, state: str = "occupied") -> np.ndarray:
        """The integer keys of every voxel in `state`: (N, 3) int32 (centre = (key + 0.5) *
        resolution)."""
        return self._mapper.voxel_keys(state)

    def counts(self) -> dict:
        """Voxel counts: regions, voxels_free, voxels_occupied."""
        return self._mapper.counts()

    def counters(self) -> dict:
        """What the mapper did: scans, rays_in, rays_integrated, rays_invalid, rays_too_short,
        rays_out_of_bounds, rays_clipped, rays_no_return, points_no_pose, batches …"""
        return self._mapper.counters()

    def heightmap(self, centre: Sequence[float], size: float = 20.0, **options: Any) -> HeightMap:
        """The 2.5D height map around centre (x, y, z), `size` metres square, as
        `raymap heightmap` makes it. Options (HeightmapRequest's fields): follow_terrain,
        min_clearance, floor_depth, ceiling_height, virtual_surfaces. Layers are
        (cells_x, cells_y) arrays in grid_map's layout."""
        return self._mapper.heightmap(_heightmap_request(centre, size, options))

    def costmap(self, centre: Sequence[float], size: float = 20.0,
                options: Optional[CostmapOptions] = None, **request: Any) -> Costmap:
        """The Nav2 costmap of the height map around centre, as raymapd publishes it; `request`
        as heightmap()'s options, `options` the costmap's (max_step, max_slope_deg …)."""
        return self._mapper.costmap(_heightmap_request(centre, size, request),
                                    options or CostmapOptions())

    def export_ply(self, path: str, kind: str = "occupied", **options: Any) -> dict:
        """Writes the PLY `raymap export` writes: kind "occupied", "free", "mean", "decay",
        "ndt", "ndt-points", "tsdf" or "tsdf-mesh"; options decay_threshold, ndt_sigmas,
        ndt_min_axis, ndt_colour ("height", "intensity", "permeability"), tsdf_min_weight (one
        that does not fit the kind is refused, naming it). Returns {"items", "vertices"}."""
        return self._mapper.export_ply(str(path), kind, **options)

    def save(self, path: str) -> None:
        """Writes the map (.rmap, what `raymap populate` writes) via a temporary file."""
        self._mapper.save(str(path))

    @property
    def map_options(self) -> MapOptions:
        """The map's settings (as created, or as read from the file by load())."""
        return self._mapper.map_options

    @property
    def backend(self) -> str:
        """Where integration runs: cpu, opencl or cuda."""
        return self._mapper.backend

    @property
    def fallback_warning(self) -> str:
        """Why the CPU replaced the requested backend (fallback_cpu=True); empty if it did not."""
        return self._mapper.fallback_warning

    @property
    def memory_warning(self) -> str:
        """Why the map holds fewer regions than max_memory asked; empty if it holds them all."""
        return self._mapper.memory_warning


class Scan:
    """One scan of a recording: world-frame rays as arrays (views of the scan's own buffer).

    origins, ends: (N, 3) float64, metres; intensities: (N,) float32; no_return: (N,) bool.
    """

    __slots__ = ("origins", "ends", "intensities", "no_return", "_rays")

    def __init__(self, arrays: dict) -> None:
        self.origins = arrays["origins"]
        self.ends = arrays["ends"]
        self.intensities = arrays["intensities"]
        self.no_return = arrays["no_return"]
        self._rays = arrays["rays"]  # the buffer the arrays view (Mapper.integrate_scan)

    def __len__(self) -> int:
        return len(self.ends)


class Cloud:
    """One point cloud (or depth image) of a bag as its sensor took it (views of the cloud's own
    buffer).

    topic, frame_id: the sensor's topic and header.frame_id; stamp_ns: header.stamp (int,
    nanoseconds). points: (N, 3) float64, the sensor's frame, metres; times: (N,) float64, each
    point's time in seconds after stamp_ns; intensities: (N,) float32; no_return: (N,) bool
    (free-space points of a depth image read with invalid_as_free). pose_times (M,) and poses
    (M, 4, 4): the sensor's pose in the world (sensor-to-world) at each distinct point time,
    seconds after stamp_ns — the poses `raymap populate` maps the cloud with. sensor_to_base
    (4, 4): the sensor on the robot (from /tf_static or sensor_offset).

    Mapper.integrate_cloud(cloud) maps it as it is; Mapper.integrate(cloud.points,
    times=cloud.times, pose_at=(cloud.pose_times, cloud.poses)) does the same from the arrays.
    """

    __slots__ = ("topic", "frame_id", "stamp_ns", "points", "times", "intensities", "no_return",
                 "pose_times", "poses", "sensor_to_base", "_cloud")

    def __init__(self, fields: dict) -> None:
        for name in self.__slots__[:-1]:
            setattr(self, name, fields[name])
        self._cloud = fields["cloud"]  # the buffer the arrays view (Mapper.integrate_cloud)

    def __len__(self) -> int:
        return len(self.points)


class Recording:
    """The scans of a recording (read_recording) or the clouds of a bag (read_clouds), in
    order (iterate it); report() and warnings() afterwards."""

    def __init__(self, reader: Any, clouds: bool = False) -> None:
        self._reader = reader
        self._clouds = clouds

    def __iter__(self) -> Iterator[Any]:
        while True:
            if self._clouds:
                fields = self._reader.next_cloud()
                if fields is None:
                    return
                yield Cloud(fields)
            else:
                arrays = self._reader.next_scan()
                if arrays is None:
                    return
                yield Scan(arrays)

    @property
    def progress(self) -> float:
        """Fraction of the recording read, 0 to 1."""
        return self._reader.progress

    @property
    def is_bag(self) -> bool:
        return self._reader.is_bag

    def report(self) -> dict:
        """A bag's counts so far: topics, messages, clouds, scans, scans_no_pose …"""
        return self._reader.report()

    def warnings(self) -> list:
        """What the reader noticed: skipped messages, damage, the pose source chosen."""
        return self._reader.warnings()


def read_recording(path: str, **options: Any) -> Recording:
    """Opens a recording as `raymap populate` reads it: a rosbag2 bag (a folder, .mcap or .db3)
    or a ray-cloud / point-cloud PLY; iterating it gives Scans of world rays. Options: the fields
    of RecordingOptions (trajectory_path, sensor_offset, scan_period_s) and of BagOptions (topics,
    pose_topic, pose_source, world_frame, base_frame, time_field, camera_info_topics, downsample,
    invalid_as_free, max_rate_hz, skip_damaged …)."""
    return Recording(_raymap._RecordingReader.open(str(path), _recording_options(options)))


def read_clouds(path: str, **options: Any) -> Recording:
    """Opens a rosbag2 bag whose iteration gives its point clouds (or depth images) as Clouds:
    points in the sensor's frame with the sensor's poses from the bag's odometry or TF. The
    options are read_recording()'s. A PLY file raises UnsupportedError when read (its rays are in
    the world frame already: read_recording)."""
    return Recording(_raymap._RecordingReader.open(str(path), _recording_options(options)),
                     clouds=True)


def _camera(camera: Any) -> "CameraIntrinsics":
    if isinstance(camera, CameraIntrinsics):
        return camera
    if not isinstance(camera, dict):
        raise InvalidArgument("camera must be a raymap.CameraIntrinsics or a dict of its fields")
    out = CameraIntrinsics()
    for name, value in camera.items():
        if not hasattr(out, name) or name.startswith("_") or name == "validate":
            raise InvalidArgument(f"camera.{name}: not a field of CameraIntrinsics")
        setattr(out, name, value)
    return out


def _recording_options(options: dict) -> RecordingOptions:
    recording = RecordingOptions()
    bag = recording.bag
    for name, value in options.items():
        if hasattr(recording, name) and name != "bag":
            setattr(recording, name, value)
        elif hasattr(bag, name):
            setattr(bag, name, value)
        else:
            raise InvalidArgument(f"{name}: not an option of RecordingOptions or BagOptions")
    recording.bag = bag
    return recording
