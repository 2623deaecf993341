"""The package tracks bit for bit as `ecvo run` does, and its ATE is `ecvo eval`'s."""

import json

import numpy as np
import pytest

import ecvo
from conftest import read_tum


def cli_trajectory(out):
    rows = np.array(read_tum(out / "trajectory.txt"), dtype=np.float64)
    assert rows.shape[1] == 8
    return rows


def test_run_sequence_is_bit_identical_to_ecvo_run(synth, cli_run):
    cli = cli_trajectory(cli_run())
    r = ecvo.run_sequence(synth)
    assert r["trajectory"].shape == (60, 8)
    # Exact: trajectory.txt holds round-trip precision, so equal floats or a failure.
    assert np.array_equal(r["trajectory"], cli), np.abs(r["trajectory"] - cli).max()
    summary = json.loads((cli_run() / "summary.json").read_text())
    c = r["counters"]
    assert c["frames"] == summary["frames"] == 60
    assert c["motion_estimations"] == summary["motion_estimations"]
    assert c["references"] == summary["references"]
    assert c["lost_frames"] == summary["lost_frames"]
    assert r["ate"]["rmse"] == summary["ate_rmse_m"]


def test_run_sequence_ate_under_2mm(synth):
    r = ecvo.run_sequence(synth)
    assert r["ate"] is not None
    assert r["ate"]["count"] == 60
    assert r["ate"]["rmse"] < 0.002
    assert set(r["states"]) == {"tracking"}


@pytest.mark.parametrize(
    "flags, settings",
    [
        (("--mode", "naive", "--max-frames", "40"), dict(mode="naive", max_frames=40)),
        (
            ("--preset", "phone", "--mode", "l1", "--weighting", "scalar", "--frame-step", "2"),
            dict(preset="phone", mode="l1", weighting="scalar", frame_step=2),
        ),
        (
            ("--paper", "--levels", "20mm:5deg,80mm:10deg", "--threads", "1"),
            dict(paper=True, levels="20mm:5deg,80mm:10deg", threads=1),
        ),
        (
            ("--tracking", "keyframe", "--keyframe-overlap", "0.6", "--max-frames", "60"),
            dict(tracking="keyframe", keyframe_overlap=0.6, max_frames=60),
        ),
    ],
)
def test_settings_map_to_the_same_flags(synth, cli_run, flags, settings):
    cli = cli_trajectory(cli_run(*flags))
    r = ecvo.run_sequence(synth, **settings)
    assert np.array_equal(r["trajectory"], cli)


def test_tracker_push_is_bit_identical_to_ecvo_run(synth, cli_run):
    cli = cli_trajectory(cli_run())
    seq = ecvo.read_sequence(synth)
    tracker = ecvo.Tracker(seq.camera, preset="pc", mode="l2")
    for k, (t, intensity, depth) in enumerate(seq):
        pose, state = tracker.push(t, intensity, depth)
        assert pose.shape == (4, 4) and pose.dtype == np.float64
        assert state == "tracking"
        # The returned matrix is the trajectory's pose.
        assert np.array_equal(pose[:3, 3], cli[k, 1:4])
    assert np.array_equal(tracker.trajectory(), cli)
    assert len(tracker) == 60
    assert tracker.poses().shape == (60, 4, 4)
    assert np.array_equal(tracker.timestamps(), cli[:, 0])
    assert tracker.counters()["frames"] == 60


def test_strided_arrays_track_as_contiguous_ones(synth):
    seq = ecvo.read_sequence(synth, max_frames=12)
    a = ecvo.Tracker(seq.camera)
    b = ecvo.Tracker(seq.camera, threads=1)
    for t, intensity, depth in seq:
        a.push(t, intensity, depth)
        # Fortran order, and a view into a wider buffer with a column stride.
        wide = np.zeros((depth.shape[0], depth.shape[1] * 2), dtype=np.uint16)
        wide[:, ::2] = depth
        view = wide[:, ::2]
        assert not view.flags.c_contiguous
        b.push(t, np.asfortranarray(intensity), view)
    assert np.array_equal(a.trajectory(), b.trajectory())


def test_ate_agrees_with_ecvo_eval(synth, cli, cli_run):
    est = cli_run() / "trajectory.txt"
    gt = synth / "groundtruth.txt"
    ev = json.loads(cli("eval", "--json", gt, est))
    from_files = ecvo.ate(gt, est)
    seq = ecvo.read_sequence(synth)
    from_arrays = ecvo.ate(seq.groundtruth, cli_trajectory(cli_run()))
    from_lists = ecvo.ate(seq.groundtruth.tolist(), str(est))
    for a in (from_files, from_arrays, from_lists):
        assert a["rmse"] == ev["ate_rmse_m"]
        for key in ("mean", "median", "std", "min", "max"):
            assert a[key] == ev["ate"][key + "_m"], key
        assert a["count"] == ev["ate"]["pairs"]
        assert a["alignment"].shape == (4, 4)
        assert a["errors"].shape == (a["count"],)
        assert np.isclose(np.sqrt(np.mean(a["errors"] ** 2)), a["rmse"], rtol=1e-12)


def test_ate_of_a_shifted_estimate_is_zero_and_a_bent_one_is_not(synth):
    gt = ecvo.read_sequence(synth).groundtruth
    moved = gt.copy()
    moved[:, 1:4] += [0.5, -0.25, 2.0]
    assert ecvo.ate(gt, moved)["rmse"] < 1e-12
    bent = gt.copy()
    bent[30:, 1] += 0.01
    a = ecvo.ate(gt, bent)
    assert 0.001 < a["rmse"] < 0.01
