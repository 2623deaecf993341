"""The API's types, and bad input: clear ValueError/TypeError, never a crash."""

import math

import numpy as np
import pytest

import ecvo


def camera():
    return ecvo.Camera(320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0)


def frame(h=180, w=320):
    return np.zeros((h, w), np.uint8), np.full((h, w), 1500, np.uint16)


def test_camera_fields_and_json(synth):
    c = camera()
    assert (c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.depth_scale) == (
        320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0,
    )
    assert c == ecvo.Camera.from_json(synth / "camera.json")
    assert c == ecvo.read_sequence(synth).camera
    assert np.array_equal(c.intrinsic_matrix(), [[250, 0, 159.5], [0, 250, 89.5], [0, 0, 1]])
    assert "Camera(width=320" in repr(c)


@pytest.mark.parametrize(
    "args, field",
    [
        ((320, 180, math.nan, 250.0, 159.5, 89.5, 1000.0), "fx"),
        ((320, 180, 250.0, math.inf, 159.5, 89.5, 1000.0), "fy"),
        ((320, 180, 250.0, 250.0, math.nan, 89.5, 1000.0), "cx"),
        ((320, 180, 250.0, 250.0, 159.5, 89.5, 0.0), "depth_scale"),
        ((320, 180, 250.0, 250.0, 159.5, 89.5, -5.0), "depth_scale"),
        ((0, 180, 250.0, 250.0, 159.5, 89.5, 1000.0), "width"),
        ((-320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0), "width"),
    ],
)
def test_bad_intrinsics_are_value_errors(args, field):
    with pytest.raises(ValueError, match=field):
        ecvo.Camera(*args)


def test_camera_wants_numbers():
    with pytest.raises(TypeError):
        ecvo.Camera("320", 180, 250.0, 250.0, 159.5, 89.5, 1000.0)


def test_read_sequence(synth):
    seq = ecvo.read_sequence(synth)
    assert len(seq) == 60
    t, i, d = seq[0]
    assert i.dtype == np.uint8 and i.shape == (180, 320) and i.flags.c_contiguous
    assert d.dtype == np.uint16 and d.shape == (180, 320)
    assert t == seq.timestamps[0]
    assert seq[-1][0] == seq.timestamps[59]
    assert np.array_equal(seq[-60][1], i)
    with pytest.raises(IndexError):
        seq[60]
    assert sum(1 for _ in seq) == 60
    it = iter(ecvo.read_sequence(synth, max_frames=2))
    assert iter(it) is it
    first, second = next(it), next(it)
    assert first[0] == t and np.array_equal(first[2], d)
    assert second[0] == seq.timestamps[1]
    with pytest.raises(StopIteration):
        next(it)
    with pytest.raises(StopIteration):
        next(it)
    assert seq.groundtruth.shape == (60, 8)
    assert len(ecvo.read_sequence(synth, max_frames=7)) == 7
    stepped = ecvo.read_sequence(synth, frame_step=3)
    assert len(stepped) == 20 and stepped.timestamps[1] == seq.timestamps[3]


def test_missing_sequence_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        ecvo.read_sequence(tmp_path / "nope")
    with pytest.raises(FileNotFoundError):
        ecvo.run_sequence(tmp_path / "nope")
    with pytest.raises(ValueError, match="layout|rgb.txt|associations"):
        ecvo.read_sequence(tmp_path)


@pytest.mark.parametrize(
    "intensity, depth, exc, words",
    [
        (np.zeros((180, 320), np.float16), None, TypeError, "intensity.*uint8.*float16"),
        (np.full((180, 320), 1.5, np.float32), None, ValueError, r"intensity.*\[0, 1\].*1.5"),
        (np.full((180, 320), np.nan, np.float32), None, ValueError, r"intensity.*\[0, 1\]"),
        (np.zeros((180, 320, 3), np.float32), None, TypeError, "intensity.*dtype"),
        (None, np.zeros((180, 320), np.int32), TypeError, "depth.*uint16.*int32"),
        (None, np.zeros((180, 320), np.uint8), TypeError, "depth.*uint16"),
        (None, np.full((180, 320), -1.0, np.float32), ValueError, "depth.*metres.*-1"),
        (None, np.full((180, 320), np.inf, np.float32), ValueError, "depth.*metres.*inf"),
        (None, np.full((180, 320), 70.0, np.float32), ValueError, r"depth.*65\.535.*70"),
        (np.zeros((180, 321), np.uint8), None, ValueError, r"intensity.*\(180, 320\).*\(180, 321\)"),
        (np.zeros((320, 180), np.uint8), None, ValueError, "intensity.*shape"),
        (np.zeros((180, 320, 2), np.uint8), None, ValueError, "intensity.*shape"),
        (None, np.zeros(180 * 320, np.uint16), ValueError, "depth.*shape"),
        ([[0] * 320] * 180, None, TypeError, "intensity.*dtype.*int64"),
        (None, b"\x00" * (2 * 180 * 320), TypeError, "depth.*numpy.ndarray.*buffer protocol.*bytes"),
        (object(), None, TypeError, "intensity.*numpy.ndarray.*object"),
    ],
)
def test_bad_frames_raise(intensity, depth, exc, words):
    tracker = ecvo.Tracker(camera())
    good_i, good_d = frame()
    with pytest.raises(exc, match=words):
        tracker.push(0.0, good_i if intensity is None else intensity, good_d if depth is None else depth)
    # Nothing was tracked, and the tracker still works.
    assert len(tracker) == 0
    tracker.push(0.0, good_i, good_d)
    assert len(tracker) == 1


