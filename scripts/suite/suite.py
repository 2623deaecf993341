#!/usr/bin/env python3
"""The robustness suite as one command (issue 26): run every cell with one set of `ecvo run`
flags, then compare two labels' runs group by group, or tabulate them for the docs.
Python 3 standard library only. See scripts/suite/README.md.

    suite.py render --suite DIR
    suite.py run --label NAME --out DIR [--suite DIR] [--cells FILE] [--jobs N] -- [FLAGS...]
    suite.py compare DIR/A DIR/B [--markdown]
    suite.py table DIR/A [DIR/B ...]
    suite.py cells [--suite DIR]          (the default cells as TSV, a start for --cells)
"""

import argparse
import concurrent.futures
import hashlib
import json
import math
import os
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DATASETS = os.path.join(os.path.dirname(ROOT), "shared", "datasets")
DEFAULT_SUITE = "/tmp/ecvo-suite"

# Ratios of near-zero figures mean nothing (an ATE of 0.0001 m against 0.0002 m is "2x"):
# every figure is raised to its floor before a ratio is taken.
FLOORS = {"ate_m": 1e-5, "drift_trans_m_per_s": 1e-5, "drift_rot_deg_per_s": 1e-4}
METRICS = [("drift_trans_m_per_s", "drift trans"), ("drift_rot_deg_per_s", "drift rot"),
           ("ate_m", "ATE")]

# group -> (subfolder of the suite, script that renders it, frame steps, required)
RENDERED = [("fast", "synth", "make-synth-suite.sh", (1, 2), True),
            ("weak", "weak", "make-weak-texture.sh", (1,), True),
            ("noise", "noise", "make-noise-suite.sh", (1,), False),
            ("pan", "pan", "make-pan-suite.sh", (1, 2, 3, 4), False)]
REAL = [("tum_fr1_xyz_half", (1, 2, 3, 4)), ("tum_fr1_desk_half", (1, 2, 3, 4)),
        ("tum_fr1_xyz_full300", (1, 2, 3, 4))]


def warn(msg):
    print(f"suite.py: {msg}", file=sys.stderr)


# ---------------------------------------------------------------- cells

def cell(group, seq, step):
    seq = os.path.abspath(seq)
    return {"group": group, "seq": seq, "step": int(step),
            "id": f"{group}/{os.path.basename(seq.rstrip('/'))}_s{int(step)}"}


def read_list(path):
    with open(path) as f:
        return [line.strip() for line in f if line.strip() and not line.startswith("#")]


def default_cells(suite, datasets=DATASETS):
    """The default groups. Returns (cells, missing): missing lists the rendered groups whose
    suite.txt is absent, with whether the group is required."""
    cells, missing = [], []
    for name, steps in REAL:
        for step in steps:
            cells.append(cell("real", os.path.join(datasets, name), step))
    for group, sub, script, steps, required in RENDERED:
        listing = os.path.join(suite, sub, "suite.txt")
        if not os.path.isfile(listing):
            missing.append({"group": group, "listing": listing, "script": script,
                            "required": required})
            continue
        for seq in read_list(listing):
            for step in steps:
                cells.append(cell(group, seq, step))
    return cells, missing


def load_cells(path):
    """A cells file: JSON {"groups": {GROUP: [[SEQ, STEP], ...]}} (or [{"seq":, "step":}]), or
    TSV lines GROUP<TAB>SEQ<TAB>STEP ('#' comments). Relative SEQs are relative to the file."""
    base = os.path.dirname(os.path.abspath(path))
    with open(path) as f:
        text = f.read()
    cells = []
    if text.lstrip().startswith("{"):
        for group, entries in json.loads(text)["groups"].items():
            for e in entries:
                seq, step = (e["seq"], e.get("step", 1)) if isinstance(e, dict) else e
                cells.append(cell(group, os.path.join(base, seq), step))
    else:
        for n, line in enumerate(text.splitlines(), 1):
            if not line.strip() or line.startswith("#"):
                continue
            parts = line.split("\t") if "\t" in line else line.split()
            if len(parts) != 3:
                raise SystemExit(f"{path}:{n}: expected GROUP SEQ STEP, got {line!r}")
            cells.append(cell(parts[0], os.path.join(base, parts[1]), parts[2]))
    ids = [c["id"] for c in cells]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise SystemExit(f"{path}: cells listed twice: {', '.join(dup)}")
    return cells


