"""Type stubs of ecvo's native module (rust/ecvo-py/src)."""

import os
import pathlib
from typing import Any, Dict, Iterator, List, Literal, Optional, Tuple, TypedDict, Union, final, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike]
_State = Literal["initialising", "tracking", "lost"]
_Preset = Literal["pc", "phone"]
_Mode = Literal["naive", "l1", "l2"]
_Channels = Literal["rgb", "bgr"]
_Reason = Literal[
    "no_valid_depth",
    "too_few_points",
    "degenerate",
    "diverged",
    "inconsistent",
    "implausible_speed",
    "spread_jump",
]
_Frame = Tuple[float, npt.NDArray[np.uint8], npt.NDArray[np.uint16]]

__all__ = [
    "Camera",
    "FrameResult",
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
    registered to its depth: Camera(width, height, fx, fy, cx, cy, depth_scale).
    fy may be negative (a flipped y axis); depth_scale is raw depth units per metre
    (5000 for TUM, 1000 for millimetres). Non-finite or unusable values are a
    ValueError naming the field. Cameras compare equal field by field, hash alike
    when equal, and pickle."""

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
        """Reads a camera.json (the file ecvo sequences carry)."""
    @staticmethod
    def from_matrix(
        k: npt.ArrayLike, width: int, height: int, depth_scale: float
    ) -> "Camera":
        """A camera from the 3x3 intrinsic matrix K ([[fx, 0, cx], [0, fy, cy], [0, 0,
        1]]; skew must be 0), the image size in pixels and the raw depth units per
        metre. Anything else is a ValueError."""
    @property
    def width(self) -> int:
        """Image width, pixels."""
    @property
    def height(self) -> int:
        """Image height, pixels."""
    @property
    def fx(self) -> float:
        """Focal length along x, pixels."""
    @property
    def fy(self) -> float:
        """Focal length along y, pixels (negative: a flipped y axis)."""
    @property
    def cx(self) -> float:
        """Principal point x, pixels."""
    @property
    def cy(self) -> float:
        """Principal point y, pixels."""
    @property
    def depth_scale(self) -> float:
        """Raw depth units per metre."""
    def intrinsic_matrix(self) -> npt.NDArray[np.float64]:
        """The 3x3 intrinsic matrix K (float64)."""
    def to_dict(self) -> Dict[str, Union[int, float]]:
        """The fields as a dict with the keys of camera.json and of the constructor:
        Camera(**camera.to_dict()) == camera."""
    def __eq__(self, value: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> Tuple[Any, Tuple[int, int, float, float, float, float, float]]: ...

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
    keyframe_fallbacks: int
    overlap_keyframes: int
    keyframe_spread_refusals: int
    keyframe_fusions: int
    noise_refits: int
    imu: _ImuCounters

class _ImuCounters(TypedDict):
    """What became of the gyroscope's samples (Tracker.push_imu) and priors."""

    samples: int
    refused: int
    dropped: int
    priors: int
    late: int
    missing: int
    bias_updates: int
    bias_outliers: int
    depth_turned: int
    depth_unturned: int

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
class FrameResult:
    """What Tracker.push returns for one frame: the pose and the state (it unpacks as
    (pose, state)), and the quality of the registration the pose came from."""

    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """Camera-to-world pose (4x4 float64; the world is the first camera); a lost
        frame keeps the last good pose."""
    @property
    def state(self) -> _State:
        """"tracking" or "lost"."""
    @property
    def timestamp(self) -> float:
        """The frame's timestamp (seconds)."""
    @property
    def index(self) -> int:
        """The frame's position in the stream, from 0."""
    @property
    def information(self) -> npt.NDArray[np.float64]:
        """6x6 information matrix (float64, symmetric) of the registration the pose came
        from: the normal equations' JᵀWJ at the solution, whitened by the fitted
        residual scale (units of the noise), in the tangent space of the motion from
        the frame registered against (the previous frame, the keyframe or the
        reference a recovery used) to this one, perturbed on the left, ordered
        (rx, ry, rz, tx, ty, tz) as Open3D's compute_rgbd_odometry(previous, current)
        returns it. Its inverse approximates the motion's covariance (radians,
        metres). Zeros on the first frame and on lost frames (no constraint)."""
    @property
    def residual_scale(self) -> Optional[npt.NDArray[np.float64]]:
        """The fitted residual scale Σ of that registration, 2x2 float64 over
        (intensity in [0, 1], depth residual times its gain), or None without one."""
    @property
    def valid_points(self) -> int:
        """Template points that landed on valid pixels at the finest step."""
    @property
    def template_points(self) -> int:
        """Template points of the finest step."""
    @property
    def point_fraction(self) -> float:
        """valid_points / template_points: the fraction of the template used (0.0
        without a registration)."""
    @property
    def reason(self) -> Optional[_Reason]:
        """Why the frame was lost ("no_valid_depth", "too_few_points", "degenerate",
        "diverged", "inconsistent", "implausible_speed", "spread_jump"), None unless
        lost."""
    @property
    def recovered(self) -> bool:
        """[A] failed and the frame registered against a kept reference instead."""
    @property
    def reanchored(self) -> bool:
        """After too many lost frames tracking started afresh at this frame."""
    @property
    def reference_levels(self) -> int:
        """The frame became the reference at levels 1..=reference_levels (0: none)."""
    @property
    def motion_estimations(self) -> int:
        """MOTION calls spent on this frame."""
    @property
    def refused_corrections(self) -> int:
        """Corrections of this frame that failed or were rejected."""
    def __len__(self) -> int: ...
    @overload
    def __getitem__(self, index: Literal[0, -2]) -> npt.NDArray[np.float64]: ...
    @overload
    def __getitem__(self, index: Literal[1, -1]) -> _State: ...
    def __iter__(self) -> Iterator[Any]: ...

@final
class Tracker:
    """Frame-to-frame RGB-D tracking with multi-level pose error correction (An et
    al., WACV 2018), frame by frame: Tracker(camera, preset="pc", mode="l2",
    threads=None, **settings).

    preset picks the paper's thresholds and filter angles ("pc": Table 1, "phone":
    Table 2); mode which correction levels run ("naive", "l1", "l2"). threads sizes
    a private thread pool for the engine's inner loops (None: the process-wide
    pool). The other settings are the flags of ecvo run with underscores: levels
    ("30mm:7deg,120mm:12deg"), bilateral, normal_filter, contour_filter (bools,
    default True), paper (bool), schedule, point_budget (str), weighting ("scalar",
    "bivariate", "hybrid"), depth_noise ("constant", "quadratic", "fitted": the
    default), prior ("identity", "velocity"), max_correction_distance,
    max_fine_depth_weight, min_predicted_decrease, min_update_px (floats),
    scale_passes, refine_every (ints), corrections ("fuse", "replace"), tracking
    ("keyframe": the default, "chain": the paper's frame-to-frame chain),
    keyframe_overlap, keyframe_spread (floats), lookup_depth ("bilateral": the
    default, "raw", "filtered"), keyframe_fuse_every (int), memory_budget
    (int, bytes: the engine refuses a configuration that needs more). With a
    gyroscope (push_imu): imu_rotation (3x3 rotation taking IMU-frame vectors into
    the camera frame, x right, y down, z forward; default the identity),
    imu_time_offset (seconds added to an IMU timestamp to put it on the frames'
    clock; default 0), gyro_noise_density (rad/s/√Hz), gyro_bias_random_walk
    (rad/s/√s), imu_fusion (bool, default False: also fuse the gyro's rotation
    into each believed registration) and imu_prior_term (bool, default True: the
    gyro's rotation is also a prior term in the registration's normal equations),
    imu_depth_time (bool, default True: a depth pushed with its own depth_timestamp
    is turned to the intensity's time by the gyro). An
    unknown keyword is a TypeError, a bad value a ValueError.

    One tracker serves one thread at a time (another thread calling it meanwhile
    gets a RuntimeError saying so); several trackers run in parallel on several
    threads (the GIL is released while a frame is tracked). close() or a with block
    frees its memory."""

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
        intensity: Any,
        depth: Any = None,
        channels: _Channels = "rgb",
        initial_guess: Optional[npt.ArrayLike] = None,
        rotation_guess: Optional[npt.ArrayLike] = None,
        depth_timestamp: Optional[float] = None,
    ) -> FrameResult:
        """Tracks one frame and returns its FrameResult (which unpacks as (pose,
        state)). Timestamps (seconds) must increase.

        intensity: grey (height, width) uint8; colour (height, width, 3 or 4) uint8 in
        the channel order channels ("rgb" or "bgr"; alpha ignored), converted to grey
        as 0.299 R + 0.587 G + 0.114 B rounded (as read_sequence); or grey float32 /
        float64 in [0, 1] (Open3D's RGBDImage.color). depth: uint16 raw units (0: no
        measurement) or float32 / float64 metres (NaN or 0: no measurement), rounded
        to the camera's units (1 / depth_scale m; exact for metres that came from raw
        / depth_scale). Any object numpy.asarray takes works (the buffer protocol:
        open3d.geometry.Image, memoryview); an object with .color and .depth (an
        Open3D RGBDImage) may stand for both planes. A masked array's masked pixels
        have no depth. C-contiguous uint8 grey and uint16 depth are read in place,
        everything else converted once into a reused buffer; the arrays must not be
        written by another thread during the call.

        initial_guess: a 4x4 camera-to-world pose guess for this frame (as the poses
        returned), or rotation_guess: a 3x3 rotation of this camera relative to the
        previous frame's (a gyroscope's), the translation then predicted from the
        velocity. Registration starts from the identity and from the guess, and the
        better start wins at the coarsest level; ignored on the first frame.

        depth_timestamp: when the depth image was taken (seconds, the frames' clock),
        if not with the intensity: with gyroscope samples pushed that cover the two
        times, the depth is turned to the intensity's time by the gyro's rotation
        between them (imu_depth_time=False turns this off).

        A wrong type or dtype is a TypeError; a wrong shape, an out-of-range value,
        a non-increasing timestamp or a closed tracker a ValueError."""
    def push_imu(self, timestamps: npt.ArrayLike, rates: npt.ArrayLike) -> None:
        """Gyroscope samples for the frames pushed after this call: timestamps (N,)
        seconds on the IMU's clock, rates (N, 3) rad/s in the IMU's frame, in time
        order. Each frame's registration then starts from the gyro's rotation since
        the previous frame (less its bias, estimated as it goes) besides the
        identity. A sample not after the last one taken is dropped and counted
        (counters()["imu"]["refused"]); samples that do not cover a frame leave it
        tracked without them (counted "late" or "missing"), never an error. A
        non-finite value refuses the whole batch with a ValueError; a wrong shape
        is a ValueError."""
    def set_intrinsics(self, camera: Camera) -> None:
        """New intrinsics of the same image size (a zoom) for the frames pushed from
        now on."""
    def reset(self) -> None:
        """Forgets every frame: the next one starts a new trajectory at the identity,
        with the same settings and the current camera. Reopens a closed tracker."""
    def close(self) -> None:
        """Frees the engine's memory; pushing afterwards is a ValueError. The
        trajectory stays readable. Idempotent."""
    @property
    def closed(self) -> bool:
        """True once closed."""
    def __enter__(self) -> "Tracker": ...
    def __exit__(self, *args: object) -> bool: ...
    def trajectory(self) -> npt.NDArray[np.float64]:
        """The poses so far as an (N, 8) float64 array of TUM rows [t, tx, ty, tz, qx,
        qy, qz, qw]."""
    def poses(self) -> npt.NDArray[np.float64]:
        """The poses so far as an (N, 4, 4) float64 array."""
    def timestamps(self) -> npt.NDArray[np.float64]:
        """The timestamps so far (seconds)."""
    def states(self) -> List[_State]:
        """Every frame's state so far."""
    def counters(self) -> _Counters:
        """The tracker's counters (the paper's Table 1 and what went wrong)."""
    @property
    def state(self) -> _State:
        """The state after the last frame ("initialising" before the first)."""
    @property
    def camera(self) -> Camera:
        """The camera of the frames pushed next."""
    def __len__(self) -> int: ...
    @property
    def _last_engine_s(self) -> float:
        """Seconds the engine itself (Odometry::push, timed in Rust) took over the last
        push: what Tracker.push costs beyond it is the binding's
        (scripts/python/bench_push.py)."""

