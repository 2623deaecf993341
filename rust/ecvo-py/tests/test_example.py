"""The example script runs (without matplotlib unless --plot) and writes what the
tracker gives."""

import subprocess
import sys
from pathlib import Path

import numpy as np

import ecvo

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "track_tum.py"


def test_example_tracks_and_writes_the_trajectory(synth, tmp_path):
    out = tmp_path / "est.txt"
    # -X importtime lists every module imported, on stderr.
    p = subprocess.run(
        [sys.executable, "-X", "importtime", str(EXAMPLE), str(synth), "--max-frames", "20", "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert p.returncode == 0, p.stderr
    assert "ATE RMSE" in p.stdout and "20 frames" in p.stdout
    assert "matplotlib" not in p.stderr
    written = np.loadtxt(out)
    seq = ecvo.read_sequence(synth, max_frames=20)
    tracker = ecvo.Tracker(seq.camera)
    for frame in seq:
        tracker.push(*frame)
    assert np.array_equal(written, tracker.trajectory())


def test_inputs_and_quality_example_runs(synth):
    example = EXAMPLE.parent / "inputs_and_quality.py"
    p = subprocess.run(
        [sys.executable, str(example), str(synth), "--max-frames", "30"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert p.returncode == 0, p.stderr
    assert "30 frames, 29 odometry edges" in p.stdout and "ATE RMSE" in p.stdout
    assert "lost" not in p.stderr
