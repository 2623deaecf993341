"""The inputs researchers have (float metres, colour, buffer-protocol objects, masked
arrays) give the poses of the equivalent uint16 / grey input."""

import numpy as np
import pytest

import ecvo


@pytest.fixture(scope="module")
def frames(synth):
    seq = ecvo.read_sequence(synth, max_frames=30)
    return seq.camera, list(seq)


def track(camera, frames, **push):
    tracker = ecvo.Tracker(camera)
    for t, i, d in frames:
        tracker.push(t, i, d, **push)
    return tracker.trajectory()


def grey(rgb):
    """ecvo-io's rgb_to_gray, in numpy."""
    r, g, b = (rgb[..., k].astype(np.uint32) for k in range(3))
    return ((299 * r + 587 * g + 114 * b + 500) // 1000).astype(np.uint8)


def colour_of(g):
    """A colour image whose grey is exactly g, with channels that differ (so that a
    wrong channel order changes the grey): R = g + 20, G = g - 10 where they fit."""
    g16 = g.astype(np.int16)
    fits = (g16 >= 10) & (g16 <= 235)
    rgb = np.stack([g16 + 20 * fits, g16 - 10 * fits, g16], axis=-1).astype(np.uint8)
    assert np.array_equal(grey(rgb), g)
    return rgb


def test_float_metres_give_the_uint16_poses(frames):
    camera, fr = frames
    base = track(camera, fr)
    # float32 metres converted from the raw units, the missing depth as NaN or 0.
    metres = []
    for k, (t, i, d) in enumerate(fr):
        m = d.astype(np.float32) / np.float32(camera.depth_scale)
        if k % 2:
            m[d == 0] = np.nan
        metres.append((t, i, m))
    est = track(camera, metres)
    assert np.abs(est[:, 1:4] - base[:, 1:4]).max() <= 1e-9
    assert np.array_equal(est, base)  # the conversion is exact: bit for bit
    est64 = track(camera, [(t, i, d.astype(np.float64) / camera.depth_scale) for t, i, d in fr])
    assert np.abs(est64[:, 1:4] - base[:, 1:4]).max() <= 1e-9


def test_colour_gives_the_grey_poses_in_either_channel_order(frames):
    camera, fr = frames
    base = track(camera, fr)
    rgb = [(t, colour_of(i), d) for t, i, d in fr]
    assert np.array_equal(track(camera, rgb), base)
    bgr = [(t, np.ascontiguousarray(c[..., ::-1]), d) for t, c, d in rgb]
    assert np.array_equal(track(camera, bgr, channels="bgr"), base)
    # A strided view (no copy by the caller) reads the same.
    assert np.array_equal(track(camera, [(t, c[..., ::-1], d) for t, c, d in rgb], channels="bgr"), base)
    # The wrong order is a different image: other poses.
    assert not np.array_equal(track(camera, bgr), base)
    rgba = [(t, np.dstack([c, np.full(c.shape[:2], 7, np.uint8)]), d) for t, c, d in rgb]
    assert np.array_equal(track(camera, rgba), base)
    with pytest.raises(ValueError, match="channels"):
        ecvo.Tracker(camera).push(0.0, rgb[0][1], rgb[0][2], channels="rgba")


def test_float_grey_as_open3d_holds_it(frames):
    camera, fr = frames
    base = track(camera, fr)
    est = track(camera, [(t, i.astype(np.float32) / np.float32(255), d) for t, i, d in fr])
    assert np.array_equal(est, base)


def test_read_sequence_colour(synth):
    seq = ecvo.read_sequence(synth, colour=True, max_frames=3)
    grey_seq = ecvo.read_sequence(synth, max_frames=3)
    assert seq.colour and not grey_seq.colour
    t, c, d = seq[1]
    tg, g, dg = grey_seq[1]
    assert c.shape == (180, 320, 3) and c.dtype == np.uint8
    assert t == tg and np.array_equal(d, dg) and np.array_equal(grey(c), g)


def test_buffer_protocol_and_array_likes(frames):
    camera, fr = frames
    base = track(camera, fr[:10])

    class Image:
        """Like open3d.geometry.Image: the buffer protocol, nothing numpy."""

        def __init__(self, a):
            self._view = memoryview(a)

        def __buffer__(self, flags):  # Python >= 3.12
            return self._view

        def __array__(self, dtype=None, copy=None):  # older Pythons
            return np.asarray(self._view)

    est = track(camera, [(t, memoryview(i), memoryview(d)) for t, i, d in fr[:10]])
    assert np.array_equal(est, base)
    est = track(camera, [(t, Image(i), Image(d)) for t, i, d in fr[:10]])
    assert np.array_equal(est, base)

    class RGBD:
        """Like open3d.geometry.RGBDImage: .color float [0, 1], .depth float metres."""

        def __init__(self, i, d):
            self.color = i.astype(np.float32) / np.float32(255)
            self.depth = d.astype(np.float32) / np.float32(camera.depth_scale)

    tracker = ecvo.Tracker(camera)
    for t, i, d in fr[:10]:
        tracker.push(t, RGBD(i, d))
    assert np.array_equal(tracker.trajectory(), base)
    with pytest.raises(TypeError, match="needs depth"):
        tracker.push(99.0, fr[0][1])


def test_masked_arrays_are_honoured(frames):
    camera, fr = frames
    # Masking a region is removing its depth.
    region = np.zeros((180, 320), bool)
    region[40:120, 100:220] = True
    removed = [(t, i, np.where(region, 0, d).astype(np.uint16)) for t, i, d in fr[:15]]
    base = track(camera, removed)
    assert not np.array_equal(base, track(camera, fr[:15])), "the region matters"
    masked_depth = [(t, i, np.ma.masked_array(d, mask=region)) for t, i, d in fr[:15]]
    assert np.array_equal(track(camera, masked_depth), base)
    masked_metres = [
        (t, i, np.ma.masked_array(d.astype(np.float32) / np.float32(camera.depth_scale), mask=region))
        for t, i, d in fr[:15]
    ]
    assert np.array_equal(track(camera, masked_metres), base)
    masked_intensity = [(t, np.ma.masked_array(i, mask=region), d) for t, i, d in fr[:15]]
    assert np.array_equal(track(camera, masked_intensity), base)
    mask3 = np.repeat(region[..., None], 3, axis=2)
    masked_colour = [(t, np.ma.masked_array(colour_of(i), mask=mask3), d) for t, i, d in fr[:15]]
    assert np.array_equal(track(camera, masked_colour), base)
    # The caller's arrays are left alone.
    assert np.array_equal(masked_depth[0][2].data, fr[0][2])
    # Nothing masked: the plain arrays' poses.
    none = [(t, i, np.ma.masked_array(d, mask=False)) for t, i, d in fr[:15]]
    assert np.array_equal(track(camera, none), track(camera, fr[:15]))
