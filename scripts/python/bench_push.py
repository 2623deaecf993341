#!/usr/bin/env python3
"""Per-frame cost of ecvo.Tracker.push from Python against the Rust engine's own
(ecvo_core::Odometry::push timed in Rust) on the same frames, already in memory.

    python scripts/python/bench_push.py testdata/synth_phone_320x180 --rounds 7

Two comparisons, both with the same build of the engine (the installed package),
settings and thread pool:
- paired: each Tracker.push is timed from Python (perf_counter around the call)
  and, inside it, Odometry::push is timed in Rust (Tracker._last_engine_s): the same
  frame at the same moment, so the ratio is the binding's overhead whatever else the
  machine is doing;
- separate: the Rust engine alone over the same frames (_ecvo._engine_push_times),
  in rounds alternating with the Python ones (sensitive to the machine's load). The sequence is played
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
    ap.add_argument(
        "--input",
        default="grey",
        choices=["grey", "colour", "metres"],
        help="what Tracker.push is given: uint8 grey + uint16 depth (read in place), "
        "(H, W, 3) uint8 colour, or float32 metres depth (both converted in push); "
        "the Rust engine always gets the grey/uint16 frames",
    )
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    seq = ecvo.read_sequence(args.sequence, max_frames=args.max_frames)
    base = [(i, d) for _, i, d in seq]
    path = []
    for lap in range(args.laps):
        path += base if lap % 2 == 0 else base[::-1]
    frames = [(k / 30.0, i, d) for k, (i, d) in enumerate(path)]
    if args.input == "colour":
        given = [(t, np.repeat(i[..., None], 3, axis=2), d) for t, i, d in frames]
    elif args.input == "metres":
        scale = np.float32(seq.camera.depth_scale)
        given = [(t, i, d.astype(np.float32) / scale) for t, i, d in frames]
    else:
        given = frames
    settings = dict(preset=args.preset, threads=args.threads)

    py_times, inner_times, rust_times = [], [], []
    for r in range(args.rounds + 1):
        tracker = ecvo.Tracker(seq.camera, **settings)
        times, inner = [], []
        for t, i, d in given:
            t0 = time.perf_counter()
            tracker.push(t, i, d)
            times.append(time.perf_counter() - t0)
            inner.append(tracker._last_engine_s)
        engine = _ecvo._engine_push_times(seq.camera, frames, **settings)
        if r > 0:  # round 0 warms both up
            py_times += times
            inner_times += inner
            rust_times += engine
    py, inner, rust = stats(py_times), stats(inner_times), stats(rust_times)
    paired = {k: py[k] / inner[k] for k in py}
    overhead_us = {k: 1e3 * v for k, v in stats(np.subtract(py_times, inner_times)).items()}
    ratio = {k: py[k] / rust[k] for k in py}
    result = {
        "sequence": str(args.sequence),
        "frames_per_round": len(frames),
        "rounds": args.rounds,
        "threads": args.threads,
        "input": args.input,
        "simd": _ecvo.simd_path,
        "python_ms": py,
        "engine_inside_push_ms": inner,
        "paired_ratio": paired,
        "binding_overhead_us": overhead_us,
        "rust_ms": rust,
        "ratio": ratio,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(
            f"{args.sequence}: {len(frames)} frames x {args.rounds} rounds, threads {args.threads}, "
            f"input {args.input}"
        )
        rows = (
            ("Tracker.push (Python)", py, "ms"),
            ("  its Odometry::push", inner, "ms"),
            ("  paired ratio", paired, ""),
            ("  binding overhead", overhead_us, "us"),
            ("Odometry::push alone", rust, "ms"),
            ("  ratio Python/alone", ratio, ""),
        )
        for name, s, unit in rows:
            print(f"  {name:22s} median {s['median']:.3f}  mean {s['mean']:.3f}  p95 {s['p95']:.3f} {unit}")


if __name__ == "__main__":
    main()
