#!/usr/bin/env python3
"""Per-frame cost of ecvo.Tracker.push from Python against the Rust engine's own
(ecvo_core::Odometry::push timed in Rust) on the same frames, already in memory.

    python scripts/python/bench_push.py testdata/synth_phone_320x180 --rounds 7

Both sides run the same build of the engine (the installed ecvo package) with the
same settings and thread pool; rounds alternate between them. The sequence is played
forward, backward and forward again (--laps) with increasing timestamps, a
continuous path. Prints median, mean and p95 per frame (ms) for each side and the
ratio Python / Rust of each figure.
"""

import argparse
import json
import time

import numpy as np

import ecvo
from ecvo import _ecvo


def stats(x):
    x = np.asarray(x) * 1e3
    return {"median": float(np.median(x)), "mean": float(x.mean()), "p95": float(np.percentile(x, 95))}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequence")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--laps", type=int, default=3)
    ap.add_argument("--max-frames", type=int)
    ap.add_argument("--threads", type=int, default=None, help="engine pool size (default: rayon's global pool)")
    ap.add_argument("--preset", default="pc")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    seq = ecvo.read_sequence(args.sequence, max_frames=args.max_frames)
    base = [(i, d) for _, i, d in seq]
    path = []
    for lap in range(args.laps):
        path += base if lap % 2 == 0 else base[::-1]
    frames = [(k / 30.0, i, d) for k, (i, d) in enumerate(path)]
    settings = dict(preset=args.preset, threads=args.threads)

    py_times, rust_times = [], []
    for r in range(args.rounds + 1):
        tracker = ecvo.Tracker(seq.camera, **settings)
        times = []
        for t, i, d in frames:
            t0 = time.perf_counter()
            tracker.push(t, i, d)
            times.append(time.perf_counter() - t0)
        engine = _ecvo._engine_push_times(seq.camera, frames, **settings)
        if r > 0:  # round 0 warms both up
            py_times += times
            rust_times += engine
    py, rust = stats(py_times), stats(rust_times)
    ratio = {k: py[k] / rust[k] for k in py}
    result = {
        "sequence": str(args.sequence),
        "frames_per_round": len(frames),
        "rounds": args.rounds,
        "threads": args.threads,
        "simd": _ecvo.simd_path,
        "python_ms": py,
        "rust_ms": rust,
        "ratio": ratio,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"{args.sequence}: {len(frames)} frames x {args.rounds} rounds, threads {args.threads}")
        for name, s in (("Tracker.push (Python)", py), ("Odometry::push (Rust)", rust)):
            print(f"  {name:22s} median {s['median']:.3f}  mean {s['mean']:.3f}  p95 {s['p95']:.3f} ms")
        print(f"  ratio Python/Rust      median {ratio['median']:.3f}  mean {ratio['mean']:.3f}  p95 {ratio['p95']:.3f}")


if __name__ == "__main__":
    main()