# ---------------------------------------------------------------- run

def file_sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def extract(summary):
    """The figures a comparison needs from an `ecvo run` summary.json."""
    rpe = (summary.get("rpe") or {}).get("per_second") or {}
    ms = summary.get("ms_per_frame") or {}
    return {
        "ate_m": summary.get("ate_rmse_m"),
        "drift_trans_m_per_s": rpe.get("trans_m_per_s"),
        "drift_rot_deg_per_s": rpe.get("rot_deg_per_s"),
        "lost_frames": summary.get("lost_frames"),
        "motion_estimations": summary.get("motion_estimations"),
        "frames": summary.get("frames"),
        "ms_per_frame": {k: {"median": v.get("median"), "mean": v.get("mean")}
                         for k, v in ms.items() if isinstance(v, dict)},
        "wall_ms_per_frame": summary.get("wall_ms_per_frame"),
    }


def run_cell(c, ecvo, flags, key, label_dir, keep_cloud, timeout):
    out = os.path.join(label_dir, c["group"], os.path.basename(c["id"]))
    record_path = os.path.join(out, "suite-cell.json")
    if os.path.isfile(record_path):
        with open(record_path) as f:
            old = json.load(f)
        if old.get("key") == key and old.get("status") == "ok":
            old["resumed"] = True
            return old
    os.makedirs(out, exist_ok=True)
    for stale in ("summary.json", "suite-cell.json"):
        if os.path.exists(os.path.join(out, stale)):
            os.remove(os.path.join(out, stale))
    cmd = [ecvo, "run", c["seq"], "--out", out, "--threads", "1",
           "--frame-step", str(c["step"]), "-q"] + list(flags)
    rec = dict(c, key=key, command=cmd, resumed=False)
    start = time.monotonic()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        rc, stderr = proc.returncode, proc.stderr
    except subprocess.TimeoutExpired as e:
        err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else e.stderr
        rc, stderr = None, f"timed out after {timeout} s\n{err or ''}"
    except OSError as e:
        rc, stderr = None, f"could not start: {e}"
    rec["wall_s"] = round(time.monotonic() - start, 3)
    rec["exit_code"] = rc
    summary_path = os.path.join(out, "summary.json")
    if rc == 0 and os.path.isfile(summary_path):
        with open(summary_path) as f:
            rec.update(extract(json.load(f)), status="ok")
    else:
        why = "exit code %s" % rc if rc not in (None, 0) else (
            "no summary.json" if rc == 0 else stderr.splitlines()[0] if stderr else "failed")
        rec.update(status="failed", error=why,
                   stderr_tail="\n".join((stderr or "").splitlines()[-15:]))
    if not keep_cloud and os.path.exists(os.path.join(out, "cloud.ply")):
        os.remove(os.path.join(out, "cloud.ply"))
    with open(record_path, "w") as f:
        json.dump(rec, f, indent=1)
    return rec


