"""Type stubs of ecvo's native module (rust/ecvo-py/src)."""

import os
import pathlib
from typing import List, Literal, Optional, Tuple, TypedDict, Union, final

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike]
_State = Literal["initialising", "tracking", "lost"]
_Preset = Literal["pc", "phone"]
_Mode = Literal["naive", "l1", "l2"]

__all__ = [
    "Camera",
    "Tracker",
    "Sequence",
    "SequenceIterator",
    "read_sequence",
    "run_sequence",
    "ate",
    "_engine_push_times",
    "simd_path",
    "__version__",
]
__version__: str
simd_path: str
"""Which kernel copies the engine runs here (the same poses on every path)."""

@final
class Camera:
    """Pinhole intrinsics and depth units of an RGB-D stream whose intensity is
    registered to its depth. ``fy`` may be negative (a flipped y axis);
    ``depth_scale`` is raw depth units per metre (5000 for TUM, 1000 for mm).
    Non-finite or unusable values are a ValueError naming the field."""

    def __new__(
        cls,
        width: int,
        height: int,
        fx: float,
        fy: float,
        cx: float,
        cy: float,
        depth_scale: float,
    ) -> "Camera": ...
    @staticmethod
    def from_json(path: _Path) -> "Camera":
        """Reads a ``camera.json`` (the file ecvo sequences carry)."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    @property
    def depth_scale(self) -> float: ...
    def intrinsic_matrix(self) -> npt.NDArray[np.float64]:
        """The 3x3 intrinsic matrix K."""
    def __eq__(self, value: object, /) -> bool: ...

class _Counters(TypedDict):
    """The tracker's counters: the paper's Table 1 and what went wrong."""

    frames: int
    motion_estimations: int
    references: List[int]
    lost_frames: int
    failed_corrections: int
    rejected_corrections: int
    stale_references: int
    recovered_frames: int
    predicted_starts: int
    reanchors: int
    implausible_motions: int
    refinements: int
    refused_refinements: int
    spread_jumps: int

class _Ate(TypedDict):
    """Absolute trajectory error (metres) after rigid alignment of the estimate."""

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    count: int
    alignment: npt.NDArray[np.float64]
    errors: npt.NDArray[np.float64]

class _RunResult(TypedDict):
    trajectory: npt.NDArray[np.float64]
    """(N, 8) TUM rows [t, tx, ty, tz, qx, qy, qz, qw], camera to world."""
    poses: npt.NDArray[np.float64]
    """(N, 4, 4) camera-to-world poses."""
    states: List[_State]
    lost_frame_indices: List[int]
    counters: _Counters
    skipped_frames: int
    """Frames not tracked: bit-identical repeats and non-increasing timestamps."""
    ate: Optional[_Ate]
    """Against the sequence's ground truth; None without one."""
    camera: Camera
    wall_time_s: float
    threads: int

@final
class Tracker:
    """Frame-to-frame RGB-D tracking with multi-level pose error correction
    (An et al., WACV 2018), frame by frame.

    ``preset`` picks the paper's thresholds and filter angles (``"pc"``: Table 1,
    ``"phone"``: Table 2); ``mode`` which correction levels run (``"naive"``,
    ``"l1"``, ``"l2"``). ``threads`` sizes a private thread pool for the engine's
    inner loops (None: the process-wide pool). The other settings are the flags of
    ``ecvo run`` with underscores: ``levels`` ("30mm:7deg,120mm:12deg"),
    ``bilateral``, ``normal_filter``, ``contour_filter`` (bools, default True),
    ``paper`` (bool), ``schedule``, ``point_budget`` (str), ``weighting``
    ("scalar", "bivariate", "hybrid"), ``depth_noise`` ("constant", "quadratic", "fitted": the default),
    ``prior`` ("identity", "velocity"), ``max_correction_distance``,
    ``max_fine_depth_weight``, ``min_predicted_decrease``, ``min_update_px``
    (floats), ``scale_passes``, ``refine_every`` (ints), ``corrections`` ("fuse",
    "replace"), ``tracking`` ("chain", "keyframe"), ``keyframe_overlap``, ``keyframe_spread`` (floats). An unknown keyword is a TypeError, a bad value a ValueError.

    One tracker is used by one thread at a time; several trackers run in parallel on
    several threads (the GIL is released while a frame is tracked).
    """

    def __new__(
        cls,
        camera: Camera,
        preset: _Preset = "pc",
        mode: _Mode = "l2",
        threads: Optional[int] = None,
        **settings: object,
    ) -> "Tracker": ...
    def push(
        self,
        timestamp: float,
        intensity: npt.NDArray[np.uint8],
        depth: npt.NDArray[np.uint16],
    ) -> Tuple[npt.NDArray[np.float64], _State]:
        """Tracks one frame: ``intensity`` (uint8) and raw ``depth`` (uint16, 0 = no
        measurement) are (height, width) arrays; C-contiguous ones are read in place,
        others copied once. Timestamps (seconds) must increase. Returns the
        camera-to-world pose (4x4; the world is the first camera; a lost frame keeps
        the last good pose) and the state. A wrong type or dtype is a TypeError, a
        wrong shape or timestamp a ValueError. The arrays must not be written by
        another thread during the call."""
    def set_intrinsics(self, camera: Camera) -> None:
        """New intrinsics of the same image size (a zoom) for the next frames."""
    def trajectory(self) -> npt.NDArray[np.float64]:
        """The poses so far, (N, 8) TUM rows [t, tx, ty, tz, qx, qy, qz, qw]."""
    def poses(self) -> npt.NDArray[np.float64]:
        """The poses so far, (N, 4, 4)."""
    def timestamps(self) -> npt.NDArray[np.float64]: ...
    def states(self) -> List[_State]: ...
    def counters(self) -> _Counters: ...
    @property
    def state(self) -> _State: ...
    @property
    def camera(self) -> Camera: ...
    def __len__(self) -> int: ...
    @property
    def _last_engine_s(self) -> float:
        """Seconds Odometry::push (timed in Rust) took over the last push."""

