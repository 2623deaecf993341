#!/usr/bin/env python3
"""Tests of suite.py on fabricated results and a fake ecvo binary (no ecvo needed).

    python3 -m unittest discover -s scripts/suite -p 'test_*.py'
"""

import contextlib
import io
import json
import math
import os
import stat
import sys
import tempfile
import textwrap
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import suite  # noqa: E402


def rec(group, name, ate, trans, rot, lost=0, motion=100, ms=2.0, status="ok"):
    r = {"group": group, "id": f"{group}/{name}", "seq": f"/x/{name}", "step": 1,
         "status": status}
    if status == "ok":
        r.update(ate_m=ate, drift_trans_m_per_s=trans, drift_rot_deg_per_s=rot,
                 lost_frames=lost, motion_estimations=motion,
                 ms_per_frame={"total": {"median": ms, "mean": ms * 1.2}})
    else:
        r.update(exit_code=101, error="exit code 101")
    return r


def write_results(root, label, cells, **extra):
    d = os.path.join(root, label)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "results.json"), "w") as f:
        json.dump(dict({"label": label, "flags": [], "cells": cells}, **extra), f)
    return d


def capture(argv):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = suite.main(argv)
    return rc, buf.getvalue()


class CompareTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def test_known_ratios(self):
        # real: trans ratios 0.5 and 2 (geomean 1), rot 0.25 and 0.25, ATE 0.8 and 0.8
        a = [rec("real", "a_s1", 0.010, 0.020, 1.0, lost=1, motion=100, ms=2.0),
             rec("real", "b_s1", 0.020, 0.010, 2.0, lost=0, motion=300, ms=4.0),
             rec("fast", "c_s1", 0.004, 0.008, 0.5)]
        b = [rec("real", "a_s1", 0.008, 0.010, 0.25, lost=3, motion=200, ms=4.0),
             rec("real", "b_s1", 0.016, 0.020, 0.5, lost=0, motion=600, ms=8.0),
             rec("fast", "c_s1", 0.004 * 1.1, 0.008 * 1.2, 0.5 * 0.9)]
        rows, floored = suite.compare(suite.load_results(write_results(self.root, "A", a)),
                                      suite.load_results(write_results(self.root, "B", b)))
        self.assertEqual(floored, 0)
        real, fast = rows
        self.assertEqual((real["group"], real["cells"]), ("real", 2))
        m = real["metrics"]
        self.assertAlmostEqual(m["drift_trans_m_per_s"]["geomean"], 1.0)
        self.assertAlmostEqual(m["drift_rot_deg_per_s"]["geomean"], 0.25)
        self.assertAlmostEqual(m["ate_m"]["geomean"], 0.8)
        self.assertEqual(m["drift_trans_m_per_s"]["better"], 1)
        self.assertEqual(m["drift_trans_m_per_s"]["worse"], 1)
        self.assertAlmostEqual(m["drift_trans_m_per_s"]["worst"], 2.0)
        self.assertEqual(m["drift_trans_m_per_s"]["worst_cell"], "real/b_s1")
        self.assertEqual(m["ate_m"]["better"], 2)
        self.assertEqual((real["lost_a"], real["lost_b"]), (1, 3))
        self.assertAlmostEqual(real["motion_ratio"], 2.0)
        self.assertAlmostEqual(real["ms_ratio"], 2.0)
        self.assertAlmostEqual(fast["metrics"]["drift_trans_m_per_s"]["geomean"], 1.2)
        self.assertAlmostEqual(fast["metrics"]["ate_m"]["geomean"], 1.1)
        self.assertEqual(fast["metrics"]["ate_m"]["better"], 0)
        # drift over 1.05x: real/b_s1 (translation 2x), fast/c_s1 (translation 1.2x)
        self.assertEqual(real["over"], {"real/b_s1": 2.0})
        self.assertEqual(list(fast["over"]), ["fast/c_s1"])
        self.assertAlmostEqual(fast["over"]["fast/c_s1"], 1.2)
        rc, out = capture(["compare", os.path.join(self.root, "A"), os.path.join(self.root, "B"),
                           "--threshold", "1.5"])
        self.assertIn("real: 1 of 2 cells worse than 1.5x in drift: real/b_s1 (2.000)", out)
        self.assertNotIn("fast: 1 of 1 cells worse", out)

    def test_figures_keep_three_significant_digits(self):
        self.assertEqual([suite.sig(v) for v in (0.02, 0.00013, 13.303, 0.3240, None)],
                         ["0.0200", "0.000130", "13.3", "0.324", "–"])

    def test_floors_keep_tiny_figures_from_blowing_up(self):
        # ATE 0.0001 m against 0.000001 m would be a ratio of 0.01; floored at 1e-5: 0.1.
        # Drift of 1e-7 against 1e-8 m/s: both under the floor, ratio 1.
        a = [rec("weak", "w_s1", 1e-4, 1e-7, 1e-6)]
        b = [rec("weak", "w_s1", 1e-6, 1e-8, 2e-4)]
        rows, floored = suite.compare(suite.load_results(write_results(self.root, "A", a)),
                                      suite.load_results(write_results(self.root, "B", b)))
        m = rows[0]["metrics"]
        self.assertAlmostEqual(m["ate_m"]["geomean"], 0.1)
        self.assertAlmostEqual(m["drift_trans_m_per_s"]["geomean"], 1.0)
        self.assertAlmostEqual(m["drift_rot_deg_per_s"]["geomean"], 2.0)  # 2e-4 / 1e-4
        self.assertEqual(floored, 4)  # ATE of B, both drifts, the rotation of A
        rc, out = capture(["compare", os.path.join(self.root, "A"),
                           os.path.join(self.root, "B")])
        self.assertEqual(rc, 0)
        self.assertIn("floored", out)
        self.assertIn("4 figure(s) were below their floor", out)

    def test_failures_and_missing_cells_are_reported_not_averaged(self):
        a = [rec("real", "ok_s1", 0.01, 0.01, 1.0), rec("real", "bad_s1", 0.01, 0.01, 1.0),
             rec("real", "gone_s1", 0.01, 0.01, 1.0)]
        b = [rec("real", "ok_s1", 0.02, 0.02, 2.0), rec("real", "bad_s1", 0, 0, 0,
                                                        status="failed"),
             rec("real", "new_s1", 0.01, 0.01, 1.0)]
        da = write_results(self.root, "A", a)
        db = write_results(self.root, "B", b, missing_groups=[
            {"group": "noise", "listing": "/s/noise/suite.txt", "required": False}])
        rows, _ = suite.compare(suite.load_results(da), suite.load_results(db))
        real = rows[0]
        self.assertEqual(real["cells"], 1)
        self.assertAlmostEqual(real["metrics"]["ate_m"]["geomean"], 2.0)
        self.assertEqual(real["failed"], [("real/bad_s1", ["B"])])
        self.assertEqual(real["only_a"], ["real/gone_s1"])
        self.assertEqual(real["only_b"], ["real/new_s1"])
        rc, out = capture(["compare", da, db, "--markdown"])
        self.assertIn("real/bad_s1 FAILED in B", out)
        self.assertIn("real/gone_s1 only in A", out)
        self.assertIn("group noise was not run in B", out)
        self.assertIn("| real/bad_s1 | 0.0100 | failed |", out)
        rc, out = capture(["table", da, db])
        self.assertIn("| real | bad_s1 | 0.0100 (0) | failed (exit code 101) |", out)
        self.assertIn("| real | new_s1 | – | 0.0100 (0) |", out)


