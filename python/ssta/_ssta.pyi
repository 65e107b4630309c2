"""Type stubs of the compiled module ssta._ssta (re-exported by `ssta`). Units and frames: W is
right-handed with z up, metres; yaw in radians; `_deg` degrees; `_m` metres (docs/python.md)."""

import os
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
#: True in a map-only build (cmake -DSSTA_MAP_ONLY=ON): only Map and Error are bound.
MAP_ONLY: bool
#: Rule names by id: classify's "rules" image holds these ids (docs/interfaces.md).
LABEL_RULES: Tuple[str, ...]

_Path = Union[str, os.PathLike]
_Array = npt.ArrayLike

class Error(ValueError):
    """Bad input to SSTA (ssta::Error): the message `ssta` on the command line prints."""

class ConfigSection:
    """One section of a Config; its keys as attributes (checked when set)."""
    def __getattr__(self, key: str) -> Any: ...
    def __setattr__(self, key: str, value: Any) -> None: ...
    def keys(self) -> list[str]: ...
    def to_dict(self) -> dict[str, Any]: ...

class Config:
    """Every SSTA setting (config/default.yaml), one ConfigSection per stage."""
    vehicle: ConfigSection
    rectification: ConfigSection
    stereo: ConfigSection
    triangulation: ConfigSection
    normals: ConfigSection
    segmentation: ConfigSection
    analysis: ConfigSection
    gravity: ConfigSection
    attitude: ConfigSection
    map: ConfigSection
    refinement: ConfigSection
    def __init__(self) -> None: ...
    @staticmethod
    def load(*files: _Path) -> Config: ...
    def to_yaml(self) -> str: ...
    def save(self, path: _Path) -> None: ...
    def to_dict(self) -> dict[str, dict[str, Any]]: ...
    def sections(self) -> list[str]: ...
    def copy(self) -> Config: ...

class CameraCalibration:
    """One camera (camN/sensor.yaml): pinhole [px], radial-tangential distortion, body_T_camera."""
    def __init__(
        self,
        width: int,
        height: int,
        K: _Array,
        distortion: Sequence[float] = (0.0, 0.0, 0.0, 0.0),
        body_T_camera: Optional[_Array] = None,
    ) -> None: ...
    @staticmethod
    def load(path: _Path) -> CameraCalibration: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def K(self) -> npt.NDArray[np.float64]: ...
    @property
    def distortion(self) -> list[float]: ...
    @property
    def body_T_camera(self) -> npt.NDArray[np.float64]: ...

class StereoCalibration:
    """The left (cam0) and right (cam1) cameras of a rig."""
    def __init__(self, left: CameraCalibration, right: CameraCalibration) -> None: ...
    @staticmethod
    def load(cam0_yaml: _Path, cam1_yaml: _Path) -> StereoCalibration: ...
    @property
    def left(self) -> CameraCalibration: ...
    @property
    def right(self) -> CameraCalibration: ...
    @property
    def is_rectified(self) -> bool: ...

class FramePipeline:
    """The per-frame chain for one rig and config, reused frame after frame."""
    def __init__(self, calibration: StereoCalibration, config: Optional[Config] = None) -> None: ...
    def classify(self, left: _Array, right: _Array, *, up: Optional[Sequence[float]] = None) -> dict[str, Any]: ...

def classify(
    left: _Array,
    right: _Array,
    calibration: StereoCalibration,
    config: Optional[Config] = None,
    *,
    up: Optional[Sequence[float]] = None,
) -> dict[str, Any]:
    """One stereo pair -> labels (uint8 class ids), segments (structured array), ground plane, ..."""

def build_map(
    sequence: _Path,
    map_path: _Path,
    config: Union[None, Config, _Path, Sequence[_Path]] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
    *,
    resume: bool = False,
    static_platform: bool = False,
    max_frames: int = 0,
    every: int = 1,
    strict: bool = False,
    sequential: bool = False,
    refine: bool = False,
    oracle_disparity: bool = False,
    oracle_labels: bool = False,
    allow_overlap: bool = False,
) -> dict[str, Any]:
    """Fuses a sequence into the map at map_path; returns the run summary (build-map --json)."""

class Map:
    """A read-only traversability map (.ot). W: z up, metres; yaw [rad]; classes 0..4."""
    @staticmethod
    def open(path: _Path) -> Map: ...
    @property
    def resolution_m(self) -> float: ...
    @property
    def file(self) -> str: ...
    @property
    def bounds(self) -> Optional[Tuple[float, float, float, float, float, float]]: ...
    @property
    def metadata(self) -> dict[str, Any]: ...
    def query(
        self,
        points: _Array,
        *,
        as_exported: bool = False,
        fill_holes: int = 5,
        local_ground_radius_m: float = 0.0,
        min_confidence: float = 0.0,
    ) -> np.ndarray:
        """N x 2 / N x 3 points [m] -> structured rows: x, y, z, class, cost, probability,
        slope_deg, step_m, observations, confidence, height_m, observed."""
    def footprints(
        self,
        poses: _Array,
        length_m: float,
        width_m: float,
        *,
        as_exported: bool = False,
        fill_holes: int = 5,
        local_ground_radius_m: float = 0.0,
        min_confidence: float = 0.0,
    ) -> np.ndarray:
        """N x 3 poses (x [m], y [m], yaw [rad]) -> structured rows: worst, mean_cost, max_cost,
        fraction_observed, cells, observed_cells, pitch_deg, roll_deg, attitude,
        attitude_heights, drivable_confidence, within_limits."""
    def path(
        self,
        vertices: _Array,
        width_m: float,
        *,
        as_exported: bool = False,
        fill_holes: int = 5,
        local_ground_radius_m: float = 0.0,
        min_confidence: float = 0.0,
    ) -> dict[str, Any]:
        """N x 2 vertices [m] and a corridor width [m] -> samples and the verdict."""
    def project(
        self,
        region: Optional[Sequence[float]] = None,
        resolution_m: Optional[float] = None,
        *,
        as_exported: bool = False,
        fill_holes: int = 5,
        local_ground_radius_m: float = 0.0,
        headings: int = 0,
        heading_footprint: Sequence[float] = (1.0, 0.6),
        min_confidence: float = 0.0,
    ) -> dict[str, Any]:
        """The top surface as H x W arrays (class, cost, height_m, slope_deg, step_m,
        surface_z_m), origin, extent; with headings=N, cost_heading (H x W x N) and headings_deg."""
    def diff(
        self,
        other: Map,
        *,
        out: Optional[_Path] = None,
        min_confidence: float = 0.6,
        slope_noise_deg: float = 20.0,
        step_noise_m: float = 0.10,
        boundary_shift_columns: int = 1,
    ) -> dict[str, Any]:
        """What changed from this map to `other`: H x W change, class_a/b, confidence_a/b; counts."""
