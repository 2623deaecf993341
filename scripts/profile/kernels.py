#!/usr/bin/env python3
"""Where each microsecond of a frame goes, kernel by kernel (issue 30).

For every bench of `cargo bench -p ecvo-bench --bench stages` (`prepare/SIZE`: the
filter stage; `motion/SIZE`: one [A] from the identity, the tracker's settings), on
one thread:

1. criterion's estimate of the time per call (its point estimate, and the interval);
2. `perf record -F FREQ` of the same bench (criterion's `--profile-time`), each
   symbol's share of the samples that fell in ecvo_core (the synthetic frames are
   rendered once, before the timed loop; their samples and the harness's are left out);
3. per kernel: share x time, in microseconds per call.

    scripts/profile/kernels.py [--sizes 320x180,320x240,640x480] [--benches prepare,motion]
        [--seconds 5] [--freq 4000] [--json OUT.json]

Prints a Markdown table per bench. Needs `perf` (Debian: linux-perf); perf's
`cpu-clock` event samples by time, so this works where the VM has no hardware
counters. Symbols are perf's: a kernel compiled in several copies (`::avx512`,
`::avx2`) shows the copy this CPU ran; inlined helpers are booked to their caller.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def bench_binary():
    """Builds the stages bench and returns its executable."""
    out = subprocess.run(
        ["cargo", "bench", "-p", "ecvo-bench", "--bench", "stages", "--no-run",
         "--message-format", "json"], cwd=ROOT, check=True, capture_output=True, text=True)
    exe = None
    for line in out.stdout.splitlines():
        try:
            msg = json.loads(line)
        except ValueError:
            continue
        if msg.get("reason") == "compiler-artifact" and msg.get("executable") \
                and msg["target"]["name"] == "stages":
            exe = msg["executable"]
    if not exe:
        sys.exit("kernels.py: no stages bench executable in cargo's output")
    return exe


UNITS = {"ns": 1e-3, "µs": 1.0, "us": 1.0, "ms": 1e3, "s": 1e6}


def parse_time(text):
    """criterion's `time: [lo est hi]` line as microseconds (lo, est, hi)."""
    m = re.search(r"time:\s+\[([\d.]+) (\S+) ([\d.]+) (\S+) ([\d.]+) (\S+)\]", text)
    if not m:
        raise ValueError("no criterion time line")
    v = [float(m.group(i)) * UNITS[m.group(i + 1)] for i in (1, 3, 5)]
    return tuple(v)


def parse_report(text):
    """perf report --sort symbol lines as {symbol: percent}, ecvo_core symbols only."""
    shares = {}
    for line in text.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+\[\.\]\s+(\S.*?)\s*$", line)
        if not m:
            continue
        sym = m.group(2).split()[0]
        if sym.startswith("ecvo_core::") or sym.startswith("<ecvo_core::"):
            shares[sym] = shares.get(sym, 0.0) + float(m.group(1))
    return shares


def short(sym):
    s = sym.replace("<ecvo_core::motion::MotionEstimator as ecvo_core::motion::estimator::Loops>::",
                    "MotionEstimator::")
    return s.replace("ecvo_core::", "")


def profile(exe, name, seconds, freq, tmp):
    crit = subprocess.run([exe, "--bench", name, "--warm-up-time", "1",
                           "--measurement-time", str(seconds)],
                          capture_output=True, text=True, check=True, cwd=tmp)
    lo, est, hi = parse_time(crit.stdout)
    data = os.path.join(tmp, "perf.data")
    subprocess.run(["perf", "record", "-q", "-F", str(freq), "-o", data, exe, "--bench",
                    "--profile-time", str(seconds), name],
                   capture_output=True, text=True, check=True, cwd=tmp)
    rep = subprocess.run(["perf", "report", "-i", data, "--no-children", "--sort", "symbol",
                          "--stdio"], capture_output=True, text=True, check=True, cwd=tmp)
    shares = parse_report(rep.stdout)
    total = sum(shares.values())
    rows = sorted(((short(s), p / total) for s, p in shares.items()), key=lambda r: -r[1])
    return {"bench": name, "us": {"lo": lo, "est": est, "hi": hi},
            "kernels": [{"kernel": k, "share": f, "us": f * est} for k, f in rows]}


def table(r, min_share=0.005):
    t = r["us"]
    lines = [f"**{r['bench']}**: {t['est']:.1f} µs per call ({t['lo']:.1f}–{t['hi']:.1f})", "",
             "| kernel | share | µs per call |", "|---|---|---|"]
    rest = 0.0
    for k in r["kernels"]:
        if k["share"] >= min_share:
            lines.append(f"| `{k['kernel']}` | {100 * k['share']:.1f} % | {k['us']:.1f} |")
        else:
            rest += k["share"]
    if rest:
        lines.append(f"| (the rest) | {100 * rest:.1f} % | {rest * t['est']:.1f} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="320x180,320x240,640x480")
    ap.add_argument("--benches", default="prepare,motion")
    ap.add_argument("--seconds", type=int, default=5)
    ap.add_argument("--freq", type=int, default=4000)
    ap.add_argument("--json")
    a = ap.parse_args()
    if not shutil.which("perf"):
        sys.exit("kernels.py: needs perf (Debian: apt-get install linux-perf)")
    exe = bench_binary()
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for b in a.benches.split(","):
            for s in a.sizes.split(","):
                r = profile(exe, f"{b}/{s}", a.seconds, a.freq, tmp)
                out.append(r)
                print(table(r) + "\n", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