FAKE_ECVO = textwrap.dedent("""\
    #!/usr/bin/env python3
    # Stands in for `ecvo run SEQ --out DIR ... --frame-step N -q FLAGS`: writes a summary.json
    # whose ATE is the step times 0.01 (times 2 with --worse), fails on a sequence named *bad*,
    # exits with 0 but writes nothing with --no-summary, and counts its calls in SEQ/../calls.
    import json, os, sys
    args = sys.argv[1:]
    seq, out = args[1], args[args.index("--out") + 1]
    step = int(args[args.index("--frame-step") + 1])
    with open(os.path.join(os.path.dirname(seq), "calls"), "a") as f:
        f.write(seq + "\\n")
    if "--no-summary" in args:
        sys.exit(0)
    if "bad" in os.path.basename(seq):
        sys.stderr.write("error: cannot read the sequence\\n")
        sys.exit(3)
    ate = 0.01 * step * (2 if "--worse" in args else 1)
    s = {"ate_rmse_m": ate, "rpe": {"per_second": {"trans_m_per_s": ate, "rot_deg_per_s": 1.0}},
         "lost_frames": 0, "motion_estimations": 10 * step, "frames": 5,
         "ms_per_frame": {"filter": {"median": 1.0, "mean": 1.1},
                          "total": {"median": 3.0, "mean": 3.5}}, "wall_ms_per_frame": 4.0}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(s, f)
    open(os.path.join(out, "cloud.ply"), "w").write("ply")
    """)


class RunTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name
        self.ecvo = os.path.join(self.root, "ecvo")
        with open(self.ecvo, "w") as f:
            f.write(FAKE_ECVO)
        os.chmod(self.ecvo, os.stat(self.ecvo).st_mode | stat.S_IXUSR)
        self.cells = os.path.join(self.root, "cells.tsv")
        for name in ("seq_a", "seq_bad"):
            os.makedirs(os.path.join(self.root, name))
        with open(self.cells, "w") as f:
            f.write("# group\tseq\tstep\nreal\tseq_a\t1\nreal\tseq_a\t2\nweak\tseq_bad\t1\n")

    def tearDown(self):
        self.tmp.cleanup()

    def calls(self):
        with open(os.path.join(self.root, "calls")) as f:
            return len(f.readlines())

    def run_suite(self, label, *flags):
        out = os.path.join(self.root, "out")
        with contextlib.redirect_stderr(io.StringIO()):
            rc, text = capture(["run", "--ecvo", self.ecvo, "--label", label, "--out", out,
                                "--cells", self.cells, "--"] + list(flags))
        with open(os.path.join(out, label, "results.json")) as f:
            return rc, text, json.load(f)

    def test_run_records_failures_and_resumes(self):
        rc, text, res = self.run_suite("base")
        self.assertEqual(rc, 1)  # a failed cell makes the run fail
        self.assertEqual(self.calls(), 3)
        by_id = {c["id"]: c for c in res["cells"]}
        self.assertEqual(sorted(by_id), ["real/seq_a_s1", "real/seq_a_s2", "weak/seq_bad_s1"])
        self.assertAlmostEqual(by_id["real/seq_a_s2"]["ate_m"], 0.02)
        self.assertEqual(by_id["real/seq_a_s2"]["motion_estimations"], 20)
        self.assertEqual(by_id["real/seq_a_s2"]["ms_per_frame"]["total"]["median"], 3.0)
        bad = by_id["weak/seq_bad_s1"]
        self.assertEqual((bad["status"], bad["exit_code"]), ("failed", 3))
        self.assertIn("cannot read the sequence", bad["stderr_tail"])
        self.assertEqual(res["failed"], ["weak/seq_bad_s1"])
        self.assertIn("FAILED", text)
        self.assertFalse(os.path.exists(os.path.join(self.root, "out", "base", "real",
                                                     "seq_a_s1", "cloud.ply")))
        # Resume: the two good cells are not run again, the failed one is.
        rc, text, res = self.run_suite("base")
        self.assertEqual(self.calls(), 4)
        self.assertEqual(res["cells_run_now"], 1)
        self.assertIn("done before", text)
        # Other flags under the same label: everything runs again.
        rc, text, res = self.run_suite("base", "--worse")
        self.assertEqual(self.calls(), 7)
        self.assertAlmostEqual({c["id"]: c for c in res["cells"]}["real/seq_a_s1"]["ate_m"], 0.02)

    def test_a_summary_left_by_an_earlier_run_is_not_taken(self):
        self.run_suite("base")
        rc, text, res = self.run_suite("base", "--no-summary")
        self.assertEqual(rc, 1)
        self.assertEqual([(c["status"], c["error"]) for c in res["cells"]],
                         [("failed", "no summary.json")] * 3)

    def test_run_then_compare(self):
        self.run_suite("base")
        self.run_suite("worse", "--worse")
        out = os.path.join(self.root, "out")
        rows, _ = suite.compare(suite.load_results(os.path.join(out, "base")),
                                suite.load_results(os.path.join(out, "worse")))
        real = [r for r in rows if r["group"] == "real"][0]
        self.assertAlmostEqual(real["metrics"]["ate_m"]["geomean"], 2.0)
        self.assertAlmostEqual(real["metrics"]["drift_rot_deg_per_s"]["geomean"], 1.0)
        weak = [r for r in rows if r["group"] == "weak"][0]
        self.assertEqual(weak["cells"], 0)
        self.assertEqual(weak["failed"], [("weak/seq_bad_s1", ["base", "worse"])])
        self.assertTrue(math.isclose(real["ms_ratio"], 1.0))


class CellsTest(unittest.TestCase):
    def test_json_cells_and_duplicates(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "cells.json")
            with open(path, "w") as f:
                json.dump({"groups": {"g": [["s1", 2], {"seq": "/abs/s2"}]}}, f)
            cells = suite.load_cells(path)
            self.assertEqual([(c["id"], c["seq"], c["step"]) for c in cells],
                             [("g/s1_s2", os.path.join(d, "s1"), 2), ("g/s2_s1", "/abs/s2", 1)])
            with open(path, "w") as f:
                f.write("g s1 1\ng s1 1\n")
            with self.assertRaises(SystemExit):
                suite.load_cells(path)

    def test_default_cells_without_rendered_groups(self):
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "synth"))
            with open(os.path.join(d, "synth", "suite.txt"), "w") as f:
                f.write(os.path.join(d, "synth", "fast_x") + "\n")
            cells, missing = suite.default_cells(d, "/data")
            groups = [c["group"] for c in cells]
            self.assertEqual(groups.count("real"), 12)
            self.assertEqual(groups.count("fast"), 2)  # steps 1 and 2
            self.assertEqual([(m["group"], m["required"]) for m in missing],
                             [("weak", True), ("noise", False), ("pan", False)])


if __name__ == "__main__":
    unittest.main()
