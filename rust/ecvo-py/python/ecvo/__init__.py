"""ecvo: RGB-D camera tracking from numpy.

The frame-to-frame tracker of An, Lee, Jeong and Ihm, "Tracking an RGB-D Camera on
Mobile Devices Using an Improved Frame-to-Frame Pose Estimation Method" (WACV 2018),
with multi-level pose error correction, written in Rust.

    import ecvo
    seq = ecvo.read_sequence("testdata/synth_phone_320x180")
    with ecvo.Tracker(seq.camera, preset="pc", mode="l2") as tracker:
        for timestamp, intensity, depth in seq:
            r = tracker.push(timestamp, intensity, depth)  # r.pose, r.state, r.information
        print(ecvo.ate(seq.groundtruth, tracker.trajectory())["rmse"])

or, exactly as ``ecvo run`` tracks it (bit for bit the same poses):

    result = ecvo.run_sequence("testdata/synth_phone_320x180")
    print(result["ate"]["rmse"], result["counters"])

Trajectories are ``(N, 8)`` float64 arrays of TUM rows ``[t, tx, ty, tz, qx, qy,
qz, qw]`` (camera-to-world; the world is the first camera); poses are 4x4 arrays.
"""

import os as _os

import numpy as _np

from . import _ecvo
from ._ecvo import Camera, FrameResult, Sequence, Tracker, read_sequence, run_sequence

__version__ = _ecvo.__version__
__all__ = [
    "Camera",
    "FrameResult",
    "Sequence",
    "Tracker",
    "ate",
    "read_sequence",
    "run_sequence",
]


def ate(gt, est, max_dt=0.01):
    """Absolute trajectory error of ``est`` against ``gt``, as ``ecvo eval``, TUM's
    ``evaluate_ate.py`` and ``evo_ape tum GT EST -a`` compute it.

    ``gt`` and ``est`` are TUM trajectory files (paths) or ``(N, 8)`` arrays of TUM
    rows ``[t, tx, ty, tz, qx, qy, qz, qw]`` (anything ``numpy.asarray`` turns into
    one, such as ``Tracker.trajectory()`` or ``Sequence.groundtruth``). Poses are
    associated by timestamp (nearest, within ``max_dt`` seconds: 0.01, evo's
    ``t_max_diff`` default; ``ecvo eval`` and ``run_sequence`` use TUM's 0.02), the estimate is
    rigidly aligned to the ground truth (no scale), and the statistics of the position
    errors are returned as a dict: ``rmse``, ``mean``, ``median``, ``std``, ``min``,
    ``max`` (metres), ``count`` (pairs), ``alignment`` (4x4, ``gt ~ alignment @ est``)
    and ``errors`` (per pair). Fewer than 3 pairs is a ValueError.
    """
    return _ecvo.ate(_trajectory_arg(gt, "gt"), _trajectory_arg(est, "est"), max_dt)


def _trajectory_arg(x, name):
    if isinstance(x, (str, _os.PathLike)):
        return x
    try:
        return _np.ascontiguousarray(x, dtype=_np.float64)
    except (TypeError, ValueError) as e:
        raise TypeError(
            f"{name} must be a TUM trajectory file path or an (N, 8) array of rows "
            f"[t, tx, ty, tz, qx, qy, qz, qw], got {type(x).__name__}"
        ) from e
