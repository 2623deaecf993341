"""close / with / reset, memory_budget, a tracker shared by two threads, Camera as a
value (hash, pickle, from_matrix, to_dict), Sequence slicing."""

import pickle
import threading

import numpy as np
import pytest

import ecvo


def test_with_closes_and_reset_starts_afresh(synth):
    seq = ecvo.read_sequence(synth, max_frames=10)
    frames = list(seq)
    with ecvo.Tracker(seq.camera) as tracker:
        assert not tracker.closed
        for f in frames:
            tracker.push(*f)
        first = tracker.trajectory()
    assert tracker.closed
    with pytest.raises(ValueError, match="closed"):
        tracker.push(100.0, frames[0][1], frames[0][2])
    with pytest.raises(ValueError, match="closed"):
        tracker.counters()
    assert np.array_equal(tracker.trajectory(), first)  # still readable
    tracker.close()  # idempotent
    tracker.reset()  # reopens
    assert not tracker.closed and len(tracker) == 0 and tracker.state == "initialising"
    for f in frames:
        tracker.push(*f)
    assert np.array_equal(tracker.trajectory(), first)
    assert tracker.counters()["frames"] == 10
    # reset() keeps a changed camera and forgets the timestamps.
    zoomed = ecvo.Camera(320, 180, 260.0, 260.0, 159.5, 89.5, 1000.0)
    tracker.set_intrinsics(zoomed)
    tracker.reset()
    assert tracker.camera == zoomed
    tracker.push(0.0, frames[0][1], frames[0][2])
    assert len(tracker) == 1


def test_exceptions_inside_with_propagate(synth):
    seq = ecvo.read_sequence(synth, max_frames=1)
    with pytest.raises(KeyError):
        with ecvo.Tracker(seq.camera) as tracker:
            raise KeyError("x")
    assert tracker.closed


def test_memory_budget(synth):
    camera = ecvo.read_sequence(synth).camera
    with pytest.raises(ValueError, match="memory"):
        ecvo.Tracker(camera, memory_budget=1 << 20)
    big = ecvo.Camera(4096, 3072, 3000.0, 3000.0, 2047.5, 1535.5, 1000.0)
    with pytest.raises(ValueError, match="budget.*memory_budget=BYTES"):
        ecvo.Tracker(big)
    ecvo.Tracker(big, memory_budget=4 << 30).close()


def test_a_second_thread_gets_a_clear_error(synth):
    seq = ecvo.read_sequence(synth)
    frames = [(k / 30.0, i, d) for k, (_, i, d) in enumerate(list(seq) * 3)]
    tracker = ecvo.Tracker(seq.camera, threads=1)
    errors = []
    started = threading.Event()

    def pusher():
        started.set()
        for f in frames:
            tracker.push(*f)

    th = threading.Thread(target=pusher)
    th.start()
    started.wait()
    # While the other thread is inside push (most of its time, the GIL released),
    # this thread's calls are refused with a message that says why.
    for _ in range(200):
        try:
            len(tracker)
        except RuntimeError as e:
            errors.append(str(e))
    th.join()
    assert errors, "never caught the other thread inside push"
    assert all("in use by another thread" in e for e in errors)
    assert "Already borrowed" not in errors[0]
    assert len(tracker) == len(frames)


def test_camera_is_a_value():
    c = ecvo.Camera(640, 480, 525.0, 525.5, 319.5, 239.5, 5000.0)
    assert pickle.loads(pickle.dumps(c)) == c
    assert hash(pickle.loads(pickle.dumps(c))) == hash(c)
    same = ecvo.Camera(640, 480, 525.0, 525.5, 319.5, 239.5, 5000.0)
    other = ecvo.Camera(640, 480, 525.0, 525.5, 319.5, 239.5, 1000.0)
    assert len({c, same, other}) == 2
    assert {c: 1}[same] == 1
    d = c.to_dict()
    assert d == dict(width=640, height=480, fx=525.0, fy=525.5, cx=319.5, cy=239.5, depth_scale=5000.0)
    assert ecvo.Camera(**d) == c
    k = c.intrinsic_matrix()
    assert ecvo.Camera.from_matrix(k, 640, 480, 5000.0) == c
    assert ecvo.Camera.from_matrix(k.tolist(), 640, 480, 5000.0) == c
    skewed = k.copy()
    skewed[0, 1] = 0.5
    with pytest.raises(ValueError, match="skew"):
        ecvo.Camera.from_matrix(skewed, 640, 480, 5000.0)
    with pytest.raises(ValueError, match="3x3"):
        ecvo.Camera.from_matrix(np.eye(4), 640, 480, 5000.0)
    bad = k.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="fx"):
        ecvo.Camera.from_matrix(bad, 640, 480, 5000.0)


def test_sequence_slicing(synth):
    seq = ecvo.read_sequence(synth)
    part = seq[10:40:3]
    assert isinstance(part, ecvo.Sequence) and len(part) == 10
    assert np.array_equal(part.timestamps, seq.timestamps[10:40:3])
    assert np.array_equal(part[1][1], seq[13][1])
    assert np.array_equal(part[-1][2], seq[37][2])
    assert [f[0] for f in part] == list(seq.timestamps[10:40:3])
    back = seq[::-1]
    assert back[0][0] == seq[59][0] and len(back) == 60
    assert len(seq[5:5]) == 0 and len(seq[100:]) == 0
    assert np.array_equal(part[2:4].timestamps, seq.timestamps[[16, 19]])
    colour = ecvo.read_sequence(synth, colour=True)[3:5]
    assert colour.colour and colour[0][1].shape == (180, 320, 3)
    assert part.groundtruth.shape == (60, 8)  # the whole recording's
    with pytest.raises(TypeError, match="integers or slices"):
        seq["a"]
    with pytest.raises(IndexError):
        part[10]
