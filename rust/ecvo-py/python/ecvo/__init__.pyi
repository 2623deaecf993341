import os
from typing import Union

import numpy as np
import numpy.typing as npt

from ._ecvo import _Ate
from ._ecvo import (
    Camera as Camera,
    FrameResult as FrameResult,
    Sequence as Sequence,
    Tracker as Tracker,
    read_sequence as read_sequence,
    run_sequence as run_sequence,
)

__version__: str
__all__ = ["Camera", "FrameResult", "Sequence", "Tracker", "ate", "read_sequence", "run_sequence"]

_Trajectory = Union[str, os.PathLike, npt.ArrayLike]

def ate(gt: _Trajectory, est: _Trajectory, max_dt: float = 0.01) -> _Ate:
    """Absolute trajectory error of ``est`` against ``gt`` as ``ecvo eval``, TUM's
    ``evaluate_ate.py`` and ``evo_ape tum GT EST -a`` compute it: TUM files or
    (N, 8) arrays of rows [t, tx, ty, tz, qx, qy, qz, qw]; poses associated by
    timestamp within ``max_dt`` s (evo's default 0.01; ``ecvo eval`` uses TUM's 0.02),
    rigid alignment, statistics in metres."""
