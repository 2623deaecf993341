#!/usr/bin/env python3
"""Track a TUM-layout RGB-D sequence with ecvo from Python and plot the trajectory
against the ground truth.

    python track_tum.py testdata/synth_phone_320x180 --plot trajectory.png

The sequence folder needs rgb.txt, depth.txt and a camera.json (or --camera); a
groundtruth.txt, when there, gives the ATE and the plot's reference. Plotting needs
matplotlib (pip install matplotlib); without --plot it is never imported.
"""

import argparse
import importlib
import sys
import time
from typing import Any, List, Optional

import numpy as np
import numpy.typing as npt

import ecvo


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequence", help="sequence folder (TUM layout)")
    ap.add_argument("--camera", help="a camera.json overriding the folder's")
    ap.add_argument("--preset", default="pc", choices=["pc", "phone"])
    ap.add_argument("--mode", default="l2", choices=["naive", "l1", "l2"])
    ap.add_argument("--max-frames", type=int)
    ap.add_argument("--plot", metavar="PNG", help="write a top view of the trajectory here")
    ap.add_argument("--out", metavar="TXT", help="write the trajectory as a TUM file here")
    args = ap.parse_args(argv)

    seq = ecvo.read_sequence(args.sequence, camera=args.camera, max_frames=args.max_frames)
    push_s = []
    with ecvo.Tracker(seq.camera, preset=args.preset, mode=args.mode) as tracker:
        for timestamp, intensity, depth in seq:
            t0 = time.perf_counter()
            result = tracker.push(timestamp, intensity, depth)
            push_s.append(time.perf_counter() - t0)
            if result.state == "lost":
                print(f"{timestamp:.6f}: lost ({result.reason})", file=sys.stderr)
        est = tracker.trajectory()
        c = tracker.counters()
    print(
        f"{len(est)} frames, {c['motion_estimations']} motion estimations, "
        f"references {c['references']}, {c['lost_frames']} lost; "
        f"{1e3 * np.median(push_s):.2f} ms/frame (median)"
    )
    gt = seq.groundtruth
    aligned = est[:, 1:4]
    if gt is not None:
        a = ecvo.ate(gt, est)
        print(f"ATE RMSE {a['rmse'] * 1e3:.2f} mm over {a['count']} poses")
        # The estimate in the ground truth's frame, for the plot.
        r, t = a["alignment"][:3, :3], a["alignment"][:3, 3]
        aligned = est[:, 1:4] @ r.T + t
    if args.out:
        np.savetxt(args.out, est, fmt="%.17g", header="timestamp tx ty tz qx qy qz qw")
    if args.plot:
        plot(args.plot, aligned, gt, args.sequence)
    return 0


def plot(
    path: str,
    est_xyz: npt.NDArray[np.float64],
    gt: Optional[npt.NDArray[np.float64]],
    title: str,
) -> None:
    try:
        matplotlib: Any = importlib.import_module("matplotlib")
        matplotlib.use("Agg")
        plt: Any = importlib.import_module("matplotlib.pyplot")
    except ImportError:
        print("--plot needs matplotlib: pip install matplotlib", file=sys.stderr)
        sys.exit(2)
    fig, ax = plt.subplots(figsize=(6, 6))
    if gt is not None:
        ax.plot(gt[:, 1], gt[:, 3], "k--", lw=1, label="ground truth")
    ax.plot(est_xyz[:, 0], est_xyz[:, 2], "C0", lw=1.5, label="ecvo (aligned)" if gt is not None else "ecvo")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
