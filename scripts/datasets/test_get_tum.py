"""get-tum.sh --half on a local folder: the first frames of tum_fr1_xyz_full300 (640x480)
give the corresponding frames of tum_fr1_xyz_half, which was made that way: depth pixel
for pixel, gray within 1 (full300's gray is rounded, the half set was made from colour). Run: python3 -m unittest discover -s scripts/datasets -p 'test_*.py'.

Needs the shared datasets (../shared/datasets or $ECVO_DATASETS): without them the test
says NOT RUN and passes, unless ECVO_REQUIRE_DATASETS=1, as the Rust dataset tests do.
"""

import json
import os
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
SCRIPT = os.path.join(HERE, "get-tum.sh")


def datasets():
    d = os.environ.get("ECVO_DATASETS") or os.path.join(REPO, "..", "shared", "datasets")
    return d if os.path.isdir(d) else None


def read_png(path):
    """(width, height, pixels) of a non-interlaced 8- or 16-bit gray PNG."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, head = 8, b"", None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            head = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, colour, _, _, interlace = head
    assert colour == 0 and depth in (8, 16) and interlace == 0, (path, head)
    bpp = depth // 8
    stride = w * bpp
    raw = zlib.decompress(idat)
    out, prev = bytearray(), bytearray(stride)
    for y in range(h):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + b) & 255
            elif ftype == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    if bpp == 2:
        return w, h, list(struct.unpack(f">{w * h}H", bytes(out)))
    return w, h, list(out)


def data_lines(path):
    with open(path) as f:
        return [l.rstrip("\n") for l in f if l.strip() and not l.startswith("#")]


class GetTumHalf(unittest.TestCase):
    def test_half_of_a_local_folder_is_the_shared_half_set(self):
        d = datasets()
        if d is None or not os.path.isdir(os.path.join(d, "tum_fr1_xyz_full300")):
            if os.environ.get("ECVO_REQUIRE_DATASETS") == "1":
                self.fail("the shared datasets are missing and ECVO_REQUIRE_DATASETS=1")
            sys.stderr.write("\nNOT RUN (no data): test_get_tum: dataset `tum_fr1_xyz_full300` not found\n")
            return
        full = os.path.join(d, "tum_fr1_xyz_full300")
        half = os.path.join(d, "tum_fr1_xyz_half")
        with tempfile.TemporaryDirectory() as out:
            r = subprocess.run(["bash", SCRIPT, "--out", out, "--half", "--first", "3", full],
                               capture_output=True, text=True, timeout=1800)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("300 colour and 300 depth images", r.stderr)
            got = os.path.join(out, "tum_fr1_xyz_full300_half")
            with open(os.path.join(got, "camera.json")) as f:
                cam = json.load(f)
            with open(os.path.join(half, "camera.json")) as f:
                want = json.load(f)
            for k in want:
                self.assertAlmostEqual(cam[k], want[k], places=9, msg=k)
            for lst in ("rgb.txt", "depth.txt"):
                lines = data_lines(os.path.join(got, lst))
                self.assertEqual(lines, data_lines(os.path.join(half, lst))[:3], lst)
                for line in lines:
                    f = line.split()[1]
                    w, h, a = read_png(os.path.join(got, f))
                    self.assertEqual((w, h), (320, 240), f)
                    b = read_png(os.path.join(half, f))[2]
                    if lst == "depth.txt":
                        self.assertEqual(a, b, f)
                    else:
                        # The half set was made from the colour originals; full300 holds
                        # them as rounded gray: a block's mean moves by at most 0.5.
                        self.assertLessEqual(max(abs(p - q) for p, q in zip(a, b)), 1, f)
            # A bad argument is a clear error, not a download.
            r = subprocess.run(["bash", SCRIPT, "--out", out, "not/a_sequence"],
                               capture_output=True, text=True, timeout=60)
            self.assertEqual(r.returncode, 2)
            self.assertIn("is not a TUM sequence name", r.stderr)


if __name__ == "__main__":
    unittest.main()