def test_bad_timestamps_raise():
    tracker = ecvo.Tracker(camera())
    i, d = frame()
    with pytest.raises(ValueError, match="finite"):
        tracker.push(math.nan, i, d)
    tracker.push(1.0, i, d)
    with pytest.raises(ValueError, match="not after"):
        tracker.push(1.0, i, d)
    with pytest.raises(ValueError, match="not after"):
        tracker.push(0.5, i, d)
    with pytest.raises(TypeError):
        tracker.push("2.0", i, d)
    tracker.push(2.0, i, d)
    assert len(tracker) == 2


def test_bad_settings_raise(synth):
    c = camera()
    with pytest.raises(TypeError, match="camera must be an ecvo.Camera"):
        ecvo.Tracker("camera.json")
    with pytest.raises(ValueError, match="preset"):
        ecvo.Tracker(c, preset="tablet")
    with pytest.raises(ValueError, match="mode"):
        ecvo.Tracker(c, mode="l3")
    with pytest.raises(TypeError, match="unexpected keyword argument 'levelz'"):
        ecvo.Tracker(c, levelz="30mm:7deg")
    with pytest.raises(TypeError, match="bilateral must be a bool"):
        ecvo.Tracker(c, bilateral="no")
    with pytest.raises(ValueError, match="weighting must be one of"):
        ecvo.Tracker(c, weighting="cubic")
    with pytest.raises(ValueError, match="levels"):
        ecvo.Tracker(c, levels="30 millimetres")
    with pytest.raises(ValueError, match="needs at least 2"):
        ecvo.Tracker(c, mode="l2", levels="30mm:7deg")
    with pytest.raises(ValueError, match="NaN"):
        ecvo.Tracker(c, min_update_px=math.nan)
    with pytest.raises(ValueError, match="threads"):
        ecvo.Tracker(c, threads=0)
    with pytest.raises(ValueError, match="threads"):
        ecvo.run_sequence(synth, threads=0)
    with pytest.raises(ValueError, match="frame_step"):
        ecvo.run_sequence(synth, frame_step=0)
    with pytest.raises(TypeError, match="memory_budget must be an int"):
        ecvo.Tracker(c, memory_budget="lots")
    with pytest.raises(TypeError, match="unexpected keyword argument"):
        ecvo.run_sequence(synth, out="/tmp")


def test_bad_trajectories_raise(synth):
    gt = ecvo.read_sequence(synth).groundtruth
    with pytest.raises(ValueError, match=r"\(N, 8\)"):
        ecvo.ate(gt, gt[:, :7])
    with pytest.raises(ValueError, match="3"):
        ecvo.ate(gt, gt[:2])
    with pytest.raises(TypeError, match="est must be"):
        ecvo.ate(gt, object())
    back = gt[::-1].copy()
    with pytest.raises(ValueError, match="increasing"):
        ecvo.ate(gt, back)
    nan = gt.copy()
    nan[3, 2] = math.nan
    with pytest.raises(ValueError, match="non-finite"):
        ecvo.ate(nan, gt)
    with pytest.raises(FileNotFoundError):
        ecvo.ate(synth / "missing.txt", gt)


def test_camera_override_and_intrinsics_change(synth):
    c = camera()
    r = ecvo.run_sequence(synth, camera=c, max_frames=5)
    assert r["camera"] == c
    r2 = ecvo.run_sequence(synth, camera=str(synth / "camera.json"), max_frames=5)
    assert np.array_equal(r["trajectory"], r2["trajectory"])
    tracker = ecvo.Tracker(c)
    with pytest.raises(ValueError, match="size"):
        tracker.set_intrinsics(ecvo.Camera(640, 480, 525.0, 525.0, 319.5, 239.5, 5000.0))
    tracker.set_intrinsics(ecvo.Camera(320, 180, 260.0, 260.0, 159.5, 89.5, 1000.0))
    assert tracker.camera.fx == 260.0


def test_states_and_counters():
    tracker = ecvo.Tracker(camera())
    assert tracker.state == "initialising"
    i, d = frame()
    pose, state = tracker.push(0.0, i, d)
    assert np.array_equal(pose, np.eye(4))
    # A blank frame has no texture or shape to register against.
    tracker.push(0.033, i, np.zeros_like(d))
    assert tracker.states()[1] == "lost" == tracker.state
    assert tracker.counters()["lost_frames"] == 1
    assert tracker.counters()["frames"] == 2
