"""Tests of timing.py, the statistics of the peers' benches (standard library only):

    python3 -m unittest discover -s scripts/peers -p 'test_*.py'
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import timing

HERE = os.path.dirname(os.path.abspath(__file__))


def ecvo_summary_json(filter_stats, tracker_stats, simd="avx2"):
    """A summary.json with the parts timing.py reads (the stage figures as ecvo writes
    them: frames, median_ms, mean_ms, p95_ms, max_ms)."""
    def stage(median, mean, p95, frames=10):
        return {"frames": frames, "median_ms": median, "mean_ms": mean, "p95_ms": p95,
                "max_ms": p95 * 2}
    return {"simd": simd, "frames": 10,
            "pipeline": {"stages": {"filter": stage(*filter_stats),
                                    "tracker": stage(*tracker_stats),
                                    "latency": stage(99.0, 99.0, 99.0)}}}


class Percentile(unittest.TestCase):
    def test_nearest_rank_of_one_to_twenty(self):
        xs = list(range(20, 0, -1))  # unsorted on purpose
        self.assertEqual(timing.percentile(xs, 0.95), 19)  # ceil(19.0) = 19th
        self.assertEqual(timing.percentile(xs, 0.5), 10)
        self.assertEqual(timing.percentile(xs, 1.0), 20)
        self.assertEqual(timing.percentile(xs, 0.01), 1)

    def test_rank_rounds_up(self):
        xs = list(range(1, 11))  # 0.95 * 10 = 9.5 -> the 10th
        self.assertEqual(timing.percentile(xs, 0.95), 10)
        self.assertEqual(timing.percentile(xs, 0.9), 9)  # exactly 9, not 10
        self.assertEqual(timing.percentile([7.5], 0.95), 7.5)

    def test_rejects_empty_and_bad_quantiles(self):
        with self.assertRaises(ValueError):
            timing.percentile([], 0.5)
        for q in (0.0, -0.1, 1.5):
            with self.assertRaises(ValueError):
                timing.percentile([1.0], q)


class Summary(unittest.TestCase):
    def test_tail_moves_mean_and_p95_not_median(self):
        xs = [1.0] * 18 + [10.0, 100.0]
        s = timing.summary(xs)
        self.assertEqual(s["median"], 1.0)
        self.assertAlmostEqual(s["mean"], 128.0 / 20)
        self.assertEqual(s["p95"], 10.0)
        self.assertEqual(s["frames"], 20)

    def test_even_count_median_is_the_midpoint(self):
        self.assertEqual(timing.summary([4.0, 1.0, 3.0, 2.0])["median"], 2.5)

    def test_empty_is_nan(self):
        s = timing.summary([])
        self.assertTrue(all(math.isnan(s[k]) for k in timing.STATS))
        self.assertEqual(s["frames"], 0)


class RowTiming(unittest.TestCase):
    def test_headline_clock_and_process_over_thread(self):
        info = {"clock": "process_cpu", "process_ms": [4.0, 6.0, 8.0],
                "thread_ms": [2.0, 3.0, 4.0], "wall_ms": [3.0, 3.0, 3.0]}
        row = timing.row_timing(info)
        self.assertEqual(row["clock"], "process_cpu")
        self.assertEqual(row["ms_per_frame"], row["process_cpu_ms_per_frame"])
        self.assertEqual(row["ms_per_frame"]["median"], 6.0)
        self.assertEqual(row["thread_cpu_ms_per_frame"]["mean"], 3.0)
        self.assertAlmostEqual(row["process_over_thread"], 2.0)
        self.assertEqual(row["ms_per_frame_median"], 6.0)
        self.assertEqual(row["wall_ms_per_frame_median"], 3.0)

    def test_thread_clock_without_process_times(self):
        row = timing.row_timing({"clock": "thread_cpu", "thread_ms": [1.0, 2.0, 9.0],
                                 "wall_ms": [1.0, 2.0, 9.0], "process_ms": []})
        self.assertEqual(row["ms_per_frame"]["median"], 2.0)
        self.assertEqual(row["ms_per_frame"]["p95"], 9.0)
        self.assertIsNone(row["process_over_thread"])
        self.assertTrue(math.isnan(row["process_cpu_ms_per_frame"]["mean"]))


class EcvoAndRatios(unittest.TestCase):
    def test_ecvo_is_filter_plus_tracker(self):
        e = timing.ecvo_summary(ecvo_summary_json((2.0, 3.0, 6.0), (1.0, 1.5, 2.0)))
        self.assertEqual((e["median"], e["mean"], e["p95"]), (3.0, 4.5, 8.0))
        self.assertEqual(e["filter"]["p95"], 6.0)
        self.assertTrue(e["exact"]["mean"])
        self.assertFalse(e["exact"]["median"])

    def test_per_frame_cpu_figures_win_when_present(self):
        s = ecvo_summary_json((2.0, 3.0, 6.0), (1.0, 1.5, 2.0))
        st = s["pipeline"]["stages"]
        st["work"] = {"frames": 10, "median_ms": 3.1, "mean_ms": 4.5, "p95_ms": 7.0,
                      "max_ms": 9.0}
        st["work_cpu"] = {"frames": 10, "median_ms": 2.9, "mean_ms": 4.2, "p95_ms": 6.5,
                          "max_ms": 8.0}
        e = timing.ecvo_summary(s)
        self.assertEqual((e["median"], e["mean"], e["p95"]), (2.9, 4.2, 6.5))
        self.assertEqual(e["clock"], "thread_cpu")
        self.assertEqual(e["wall"]["p95"], 7.0)
        self.assertTrue(all(e["exact"].values()))
        # A run on a platform without a thread CPU clock reports zeros: fall back.
        st["work_cpu"]["mean_ms"] = 0.0
        e = timing.ecvo_summary(s)
        self.assertEqual((e["median"], e["clock"]), (3.0, "wall"))

    def test_ratios_are_peer_over_ecvo(self):
        q = timing.ratios({"mean": 4.0, "median": 2.0}, {"mean": 1.0, "median": 3.0})
        self.assertEqual(q, {"mean": 0.25, "median": 1.5})

    def test_spread(self):
        self.assertEqual(timing.spread([3.0, 1.0, 2.0, 10.0]), (2.5, 1.0, 10.0))


class RoundAndReport(unittest.TestCase):
    """The path bench-vs-peer.sh takes: `timing.py round` per round, then `report`."""

    def write_round(self, root, r, ecvo_stats, peer_ms):
        d = os.path.join(root, f"round{r}")
        os.makedirs(os.path.join(d, "ecvo"))
        os.makedirs(os.path.join(d, "vors"))
        with open(os.path.join(d, "ecvo", "summary.json"), "w") as f:
            json.dump(ecvo_summary_json(*ecvo_stats), f)
        row = {"peer": "vors"}
        row.update(timing.row_timing({"clock": "thread_cpu", "thread_ms": peer_ms,
                                      "wall_ms": peer_ms, "process_ms": peer_ms}))
        row["threads"] = {"max_seen": 1}
        with open(os.path.join(d, "vors", "peers.json"), "w") as f:
            json.dump({"rows": [row]}, f)
        return d

    def run_tool(self, *args):
        r = subprocess.run([sys.executable, os.path.join(HERE, "timing.py"), *args],
                           capture_output=True, text=True, check=True)
        return r.stdout, r.stderr

    def test_two_rounds(self):
        with tempfile.TemporaryDirectory() as root:
            # Round 1: ecvo 3 / 4 / 8 ms, vors 1 / 2 / 5: ratios of means 0.5, medians 1/3.
            d1 = self.write_round(root, 1, ((2.0, 3.0, 6.0), (1.0, 1.0, 2.0)),
                                  [1.0, 1.0, 1.0, 2.0, 5.0])
            # bash's `time` output (user, system seconds) over ecvo's 10 frames.
            with open(os.path.join(d1, "ecvo.cpu"), "w") as f:
                f.write("0.100 0.020\n")
            # Round 2: ecvo 2 / 2 / 4 ms, vors 1 / 1.5 / 3: 0.75 and 0.5.
            d2 = self.write_round(root, 2, ((1.0, 1.0, 2.0), (1.0, 1.0, 2.0)),
                                  [1.0, 1.0, 1.0, 3.0])
            lines = []
            for r, d in ((1, d1), (2, d2)):
                out, err = self.run_tool("round", d, "seq", str(r), "vors")
                rec = json.loads(out)
                lines.append(out)
                self.assertIn(f"seq round {r}:", err)
                if r == 1:
                    self.assertAlmostEqual(rec["ecvo_process_cpu_ms_per_frame"], 12.0)
                    self.assertAlmostEqual(rec["ratio"]["mean"], 0.5)
                    self.assertAlmostEqual(rec["ratio"]["median"], 1 / 3)
                else:
                    self.assertNotIn("ecvo_process_cpu_ms_per_frame", rec)
            self.assertAlmostEqual(rec["ratio"]["mean"], 0.75)
            self.assertAlmostEqual(rec["ratio"]["median"], 0.5)
            self.assertEqual(rec["peer_clock"], "thread_cpu")
            self.assertEqual(rec["peer_ms"]["p95"], 3.0)
            jsonl = os.path.join(root, "rounds.jsonl")
            with open(jsonl, "w") as f:
                f.writelines(lines)
            bench = os.path.join(root, "bench.json")
            out, _ = self.run_tool("report", jsonl, bench, "vors")
            with open(bench) as f:
                b = json.load(f)["seq"]
        self.assertAlmostEqual(b["ratio_of_means"]["median"], 0.625)
        self.assertAlmostEqual(b["ratio_of_means"]["min"], 0.5)
        self.assertAlmostEqual(b["ratio_of_means"]["max"], 0.75)
        self.assertAlmostEqual(b["ratio_of_medians"]["median"], (1 / 3 + 0.5) / 2)
        self.assertEqual(b["ecvo_simd"], ["avx2"])
        self.assertIn("| seq | 2 | 2.50 / 3.00 / 6.00 | 1.00 / 1.75 / 4.00 | "
                      "**0.62 (0.50-0.75)** | 0.42 (0.33-0.50) |", out)


if __name__ == "__main__":
    unittest.main()
