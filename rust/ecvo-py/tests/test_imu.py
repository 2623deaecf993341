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


def short_calibration(seq):
    """Rewrites seq's camera.json with the IMU calibration in short decimals and
    returns it: serde_json's float parsing (ecvo-io's) is not correctly rounded for
    long ones, Python's json is, and an ULP apart the poses would not be bit for bit
    the same."""
    cam = json.loads((seq / "camera.json").read_text())
    imu = cam["imu"]
    imu["camera_from_imu"] = [[round(x, 8) for x in row] for row in imu["camera_from_imu"]]
    imu["time_offset"] = round(imu["time_offset"], 4)
    imu["gyro_noise_density"] = 0.000122
    imu["gyro_bias_random_walk"] = 0.000014
    (seq / "camera.json").write_text(json.dumps(cam))
    return imu


def test_push_imu_tracks_as_ecvo_run_does(pan, cli, tmp_path):
    cal = short_calibration(pan)
    run = tmp_path / "run"
    cli("run", pan, "--out", run, "--frame-step", "3")
    want = np.array(read_tum(run / "trajectory.txt"))
    summary = json.loads((run / "summary.json").read_text())
    assert summary["imu"]["priors"] == len(want) - 1

    imu = np.loadtxt(pan / "imu.txt")
    seq = ecvo.read_sequence(pan, frame_step=3)
    tracker = ecvo.Tracker(
        seq.camera,
        imu_rotation=np.array(cal["camera_from_imu"]),
        imu_time_offset=cal["time_offset"],
        gyro_noise_density=cal["gyro_noise_density"],
        gyro_bias_random_walk=cal["gyro_bias_random_walk"],
    )
    # As ecvo run feeds them (ecvo_io::imu::ImuFeed): every sample stamped up to
    # 5 ms after the frame, the limit computed in the same order on the IMU's clock.
    done = 0
    for t, grey, depth in seq:
        limit = t + 0.005 - cal["time_offset"]
        upto = int(np.searchsorted(imu[:, 0], limit, side="right"))
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


def test_imu_fusion_is_the_cli_flag_with_the_same_default(pan, cli, tmp_path):
    # Off by default, as in ecvo run; imu_fusion=True is --imu-fusion, bit for bit.
    base = ecvo.run_sequence(pan, frame_step=3)
    off = ecvo.run_sequence(pan, frame_step=3, imu_fusion=False)
    on = ecvo.run_sequence(pan, frame_step=3, imu_fusion=True)
    assert np.array_equal(base["trajectory"], off["trajectory"])
    assert not np.array_equal(on["trajectory"], off["trajectory"]), "the setting is applied"
    run = tmp_path / "run"
    cli("run", pan, "--out", run, "--frame-step", "3", "--imu-fusion")
    assert np.array_equal(on["trajectory"], np.array(read_tum(run / "trajectory.txt")))
    seq = ecvo.read_sequence(pan, max_frames=1)
    with pytest.raises(TypeError, match="imu_fusion must be a bool"):
        ecvo.Tracker(seq.camera, imu_fusion="yes")


def test_imu_prior_term_is_the_cli_flag_with_the_same_default(pan, cli, tmp_path):
    # The engine's default whichever it is: no keyword is the CLI without the flag.
    base = ecvo.run_sequence(pan, frame_step=3)
    run = tmp_path / "default"
    cli("run", pan, "--out", run, "--frame-step", "3")
    assert np.array_equal(base["trajectory"], np.array(read_tum(run / "trajectory.txt")))
    for on in (True, False):
        got = ecvo.run_sequence(pan, frame_step=3, imu_prior_term=on)
        run = tmp_path / f"prior-{on}"
        cli("run", pan, "--out", run, "--frame-step", "3", "--imu-prior-term", str(on).lower())
        assert np.array_equal(got["trajectory"], np.array(read_tum(run / "trajectory.txt")))
    on = ecvo.run_sequence(pan, frame_step=3, imu_prior_term=True)["trajectory"]
    off = ecvo.run_sequence(pan, frame_step=3, imu_prior_term=False)["trajectory"]
    assert not np.array_equal(on, off), "the setting is applied"
    seq = ecvo.read_sequence(pan, max_frames=1)
    with pytest.raises(TypeError, match="imu_prior_term must be a bool"):
        ecvo.Tracker(seq.camera, imu_prior_term=1.5)


def test_depth_timestamp_turns_the_depth_as_ecvo_run_does(cli, tmp_path):
    # A pan whose depth images are taken 15 ms after the intensity (stamped so in
    # depth.txt): Tracker.push(depth_timestamp=) turns each depth to the intensity's
    # time with the gyro, bit for bit as ecvo run does; imu_depth_time=False is the
    # CLI's --imu-depth-time false, and leaves the depth as it is.
    seq_dir = tmp_path / "delayed"
    cli("synth", "--out", seq_dir, "--motion", "pan", "--max-rot-speed", "200", "--frames", "18",
        "--seed", "4", "--depth-delay-ms", "15")
    imu = short_calibration(seq_dir)
    run = tmp_path / "run"
    cli("run", seq_dir, "--out", run)
    want = np.array(read_tum(run / "trajectory.txt"))
    assert json.loads((run / "summary.json").read_text())["imu"]["depth_turned"] == len(want)

    samples = np.loadtxt(seq_dir / "imu.txt")
    depth_stamps = np.loadtxt(seq_dir / "depth.txt", usecols=0)
    seq = ecvo.read_sequence(seq_dir)
    tracker = ecvo.Tracker(
        seq.camera,
        imu_rotation=np.array(imu["camera_from_imu"]),
        imu_time_offset=imu["time_offset"],
        gyro_noise_density=imu["gyro_noise_density"],
        gyro_bias_random_walk=imu["gyro_bias_random_walk"],
    )
    done = 0
    for (t, grey, depth), td in zip(seq, depth_stamps):
        # As ecvo run feeds them: up to 5 ms after the later of the two images.
        limit = max(t, td) + 0.005 - imu["time_offset"]
        upto = int(np.searchsorted(samples[:, 0], limit, side="right"))
        tracker.push_imu(samples[done:upto, 0], samples[done:upto, 1:4])
        done = upto
        tracker.push(t, grey, depth, depth_timestamp=td)
    got = tracker.trajectory()
    assert np.array_equal(got, want), np.abs(got - want).max()
    assert tracker.counters()["imu"]["depth_turned"] == len(want)

    off = ecvo.run_sequence(seq_dir, imu_depth_time=False)
    run_off = tmp_path / "off"
    cli("run", seq_dir, "--out", run_off, "--imu-depth-time", "false")
    assert np.array_equal(off["trajectory"], np.array(read_tum(run_off / "trajectory.txt")))
    assert off["counters"]["imu"]["depth_turned"] == 0
    assert not np.array_equal(off["trajectory"], want), "the setting is applied"
    with pytest.raises(TypeError, match="imu_depth_time must be a bool"):
        ecvo.Tracker(seq.camera, imu_depth_time="no")
    t, grey, depth = seq[0]
    with pytest.raises(ValueError, match="depth timestamp NaN is not finite"):
        ecvo.Tracker(seq.camera).push(t, grey, depth, depth_timestamp=float("nan"))