@final
class Sequence:
    """A recorded RGB-D sequence; ``seq[i]`` decodes frame ``i`` as ``(timestamp,
    intensity, depth)`` (uint8 and uint16 (height, width) arrays); iterating yields
    every frame in order."""

    def __len__(self) -> int: ...
    def __getitem__(
        self, key: int, /
    ) -> Tuple[float, npt.NDArray[np.uint8], npt.NDArray[np.uint16]]: ...
    def __iter__(self) -> "SequenceIterator": ...
    @property
    def camera(self) -> Camera: ...
    @property
    def timestamps(self) -> npt.NDArray[np.float64]: ...
    @property
    def groundtruth(self) -> Optional[npt.NDArray[np.float64]]:
        """(N, 8) TUM rows, or None."""
    @property
    def path(self) -> pathlib.Path: ...

@final
class SequenceIterator:
    def __iter__(self) -> "SequenceIterator": ...
    def __next__(
        self,
    ) -> Tuple[float, npt.NDArray[np.uint8], npt.NDArray[np.uint16]]: ...

def read_sequence(
    path: _Path,
    camera: Union[Camera, _Path, None] = None,
    frame_step: int = 1,
    max_frames: Optional[int] = None,
) -> Sequence:
    """Opens a TUM-layout (with camera.json) or ICL-NUIM sequence folder. ``camera``
    (a Camera or a camera.json path) overrides the folder's; ``frame_step`` keeps
    frames 0, n, 2n, ...; ``max_frames`` the first so many. A missing folder is a
    FileNotFoundError, a malformed one a ValueError."""

def run_sequence(
    path: _Path,
    preset: _Preset = "pc",
    mode: _Mode = "l2",
    camera: Union[Camera, _Path, None] = None,
    max_frames: Optional[int] = None,
    threads: int = 2,
    frame_step: int = 1,
    **settings: object,
) -> _RunResult:
    """Tracks a recorded sequence exactly as ``ecvo run`` does (the same settings
    give bit for bit the same poses): frames decoded ahead, the filter and tracker
    stages on ``threads`` threads; bit-identical repeated frames and non-increasing
    timestamps are skipped. Settings as for :class:`Tracker`."""

def ate(
    gt: Union[_Path, npt.NDArray[np.float64]],
    est: Union[_Path, npt.NDArray[np.float64]],
    max_dt: float = ...,
) -> _Ate:
    """ATE of ``est`` against ``gt`` (TUM files or (N, 8) arrays); see ecvo.ate."""

def _engine_push_times(
    camera: Camera,
    frames: List[Tuple[float, npt.NDArray[np.uint8], npt.NDArray[np.uint16]]],
    preset: _Preset = "pc",
    mode: _Mode = "l2",
    threads: Optional[int] = None,
    **settings: object,
) -> List[float]:
    """Seconds per frame of the Rust engine's own Odometry::push on these frames
    (for scripts/python/bench_push.py)."""
