"""Per-frame timing statistics for the peers' scripts (standard library only).

`summary(xs)` gives the median, mean and p95 of per-frame times. The p95 is the
nearest-rank 95th percentile (the ceil(0.95 n)-th smallest time), the rank ecvo's
pipeline histograms use (ecvo-pipeline's stats.rs), so a peer's p95 and ecvo's are
the same statistic. `ecvo_summary(summary_json)` reads ecvo's per-frame figures from a
summary.json; `ratios(ecvo, peer)` and `spread(values)` make the bench's ratio rows.

Run as a script it is bench-vs-peer.sh's arithmetic:

    timing.py round ROUND_DIR SEQ_NAME ROUND PEER   # one JSON line for rounds.jsonl
    timing.py report ROUNDS_JSONL BENCH_JSON PEER  # the per-sequence table
"""

import json
import math
import statistics
import sys

STATS = ("median", "mean", "p95")


def percentile(xs, q):
    """Nearest-rank q-quantile (0 < q <= 1): the ceil(q n)-th smallest of xs."""
    if not xs:
        raise ValueError("percentile of no values")
    if not 0.0 < q <= 1.0:
        raise ValueError(f"quantile {q} outside (0, 1]")
    s = sorted(xs)
    rank = min(max(math.ceil(q * len(s) - 1e-9), 1), len(s))
    return s[rank - 1]


def summary(xs):
    """{"median", "mean", "p95", "frames"} of per-frame times (NaN when empty)."""
    xs = list(xs)
    if not xs:
        nan = float("nan")
        return {"median": nan, "mean": nan, "p95": nan, "frames": 0}
    return {"median": statistics.median(xs), "mean": statistics.fmean(xs),
            "p95": percentile(xs, 0.95), "frames": len(xs)}


CLOCKS = {"process_cpu": "process_ms", "thread_cpu": "thread_ms", "wall": "wall_ms"}


def row_timing(info):
    """The timing fields of a peers.json row from a run's per-frame lists.

    info has `clock` (the headline clock: process_cpu, thread_cpu or wall) and the
    per-frame milliseconds `process_ms`, `thread_ms`, `wall_ms` (any may be empty).
    `ms_per_frame` is the headline clock's summary; `process_over_thread` is the total
    process CPU over the total thread CPU (1 when the timed thread did all the work).
    """
    clock = info["clock"]
    out = {"clock": clock, "ms_per_frame": summary(info[CLOCKS[clock]])}
    for name, key in CLOCKS.items():
        out[f"{name}_ms_per_frame"] = summary(info.get(key, []))
    tp, tt = sum(info.get("process_ms", [])), sum(info.get("thread_ms", []))
    out["process_over_thread"] = tp / tt if tt > 0 and tp > 0 else None
    # Kept for older readers of peers.json.
    out["ms_per_frame_median"] = out["ms_per_frame"]["median"]
    out["wall_ms_per_frame_median"] = out["wall_ms_per_frame"]["median"]
    return out


def ecvo_summary(s):
    """ecvo's per-frame cost (filter + tracker of each frame) from a parsed summary.json.

    A summary.json that has the pipeline's per-frame `work_cpu` figures (each frame's
    preparation plus its tracking, as CPU time of the one compute thread: the peers'
    kind of clock) gives those, with `clock` "thread_cpu", and the same per-frame
    work by the wall clock as `wall`. An older one has per-stage figures only: then the
    mean is the exact sum of the stages' means, the median and p95 are sums of the
    stages' medians and p95s (a sum of medians is not the median of the sums), and the
    clock is the wall clock; `exact` says which is which.
    """
    st = s["pipeline"]["stages"]
    f, t = st["filter"], st["tracker"]
    base = {"filter": {k: f[f"{k}_ms"] for k in STATS},
            "tracker": {k: t[f"{k}_ms"] for k in STATS}}
    cpu, work = st.get("work_cpu"), st.get("work")
    if cpu and work and cpu.get("frames", 0) > 0 and cpu.get("mean_ms", 0) > 0:
        out = {k: cpu[f"{k}_ms"] for k in STATS}
        out.update(base, frames=cpu["frames"], clock="thread_cpu",
                   wall={k: work[f"{k}_ms"] for k in STATS},
                   exact={"median": True, "mean": True, "p95": True})
        return out
    return {"median": f["median_ms"] + t["median_ms"], "mean": f["mean_ms"] + t["mean_ms"],
            "p95": f["p95_ms"] + t["p95_ms"], "frames": min(f["frames"], t["frames"]),
            **base, "clock": "wall",
            "exact": {"median": False, "mean": True, "p95": False}}