def cmd_run(args):
    ecvo = os.path.abspath(args.ecvo)
    if not os.access(ecvo, os.X_OK):
        raise SystemExit(f"no ecvo binary at {ecvo} (set ECVO or --ecvo, or cargo build "
                         "--release -p ecvo-cli)")
    flags = args.flags[1:] if args.flags[:1] == ["--"] else args.flags
    missing = []
    if args.cells:
        cells = load_cells(args.cells)
    else:
        cells, missing = default_cells(args.suite, args.datasets)
        for m in missing:
            msg = f"group {m['group']}: no {m['listing']} (render it: suite.py render)"
            if m["required"] and not args.allow_missing:
                raise SystemExit(msg + "; --allow-missing runs without it")
            warn(msg + ": group left out, recorded in results.json")
    if args.groups:
        wanted = set(args.groups.split(","))
        cells = [c for c in cells if c["group"] in wanted]
    if not cells:
        raise SystemExit("no cells to run")
    label_dir = os.path.join(args.out, args.label)
    os.makedirs(label_dir, exist_ok=True)
    binary_sha = file_sha256(ecvo)
    key = {"flags": flags, "ecvo_sha256": binary_sha}
    start = time.monotonic()
    records = [None] * len(cells)
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = {pool.submit(run_cell, c, ecvo, flags, dict(key, seq=c["seq"], step=c["step"]),
                               label_dir, args.keep_cloud, args.timeout): i
                   for i, c in enumerate(cells)}
        for done, fut in enumerate(concurrent.futures.as_completed(futures), 1):
            i = futures[fut]
            r = records[i] = fut.result()
            if r["status"] == "ok":
                what = (f"ATE {sig(r['ate_m'])} m, drift {sig(r['drift_trans_m_per_s'])} m/s "
                        f"{sig(r['drift_rot_deg_per_s'])} deg/s, lost {r['lost_frames']}"
                        + (" (done before)" if r["resumed"] else f", {r['wall_s']:.1f} s"))
            else:
                what = f"FAILED: {r['error']}"
            print(f"[{done}/{len(cells)}] {r['id']}: {what}", flush=True)
    wall = time.monotonic() - start
    if args.groups:
        # A run of some groups keeps the label's other groups (same flags and binary).
        old_path = os.path.join(label_dir, "results.json")
        if os.path.isfile(old_path):
            with open(old_path) as f:
                old = json.load(f)
            if old.get("flags") == flags and old.get("ecvo_sha256") == binary_sha:
                records += [r for r in old.get("cells", []) if r.get("group") not in wanted]
    failed = [r["id"] for r in records if r["status"] != "ok"]
    results = {"label": args.label, "ecvo": ecvo, "ecvo_sha256": binary_sha, "flags": flags,
               "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
               "jobs": args.jobs, "wall_s": round(wall, 1),
               "cells_run_now": sum(1 for r in records if not r["resumed"]),
               "missing_groups": missing, "failed": failed, "cells": records}
    with open(os.path.join(label_dir, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    print(f"{len(cells)} cells ({results['cells_run_now']} run now, {len(failed)} failed) in "
          f"{wall:.0f} s; wrote {os.path.join(label_dir, 'results.json')}")
    if failed:
        warn("failed cells: " + ", ".join(failed))
    return 1 if failed else 0


# ---------------------------------------------------------------- render

def cmd_render(args):
    env = dict(os.environ, ECVO=os.path.abspath(args.ecvo))
    status = 0
    for group, sub, script, _, required in RENDERED:
        dest = os.path.join(args.suite, sub)
        path = os.path.join(HERE, script)
        marker = os.path.join(dest, ".rendered-by-suite.py")
        if os.path.isfile(marker) or (os.path.isfile(os.path.join(dest, "suite.txt"))
                                      and args.keep_existing):
            print(f"{group}: {dest} rendered before, left as it is")
            continue
        if not os.path.isfile(path):
            warn(f"{group}: no {path} here, not rendered" + ("" if required else " (optional)"))
            status |= 1 if required else 0
            continue
        start = time.monotonic()
        proc = subprocess.run(["bash", path, dest], env=env)
        if proc.returncode != 0:
            warn(f"{group}: {script} failed with exit code {proc.returncode}")
            status = 1
        else:
            with open(marker, "w") as f:
                f.write(f"{script} with {env['ECVO']}\n")
            print(f"{group}: rendered into {dest} in {time.monotonic() - start:.0f} s")
    return status


def cmd_cells(args):
    cells, missing = default_cells(args.suite, args.datasets)
    for m in missing:
        print(f"# group {m['group']}: no {m['listing']}")
    for c in cells:
        print(f"{c['group']}\t{c['seq']}\t{c['step']}")
    return 0


# ---------------------------------------------------------------- compare and table

def load_results(path):
    f = os.path.join(path, "results.json") if os.path.isdir(path) else path
    with open(f) as fh:
        res = json.load(fh)
    res.setdefault("label", os.path.basename(os.path.dirname(os.path.abspath(f))))
    return res


def floored(rec, metric):
    v = rec.get(metric)
    if v is None or not math.isfinite(v):
        return None, False
    return max(v, FLOORS[metric]), v < FLOORS[metric]


def geomean(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else None


def fmt(v, digits=3):
    if v is None:
        return "–"
    return f"{v:.{digits}f}"


def sig(v, digits=3):
    """v with `digits` significant digits, in fixed notation (0.0200, 0.000130)."""
    if v is None:
        return "–"
    if v == 0 or not math.isfinite(v):
        return str(v)
    return f"{v:.{min(8, max(0, digits - 1 - math.floor(math.log10(abs(v)))))}f}"


def ms_total(rec):
    return ((rec.get("ms_per_frame") or {}).get("total") or {}).get("median")


def compare(a, b, threshold=1.05):
    """Per-group comparison of B against A, on the cells both ran successfully. A row's
    `over` lists the cells whose drift (translation or rotation) ratio exceeds threshold."""
    cells_a = {c["id"]: c for c in a["cells"]}
    cells_b = {c["id"]: c for c in b["cells"]}
    groups, order = {}, []
    for cid in list(cells_a) + [i for i in cells_b if i not in cells_a]:
        g = (cells_a.get(cid) or cells_b[cid])["group"]
        if g not in groups:
            groups[g] = {"ids": [], "only_a": [], "only_b": [], "failed": []}
            order.append(g)
        ra, rb = cells_a.get(cid), cells_b.get(cid)
        if ra is None or rb is None:
            groups[g]["only_a" if rb is None else "only_b"].append(cid)
        elif ra["status"] != "ok" or rb["status"] != "ok":
            groups[g]["failed"].append(
                (cid, [lab for lab, r in ((a["label"], ra), (b["label"], rb))
                       if r["status"] != "ok"]))
        else:
            groups[g]["ids"].append(cid)
    floored_count = 0
    out = []
    for g in order:
        info = groups[g]
        row = {"group": g, "cells": len(info["ids"]), "only_a": info["only_a"],
               "only_b": info["only_b"], "failed": info["failed"], "metrics": {}}
        for metric, _ in METRICS:
            ratios = []
            for cid in info["ids"]:
                va, fa = floored(cells_a[cid], metric)
                vb, fb = floored(cells_b[cid], metric)
                floored_count += fa + fb
                if va is not None and vb is not None:
                    ratios.append((vb / va, cid))
            worst = max(ratios) if ratios else (None, None)
            if metric.startswith("drift"):
                row.setdefault("over", {})
                for r, cid in ratios:
                    if r > threshold:
                        row["over"][cid] = max(r, row["over"].get(cid, 0))
            row["metrics"][metric] = {
                "geomean": geomean([r for r, _ in ratios]), "n": len(ratios),
                "better": sum(1 for r, _ in ratios if r < 1),
                "worse": sum(1 for r, _ in ratios if r > 1),
                "worst": worst[0], "worst_cell": worst[1]}
        row["lost_a"] = sum(cells_a[c]["lost_frames"] or 0 for c in info["ids"])
        row["lost_b"] = sum(cells_b[c]["lost_frames"] or 0 for c in info["ids"])
        ma = sum(cells_a[c]["motion_estimations"] or 0 for c in info["ids"])
        mb = sum(cells_b[c]["motion_estimations"] or 0 for c in info["ids"])
        row["motion_ratio"] = mb / ma if ma else None
        ms = [ms_total(cells_b[c]) / ms_total(cells_a[c]) for c in info["ids"]
              if ms_total(cells_a[c]) and ms_total(cells_b[c])]
        row["ms_ratio"] = geomean(ms)
        out.append(row)
    return out, floored_count


def render_table(header, rows, markdown):
    rows = [[str(x) for x in r] for r in rows]
    if markdown:
        lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])
    widths = [max(len(x) for x in col) for col in zip(header, *rows)]
    line = lambda r: "  ".join(x.ljust(w) for x, w in zip(r, widths)).rstrip()
    return "\n".join([line(header), line(["-" * w for w in widths])] + [line(r) for r in rows])


def cmd_compare(args):
    a, b = load_results(args.a), load_results(args.b)
    rows, floored_count = compare(a, b, args.threshold)
    la, lb = a["label"], b["label"]
    print(f"{lb} against {la}: geometric means of per-cell ratios {lb}/{la} "
          "(below 1: {0} is better)".format(lb))
    for label, res in ((la, a), (lb, b)):
        wall = sum(c.get("wall_s") or 0 for c in res["cells"])
        print(f"{label}: {' '.join(res.get('flags') or []) or '(defaults)'} "
              f"({len(res['cells'])} cells, {wall:.0f} s of ecvo runs, {res.get('ecvo', '?')})")
    print("Each figure is floored before its ratio is taken (ATE %g m, drift %g m/s, %g deg/s); "
          "%d figure(s) were below their floor." % (FLOORS["ate_m"], FLOORS["drift_trans_m_per_s"],
                                                     FLOORS["drift_rot_deg_per_s"], floored_count))
    print("better t/r/ATE: cells whose drift translation / rotation / ATE went down; worst: the "
          "largest ratio; MOTION: ratio of total calls; ms/frame: geometric mean of the "
          "ms_per_frame.total medians' ratios.\n")
    header = ["group", "cells", "drift trans", "drift rot", "ATE", "better t/r/ATE",
              "worst t / r / ATE", f"lost {la}→{lb}", "MOTION", "ms/frame"]
    table, notes = [], []
    for r in rows:
        m = r["metrics"]
        t, rot, ate = (m[k] for k, _ in METRICS)
        table.append([r["group"], r["cells"], fmt(t["geomean"]), fmt(rot["geomean"]),
                      fmt(ate["geomean"]),
                      f"{t['better']}/{rot['better']}/{ate['better']} of {r['cells']}",
                      " / ".join(fmt(x["worst"], 2) for x in (t, rot, ate)),
                      f"{r['lost_a']}→{r['lost_b']}", fmt(r["motion_ratio"]),
                      fmt(r["ms_ratio"])])
        for k, name in METRICS:
            if m[k]["worst_cell"]:
                notes.append(f"{r['group']}: worst {name} {m[k]['worst_cell']} "
                             f"({fmt(m[k]['worst'], 3)})")
        if r.get("over"):
            notes.append(f"{r['group']}: {len(r['over'])} of {r['cells']} cells worse than "
                         f"{args.threshold:g}x in drift: " + ", ".join(
                             f"{c} ({x:.3f})" for c, x in sorted(r["over"].items(),
                                                               key=lambda kv: -kv[1])))
        for cid, who in r["failed"]:
            notes.append(f"{r['group']}: {cid} FAILED in {', '.join(who)} (left out of the ratios)")
        for cid in r["only_a"]:
            notes.append(f"{r['group']}: {cid} only in {la}")
        for cid in r["only_b"]:
            notes.append(f"{r['group']}: {cid} only in {lb}")
    print(render_table(header, table, args.markdown))
    for label, res in ((la, a), (lb, b)):
        for m in res.get("missing_groups") or []:
            notes.append(f"group {m['group']} was not run in {label} (no {m['listing']})")
    if notes:
        print()
        print("\n".join(("- " if args.markdown else "") + n for n in notes))
    print()
    cells_a = {c["id"]: c for c in a["cells"]}
    cells_b = {c["id"]: c for c in b["cells"]}
    header = ["cell", f"ATE {la}", f"ATE {lb}", f"drift {la} (m/s, deg/s)",
              f"drift {lb} (m/s, deg/s)", f"lost {la}/{lb}"]
    table = []
    for cid in list(cells_a) + [i for i in cells_b if i not in cells_a]:
        ra, rb = cells_a.get(cid, {}), cells_b.get(cid, {})
        table.append([cid, cell_text(ra, "ate_m"), cell_text(rb, "ate_m"),
                      drift_text(ra), drift_text(rb),
                      f"{lost_text(ra)}/{lost_text(rb)}"])
    print(render_table(header, table, args.markdown))
    return 0


def cell_text(rec, metric):
    if not rec:
        return "–"
    if rec.get("status") != "ok":
        return "failed"
    return sig(rec.get(metric))


def drift_text(rec):
    if not rec or rec.get("status") != "ok":
        return cell_text(rec, "")
    return f"{sig(rec['drift_trans_m_per_s'])}, {sig(rec['drift_rot_deg_per_s'])}"


def lost_text(rec):
    return "–" if not rec or rec.get("status") != "ok" else str(rec.get("lost_frames"))


def cmd_table(args):
    results = [load_results(p) for p in args.dirs]
    ids, by_label = [], []
    for res in results:
        cells = {c["id"]: c for c in res["cells"]}
        ids += [i for i in cells if i not in ids]
        by_label.append(cells)
    header = ["group", "cell"] + [f"{r['label']} ATE m (lost)" for r in results]
    table = []
    for cid in ids:
        group, name = cid.split("/", 1)
        row = [group, name]
        for cells in by_label:
            rec = cells.get(cid)
            if rec is None:
                row.append("–")
            elif rec["status"] != "ok":
                row.append(f"failed ({rec.get('error')})")
            else:
                row.append(f"{sig(rec['ate_m'])} ({rec['lost_frames']})")
        table.append(row)
    print(render_table(header, table, True))
    return 0


# ---------------------------------------------------------------- main

def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    ecvo_default = os.environ.get("ECVO", os.path.join(ROOT, "target", "release", "ecvo"))
    suite_default = os.environ.get("SUITE", DEFAULT_SUITE)

    def common(q):
        q.add_argument("--ecvo", default=ecvo_default,
                       help="the ecvo binary (default: $ECVO or target/release/ecvo)")
        q.add_argument("--suite", default=suite_default,
                       help=f"rendered suite folder (default: $SUITE or {DEFAULT_SUITE})")
        q.add_argument("--datasets", default=os.environ.get("ECVO_DATASETS", DATASETS),
                       help="folder of the real sequences (default: $ECVO_DATASETS or "
                       "../shared/datasets)")

    q = sub.add_parser("run", help="run every cell with one set of flags")
    common(q)
    q.add_argument("--label", required=True)
    q.add_argument("--out", required=True, help="results go to OUT/LABEL/")
    q.add_argument("--cells", help="a cells file (JSON or TSV) instead of the default groups")
    q.add_argument("--groups", help="comma-separated groups to run (default: all)")
    q.add_argument("--jobs", type=int, default=1, help="cells run at once (default 1)")
    q.add_argument("--timeout", type=float, default=None, help="seconds per cell")
    q.add_argument("--keep-cloud", action="store_true",
                   help="keep each cell's cloud.ply (deleted by default: 12 MB a cell)")
    q.add_argument("--allow-missing", action="store_true",
                   help="run without a required rendered group (fast, weak) if absent")
    q.add_argument("flags", nargs=argparse.REMAINDER, help="-- then ecvo run flags")
    q.set_defaults(func=cmd_run)

    q = sub.add_parser("render", help="render the synthetic groups into SUITE/{synth,weak,noise,pan}")
    common(q)
    q.add_argument("--keep-existing", action="store_true",
                   help="also leave alone a group with a suite.txt but no mark of a finished "
                   "render (by default such a group, e.g. from an interrupted render, is "
                   "rendered again)")
    q.set_defaults(func=cmd_render)

    q = sub.add_parser("cells", help="print the default cells as TSV")
    common(q)
    q.set_defaults(func=cmd_cells)

    q = sub.add_parser("compare", help="compare B against A, group by group")
    q.add_argument("a")
    q.add_argument("b")
    q.add_argument("--markdown", action="store_true")
    q.add_argument("--threshold", type=float, default=1.05,
                   help="list the cells whose drift ratio B/A exceeds this (default 1.05)")
    q.set_defaults(func=cmd_compare)

    q = sub.add_parser("table", help="markdown table of ATE (lost) per cell, a column per label")
    q.add_argument("dirs", nargs="+")
    q.set_defaults(func=cmd_table)

    args = p.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `suite.py table ... | head` ends quietly
    sys.exit(main())
