#!/usr/bin/env python3
"""Track a sequence from the inputs an Open3D / OpenCV user has (BGR colour, float32
depth in metres with NaN for no measurement) and keep what a pose graph needs from
each frame: the pose, the information matrix of its registration, and why a frame
was lost.

    python inputs_and_quality.py testdata/synth_phone_320x180 --max-frames 30
"""

import argparse
import sys
from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

import ecvo

Edge = Tuple[int, int, npt.NDArray[np.float64], npt.NDArray[np.float64]]


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequence")
    ap.add_argument("--max-frames", type=int)
    args = ap.parse_args(argv)

    seq = ecvo.read_sequence(args.sequence, max_frames=args.max_frames, colour=True)
    camera = seq.camera
    edges: List[Edge] = []  # (from, to, relative pose, information)
    last_pose: Optional[npt.NDArray[np.float64]] = None
    with ecvo.Tracker(camera) as tracker:
        for timestamp, rgb, raw in seq:
            bgr = rgb[..., ::-1]  # as cv2.imread gives it
            metres = raw.astype(np.float32) / np.float32(camera.depth_scale)
            metres[raw == 0] = np.nan
            r = tracker.push(timestamp, bgr, metres, channels="bgr")
            if r.state == "lost":
                print(f"frame {r.index}: lost ({r.reason})", file=sys.stderr)
            elif last_pose is not None:
                relative = np.linalg.inv(last_pose) @ r.pose
                edges.append((r.index - 1, r.index, relative, r.information))
            last_pose = r.pose
    sigma_mm = [1e3 * float(np.sqrt(np.linalg.inv(info)[3:, 3:].diagonal().max())) for *_, info in edges]
    print(f"{len(tracker)} frames, {len(edges)} odometry edges, worst translation sigma {max(sigma_mm):.3f} mm")
    if seq.groundtruth is not None:
        print(f"ATE RMSE {ecvo.ate(seq.groundtruth, tracker.trajectory())['rmse'] * 1e3:.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