@final
class Sequence:
    """A recorded RGB-D sequence (read_sequence): seq[i] decodes frame i as
    (timestamp, intensity, depth): intensity (height, width) uint8 grey, or (height,
    width, 3) uint8 RGB when opened with colour=True; depth (height, width) uint16
    raw units. seq[a:b:c] is a Sequence of those frames; iterating yields every
    frame in order, decoded when reached."""

    def __len__(self) -> int: ...
    @overload
    def __getitem__(self, key: int, /) -> _Frame: ...
    @overload
    def __getitem__(self, key: slice, /) -> "Sequence": ...
    def __iter__(self) -> "SequenceIterator": ...
    @property
    def camera(self) -> Camera:
        """The sequence's camera."""
    @property
    def timestamps(self) -> npt.NDArray[np.float64]:
        """The frames' timestamps (seconds)."""
    @property
    def groundtruth(self) -> Optional[npt.NDArray[np.float64]]:
        """The whole recording's ground truth as (N, 8) TUM rows, or None."""
    @property
    def path(self) -> pathlib.Path:
        """The sequence folder."""
    @property
    def colour(self) -> bool:
        """Whether frames decode as colour."""

@final
class SequenceIterator:
    def __iter__(self) -> "SequenceIterator": ...
    def __next__(self) -> _Frame: ...

def read_sequence(
    path: _Path,
    camera: Union[Camera, _Path, None] = None,
    frame_step: int = 1,
    max_frames: Optional[int] = None,
    colour: bool = False,
) -> Sequence:
    """Opens a TUM-layout (with camera.json) or ICL-NUIM sequence folder. camera (a
    Camera or a camera.json path) overrides the folder's; frame_step keeps frames 0,
    n, 2n, ...; max_frames the first so many; colour=True decodes intensity as
    (height, width, 3) RGB. A missing folder is a FileNotFoundError, a malformed one
    a ValueError."""

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
    timestamps are skipped. Settings as for :class:`Tracker`, and imu: None (the
    folder's imu.txt if it has one, as ecvo run), False (none, as --no-imu) or the
    path of an imu.txt (as --imu), its calibration from the camera.json beside it
    or the folder's."""

def ate(
    gt: Union[_Path, npt.NDArray[np.float64]],
    est: Union[_Path, npt.NDArray[np.float64]],
    max_dt: float = 0.01,
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