def ratios(ecvo, peer):
    """peer / ecvo of the means and of the medians."""
    return {"mean": peer["mean"] / ecvo["mean"], "median": peer["median"] / ecvo["median"]}


def spread(xs):
    """(median, min, max) of xs."""
    return statistics.median(xs), min(xs), max(xs)


def fmt3(s):
    """'median / mean / p95' of a summary, two decimals."""
    return " / ".join(f"{s[k]:.2f}" for k in STATS)


def round_record(d, name, r, peer):
    """One round's record from ROUND_DIR's ecvo/summary.json and PEER/peers.json."""
    with open(f"{d}/ecvo/summary.json") as f:
        summ = json.load(f)
    with open(f"{d}/{peer}/peers.json") as f:
        row = json.load(f)["rows"][0]
    e = ecvo_summary(summ)
    p = {k: row["ms_per_frame"][k] for k in STATS}
    p["frames"] = row["ms_per_frame"]["frames"]
    rec = {"sequence": name, "round": int(r), "peer": peer, "ecvo": e, "peer_ms": p,
           "peer_clock": row["clock"], "ratio": ratios(e, p),
           "ecvo_simd": summ.get("simd", "?"), "ecvo_frames": summ.get("frames")}
    try:
        with open(f"{d}/ecvo.cpu") as f:
            user, system = (float(x) for x in f.read().split()[-2:])
        # Whole process, every thread, decoding and start-up included: an upper bound.
        rec["ecvo_process_cpu_ms_per_frame"] = (user + system) * 1e3 / max(e["frames"], 1)
    except (OSError, ValueError):
        pass
    for k in ("process_cpu_ms_per_frame", "thread_cpu_ms_per_frame", "wall_ms_per_frame",
              "process_over_thread", "threads"):
        if k in row:
            rec[f"peer_{k}"] = row[k]
    return rec


def round_line(rec):
    """The line bench-vs-peer.sh prints per round."""
    return (f"{rec['sequence']} round {rec['round']}: ecvo ({rec['ecvo_simd']}) "
            f"{fmt3(rec['ecvo'])} ms/frame, {rec['peer']} ({rec['peer_clock']}) "
            f"{fmt3(rec['peer_ms'])} ms/frame (median / mean / p95); "
            f"{rec['peer']} / ecvo: means {rec['ratio']['mean']:.2f}, "
            f"medians {rec['ratio']['median']:.2f}")


def report(records, peer):
    """(Markdown lines, bench.json object) over the rounds, per sequence."""
    by = {}
    for rec in records:
        by.setdefault(rec["sequence"], []).append(rec)
    g = lambda xs: "{:.2f} ({:.2f}-{:.2f})".format(*spread(xs))
    lines = [f"| sequence | rounds | ecvo median / mean / p95 ms | {peer} median / mean / "
             f"p95 ms | {peer} / ecvo, means | {peer} / ecvo, medians |",
             "|---|---|---|---|---|---|"]
    out = {}
    for name, recs in by.items():
        e = {k: [x["ecvo"][k] for x in recs] for k in STATS}
        p = {k: [x["peer_ms"][k] for x in recs] for k in STATS}
        qm = [x["ratio"]["mean"] for x in recs]
        qd = [x["ratio"]["median"] for x in recs]
        m3 = lambda v: " / ".join(f"{statistics.median(v[k]):.2f}" for k in STATS)
        lines.append(f"| {name} | {len(recs)} | {m3(e)} | {m3(p)} | **{g(qm)}** | {g(qd)} |")
        out[name] = {"peer": peer, "rounds": recs,
                     "ratio_of_means": dict(zip(("median", "min", "max"), spread(qm))),
                     "ratio_of_medians": dict(zip(("median", "min", "max"), spread(qd))),
                     "ecvo_simd": sorted({x["ecvo_simd"] for x in recs})}
    return lines, out


def main(argv):
    if len(argv) == 5 and argv[0] == "round":
        rec = round_record(*argv[1:])
        print(json.dumps(rec))
        print(round_line(rec), file=sys.stderr)
    elif len(argv) == 4 and argv[0] == "report":
        with open(argv[1]) as f:
            records = [json.loads(line) for line in f if line.strip()]
        lines, out = report(records, argv[3])
        simd = sorted({r["ecvo_simd"] for r in records})
        print(f"\necvo's kernels: {', '.join(simd)}\n")
        print("\n".join(lines))
        print("\n(cells of the ecvo and peer columns: the median over the rounds of each "
              "round's per-frame median / mean / p95; ratio columns: median (min-max) "
              "over the rounds of the per-round ratio)")
        with open(argv[2], "w") as f:
            json.dump(out, f, indent=2)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
