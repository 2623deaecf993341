"""Gyroscope samples through Python (issue 47): Tracker.push_imu tracks a simulated
fast pan bit for bit as ``ecvo run`` does with its imu.txt, and bad samples are
refused with clear errors. The IMU here is simulated (``ecvo synth``)."""

import json

import numpy as np
import pytest

import ecvo
from conftest import read_tum


@pytest.fixture(scope="module")
def pan(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("pan") / "pan"
    cli("synth", "--out", out, "--motion", "pan", "--max-rot-speed", "200", "--frames", "24", "--seed", "5")
    return out


def test_push_imu_tracks_as_ecvo_run_does(pan, cli, tmp_path):
    run = tmp_path / "run"
    cli("run", pan, "--out", run, "--frame-step", "3")
    want = np.array(read_tum(run / "trajectory.txt"))
    summary = json.loads((run / "summary.json").read_text())
    assert summary["imu"]["priors"] == len(want) - 1

    imu = np.loadtxt(pan / "imu.txt")
    cal = json.loads((pan / "camera.json").read_text())["imu"]
    seq = ecvo.read_sequence(pan, frame_step=3)
    tracker = ecvo.Tracker(
        seq.camera,
        imu_rotation=np.array(cal["camera_from_imu"]),
        imu_time_offset=cal["time_offset"],
        gyro_noise_density=cal["gyro_noise_density"],
        gyro_bias_random_walk=cal["gyro_bias_random_walk"],
    )
    # As ecvo run feeds them: every sample up to 5 ms after the frame.
    frames_clock = imu[:, 0] + cal["time_offset"]
    done = 0
    for t, grey, depth in seq:
        upto = int(np.searchsorted(frames_clock, t + 0.005, side="right"))
        tracker.push_imu(imu[done:upto, 0], imu[done:upto, 1:4])
        done = upto
        tracker.push(t, grey, depth)
    got = tracker.trajectory()
    assert np.array_equal(got, want), np.abs(got - want).max()
    c = tracker.counters()["imu"]
    assert c["priors"] == len(want) - 1 and c["late"] == 0 and c["missing"] == 0
    # run_sequence reads the folder's imu.txt as ecvo run does.
    r = ecvo.run_sequence(pan, frame_step=3)
    assert np.array_equal(r["trajectory"], want)
    off = ecvo.run_sequence(pan, frame_step=3, imu=False)
    assert off["counters"]["imu"]["samples"] == 0


def test_bad_imu_samples_are_refused(synth):
    seq = ecvo.read_sequence(synth, max_frames=1)
    tracker = ecvo.Tracker(seq.camera)
    with pytest.raises(ValueError, match="not finite"):
        tracker.push_imu([0.0, 0.01], [[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match="shape"):
        tracker.push_imu([0.0, 0.01], [[0, 0, 0]])
    tracker.push_imu([1.0, 1.0, 0.5, 1.01], np.zeros((4, 3)))
    c = tracker.counters()["imu"]
    assert (c["samples"], c["refused"]) == (2, 2)
    with pytest.raises(ValueError, match="imu_rotation"):
        ecvo.Tracker(seq.camera, imu_rotation=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="time_offset"):
        ecvo.Tracker(seq.camera, imu_time_offset=5.0)
