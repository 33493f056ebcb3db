# SPDX-License-Identifier: BSD-3-Clause
# Type stubs of raymap._raymap, the compiled half of the package (python/src).
from typing import Any, Optional, Sequence, Tuple

import numpy as np

__version__: str

class NdtOptions:
    sensor_noise: Optional[float]
    regulariser: Optional[float]
    sample_threshold: Optional[int]
    reinit_probability: Optional[float]
    reinit_count: Optional[int]
    adaptation_rate: Optional[float]
    initial_intensity_variance: Optional[float]
    def __init__(self) -> None: ...

class TsdfOptions:
    truncation: Optional[float]
    max_weight: Optional[float]
    dropoff: Optional[float]
    def __init__(self) -> None: ...

class TierOptions:
    enabled: bool
    compressed_memory_bytes: int
    spill_dir: str
    def __init__(self) -> None: ...

class MapOptions:
    resolution: float
    region_voxels: int
    semantics: str
    mode: str
    voxel_mean: bool
    decay_rate: bool
    occupancy: bool
    ndt: NdtOptions
    tsdf: TsdfOptions
    hit_probability: float
    miss_probability: float
    clamp_min_probability: float
    clamp_max_probability: float
    occupied_threshold: float
    max_memory_bytes: int
    tiers: TierOptions
    window: Optional[Tuple[int, int, int]]
    def __init__(self) -> None: ...

class RayOptions:
    min_range: float
    max_range: float
    max_ray_length: float
    segment_length: float
    walk: str
    def __init__(self) -> None: ...

class BackendOptions:
    name: str
    threads: int
    opencl_platform: str
    opencl_device: str
    cuda_device: int
    fallback_cpu: bool
    device_planning: str
    gpu_cache_bytes: int
    gpu_cache_regions: int
    gpu_memory: str
    opencl_span_work: str
    batch_rays: int
    def __init__(self) -> None: ...

class MapperConfig:
    map: MapOptions
    rays: RayOptions
    backend: BackendOptions
    def __init__(self) -> None: ...

class HeightmapRequest:
    centre: Tuple[float, float, float]
    size: float
    follow_terrain: bool
    min_clearance: float
    floor_depth: Optional[float]
    ceiling_height: Optional[float]
    virtual_surfaces: bool
    def __init__(self) -> None: ...

class HeightMap:
    resolution: float
    cells_x: int
    cells_y: int
    centre: Tuple[float, float]
    elevation: np.ndarray
    clearance: np.ndarray
    kind: np.ndarray
    observed_count: np.ndarray
    def cell_centre(self, i: int, j: int) -> Tuple[float, float]: ...

class CostmapOptions:
    max_step: float
    max_slope_deg: float
    min_clearance: float
    virtual_lethal: bool
    max_free_cost: int
    def __init__(self) -> None: ...

class Costmap:
    resolution: float
    width: int
    height: int
    origin: Tuple[float, float]
    cells: np.ndarray

class BagOptions:
    topics: list[str]
    camera_info_topics: list[str]
    pose_topic: str
    pose_source: str
    world_frame: str
    base_frame: str
    sensor_offset: Optional[Tuple[float, float, float]]
    time_field: str
    downsample: int
    depth_min_range: float
    depth_max_range: float
    invalid_as_free: bool
    max_rate_hz: float
    skip_damaged: bool
    def __init__(self) -> None: ...

class RecordingOptions:
    trajectory_path: str
    sensor_offset: Tuple[float, float, float]
    scan_period_s: float
    bag: BagOptions
    def __init__(self) -> None: ...

class _Mapper:
    @staticmethod
    def create(config: MapperConfig) -> _Mapper: ...
    @staticmethod
    def load(path: str, rays: RayOptions, backend: BackendOptions) -> _Mapper: ...
    def save(self, path: str) -> None: ...
    def export_ply(self, path: str, kind: str = ..., decay_threshold: Optional[float] = ...,
                   ndt_sigmas: Optional[float] = ..., ndt_min_axis: Optional[float] = ...,
                   ndt_colour: Optional[str] = ...,
                   tsdf_min_weight: Optional[float] = ...) -> dict: ...
    def integrate_points(self, points: np.ndarray, pose: np.ndarray,
                         intensities: Optional[np.ndarray] = ...) -> None: ...
    def integrate_deskewed(self, points: np.ndarray, times: np.ndarray, pose_times: np.ndarray,
                           poses: np.ndarray, intensities: Optional[np.ndarray] = ...) -> None: ...
    def integrate_scan(self, rays: Any) -> None: ...
    def integrate_cloud(self, cloud: Any) -> None: ...
    def integrate_depth(self, image: np.ndarray, camera: CameraIntrinsics, pose: np.ndarray,
                        options: DepthOptions) -> None: ...
    def integrate_rays(self, origins: np.ndarray, ends: np.ndarray,
                       intensities: Optional[np.ndarray] = ...,
                       no_return: Optional[np.ndarray] = ...) -> None: ...
    def flush(self) -> None: ...
    def move_window(self, centre: np.ndarray) -> int: ...
    def occupancy(self, points: np.ndarray) -> np.ndarray: ...
    def log_odds(self, points: np.ndarray) -> np.ndarray: ...
    def voxels(self, state: str = ...) -> np.ndarray: ...
    def voxel_keys(self, state: str = ...) -> np.ndarray: ...
    def counts(self) -> dict: ...
    def counters(self) -> dict: ...
    def heightmap(self, request: HeightmapRequest) -> HeightMap: ...
    def costmap(self, request: HeightmapRequest, options: CostmapOptions) -> Costmap: ...
    map_options: MapOptions
    backend: str
    fallback_warning: str
    memory_warning: str

class CameraIntrinsics:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: str
    k1: float
    k2: float
    p1: float
    p2: float
    k3: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class DepthOptions:
    downsample: int
    min_range: float
    max_range: float
    invalid_as_free: bool
    def __init__(self) -> None: ...

class _RecordingReader:
    @staticmethod
    def open(path: str, options: RecordingOptions) -> _RecordingReader: ...
    def next_scan(self) -> Optional[dict]: ...
    def next_cloud(self) -> Optional[dict]: ...
    progress: float
    is_bag: bool
    def report(self) -> dict: ...
    def warnings(self) -> list[str]: ...

def parse_byte_size(text: str) -> int: ...
def load_config(path: str, base: MapperConfig) -> Tuple[MapperConfig, list[str]]: ...
def _set_error_types(types: dict) -> None: ...
def _pose_matrix(translation: np.ndarray, quaternion_xyzw: np.ndarray) -> np.ndarray: ...
