"""Tracker.push's FrameResult: the information matrix, the residual scale, the fraction
of the template used, why a frame was lost; and an outside guess seeding MOTION."""

import numpy as np
import pytest

import ecvo


@pytest.fixture(scope="module")
def seq(synth):
    return ecvo.read_sequence(synth)


def test_result_unpacks_as_pose_and_state(seq):
    tracker = ecvo.Tracker(seq.camera)
    t, i, d = seq[0]
    r = tracker.push(t, i, d)
    pose, state = r
    assert pose is not None and np.array_equal(pose, np.eye(4)) and state == "tracking"
    assert len(r) == 2 and r[0] is r.pose or np.array_equal(r[0], r.pose)
    assert r[1] == r[-1] == r.state
    with pytest.raises(IndexError):
        r[2]
    assert isinstance(r, ecvo.FrameResult) and r.index == 0 and r.timestamp == t
    # The first frame has no registration: no information, no scale, no reason.
    assert np.array_equal(r.information, np.zeros((6, 6)))
    assert r.residual_scale is None and r.reason is None and r.point_fraction == 0.0


def test_information_is_spd_on_tracked_frames(seq):
    tracker = ecvo.Tracker(seq.camera)
    results = [tracker.push(*f) for f in seq]
    assert all(r.state == "tracking" for r in results)
    for r in results[1:]:
        h = r.information
        assert h.shape == (6, 6) and h.dtype == np.float64
        assert np.allclose(h, h.T, rtol=0, atol=1e-9 * np.abs(h).max())
        assert np.linalg.eigvalsh(h)[0] > 0, r
        s = r.residual_scale
        assert s.shape == (2, 2) and s[0, 0] > 0 and s[1, 1] > 0 and s[0, 1] == s[1, 0]
        assert 0.5 < r.point_fraction <= 1.0
        assert r.valid_points == round(r.point_fraction * r.template_points)
        assert r.reason is None and r.motion_estimations >= 1
    # The covariance the information implies is small: the synthetic frames register
    # to well under a millimetre and a tenth of a degree.
    cov = np.linalg.inv(results[5].information)
    assert np.sqrt(np.diag(cov)[:3]).max() < np.radians(0.1)
    assert np.sqrt(np.diag(cov)[3:]).max() < 1e-3


def test_information_grows_with_texture(seq):
    """The same frames with the intensity's contrast around mid-grey scaled by k:
    less texture, less information, down to depth alone at k = 0."""
    frames = [seq[k] for k in range(6)]

    def information(k):
        tracker = ecvo.Tracker(seq.camera)
        for t, i, d in frames:
            flat = np.clip(128 + (i.astype(np.float64) - 128) * k, 0, 255).round().astype(np.uint8)
            r = tracker.push(t, flat, d)
        assert r.state == "tracking"
        return r.information

    hs = [information(k) for k in (1.0, 0.5, 0.25, 0.0)]
    logdet = [np.linalg.slogdet(h)[1] for h in hs]
    smallest = [np.linalg.eigvalsh(h)[0] for h in hs]
    assert all(a > b for a, b in zip(logdet, logdet[1:])), logdet
    assert all(a > b for a, b in zip(smallest, smallest[1:])), smallest
    # Measured: the smallest eigenvalue falls about 19-fold from k = 1 to k = 0 with
    # keyframe tracking, the default (about 100-fold with the chain).
    assert smallest[0] > 10 * smallest[-1], smallest


def test_every_lost_frame_has_a_reason(seq):
    tracker = ecvo.Tracker(seq.camera)
    results = []
    h, w = 180, 320
    for k, (t, i, d) in enumerate(seq):
        if k in (10, 11):
            d = np.zeros_like(d)  # a covered lens
            i = np.full_like(i, 30)
        elif k == 20:
            i, d = i[::-1, ::-1].copy(), seq[50][2][::-1, ::-1].copy()  # not this scene
        results.append(tracker.push(t, i, d))
    lost = [r for r in results if r.state == "lost"]
    assert [r.index for r in lost] == [10, 11, 20], [(r.index, r.reason) for r in lost]
    assert all(r.reason is not None for r in lost)
    assert [r.reason for r in lost[:2]] == ["no_valid_depth", "no_valid_depth"]
    assert lost[2].reason in ("inconsistent", "diverged", "spread_jump", "implausible_speed")
    for r in lost:
        assert np.array_equal(r.information, np.zeros((6, 6))) and r.point_fraction == 0.0
    assert all(r.reason is None for r in results if r.state == "tracking")
    assert tracker.counters()["lost_frames"] == 3


def test_an_initial_guess_seeds_the_registration(seq):
    """Frames 0 and 40 of the stream (0.35 m apart) without the frames between: with
    the true pose as the guess the guess wins the coarse start and the result is the
    truth; a guess far off loses to the identity and changes nothing."""
    gt = seq.groundtruth

    def pose_of(row):
        from math import sqrt

        x, y, z, w = row[4:8]
        n = sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x / n, y / n, z / n, w / n
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = r, row[1:4]
        return m

    truth = np.linalg.inv(pose_of(gt[0])) @ pose_of(gt[40])
    (t0, i0, d0), (t1, i1, d1) = seq[0], seq[40]

    def run(**guess):
        tracker = ecvo.Tracker(seq.camera, mode="naive", prior="identity")
        tracker.push(t0, i0, d0, **guess)  # ignored on the first frame
        return tracker.push(t1, i1, d1, **guess)

    plain = run()
    guided = run(initial_guess=truth)
    assert guided.state == "tracking"
    assert np.abs(guided.pose[:3, 3] - truth[:3, 3]).max() < 2e-3
    # The guess reached MOTION: another start, another last bit.
    assert not np.array_equal(guided.pose, plain.pose)
    far = truth.copy()
    far[:3, 3] += [0.8, -0.5, 0.4]
    assert np.abs(run(initial_guess=far).pose - plain.pose).max() < 1e-6
    rotated = run(rotation_guess=truth[:3, :3])
    assert rotated.state == "tracking"
    assert np.abs(rotated.pose[:3, 3] - truth[:3, 3]).max() < 2e-3

    tracker = ecvo.Tracker(seq.camera)
    tracker.push(t0, i0, d0)
    with pytest.raises(ValueError, match="not both"):
        tracker.push(t1, i1, d1, initial_guess=truth, rotation_guess=truth[:3, :3])
    with pytest.raises(ValueError, match="initial_guess.*4x4"):
        tracker.push(t1, i1, d1, initial_guess=np.eye(3))
    with pytest.raises(ValueError, match="not a rotation"):
        tracker.push(t1, i1, d1, initial_guess=np.diag([1.0, 1.0, 2.0, 1.0]))
    with pytest.raises(ValueError, match="last row"):
        bad = np.eye(4)
        bad[3, 0] = 1
        tracker.push(t1, i1, d1, initial_guess=bad)
    with pytest.raises(ValueError, match="rotation_guess.*3x3"):
        tracker.push(t1, i1, d1, rotation_guess=np.eye(4))
    assert len(tracker) == 1
