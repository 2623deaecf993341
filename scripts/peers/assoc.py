"""Pairing of a TUM sequence's colour and depth images, as ecvo's reader and TUM's
associate.py do: nearest stamps within MAX_DT seconds, closest pairs first, each image
once. Standard library only (peers.py and scripts/profile/insn-aarch64.sh use it)."""

import bisect
import os

MAX_DT = 0.02


def read_list(path):
    """(stamp, relative path) pairs of a TUM rgb.txt / depth.txt, '#' lines skipped."""
    out = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            parts = line.split()
            out.append((float(parts[0]), parts[1]))
    return out


def associate(rgb, depth, max_dt=MAX_DT):
    """Pairs (rgb, depth) entries whose stamps differ by less than max_dt: closest
    pairs first, each entry used at most once; result sorted by colour stamp."""
    dstamps = [d[0] for d in depth]
    cands = []
    for i, (t, _) in enumerate(rgb):
        lo = bisect.bisect_left(dstamps, t - max_dt)
        hi = bisect.bisect_right(dstamps, t + max_dt)
        for j in range(lo, hi):
            dt = abs(dstamps[j] - t)
            if dt < max_dt:
                cands.append((dt, i, j))
    cands.sort()
    used_r, used_d, pairs = set(), set(), []
    for _, i, j in cands:
        if i in used_r or j in used_d:
            continue
        used_r.add(i)
        used_d.add(j)
        pairs.append((rgb[i], depth[j]))
    pairs.sort(key=lambda p: p[0][0])
    return pairs


def sequence_pairs(seq):
    """The associated (rgb, depth) pairs of the TUM-layout folder seq."""
    rgb = sorted(read_list(os.path.join(seq, "rgb.txt")))
    depth = sorted(read_list(os.path.join(seq, "depth.txt")))
    return associate(rgb, depth)
