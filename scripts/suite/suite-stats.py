#!/usr/bin/env python3
"""Measures synthetic streams as written: peak and mean frame-to-frame linear (m/s) and
angular (deg/s) speed from groundtruth.txt, and, from the depth PNGs, the mean valid depth and
the valid-depth fraction (mean and worst frame). Needs numpy and cv2 (e.g. the venv
that scripts/peers/run-peers.sh sets up).

    suite-stats.py SEQ...   (or: suite-stats.py $(cat OUTDIR/suite.txt))
"""

import json
import os
import sys

import cv2
import numpy as np


def rot(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def main():
    print("| stream | frames | peak (mean) m/s | peak (mean) deg/s | mean depth (m) "
          "| valid depth mean / min |")
    print("|---|---|---|---|---|---|")
    for seq in sys.argv[1:]:
        seq = seq.rstrip("/")
        rows = [list(map(float, line.split())) for line in open(os.path.join(seq, "groundtruth.txt"))
                if line.strip() and not line.startswith("#")]
        v = w = 0.0
        vs, ws = [], []
        for a, b in zip(rows, rows[1:]):
            dt = b[0] - a[0]
            ra, rb = rot(a[4:8]), rot(b[4:8])
            vs.append(np.linalg.norm(np.subtract(b[1:4], a[1:4])) / dt)
            c = np.clip((np.trace(ra.T @ rb) - 1) / 2, -1, 1)
            ws.append(np.degrees(np.arccos(c)) / dt)
        v, w = max(vs), max(ws)
        scale = json.load(open(os.path.join(seq, "camera.json")))["depth_scale"]
        depth_files = [line.split()[1] for line in open(os.path.join(seq, "depth.txt"))
                       if line.strip() and not line.startswith("#")]
        total, count, fracs = 0.0, 0, []
        for name in depth_files:
            d = cv2.imread(os.path.join(seq, name), cv2.IMREAD_UNCHANGED)
            valid = d > 0
            total += float(d[valid].sum()) / scale
            count += int(valid.sum())
            fracs.append(valid.mean())
        print(f"| {os.path.basename(seq)} | {len(rows)} | {v:.3f} ({np.mean(vs):.3f}) | "
              f"{w:.1f} ({np.mean(ws):.1f}) | "
              f"{total / count:.2f} | {np.mean(fracs):.3f} / {np.min(fracs):.3f} |")


if __name__ == "__main__":
    main()
