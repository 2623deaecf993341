#!/usr/bin/env python3
"""Writes the seed corpora of the cargo-fuzz targets into fuzz/corpus/<target>/.

Seeds are made from testdata/ and from ../shared/datasets (the phone ToF samples and
a TUM frame) when present; nothing from shared/ is committed: run this script instead.
Standard library only (a small PNG decoder/encoder for cropping real frames).

    python3 scripts/fuzz/seeds.py [--datasets DIR]
"""
import argparse
import os
import struct
import zlib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def png_chunks(data):
    i = 8
    while i + 8 <= len(data):
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        yield kind, data[i + 8:i + 8 + n]
        i += 12 + n


def png_decode(data):
    """Non-interlaced gray/RGB/RGBA 8 or 16 bit -> (w, h, bytes per pixel, rows)."""
    idat = b""
    for kind, body in png_chunks(data):
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
    assert interlace == 0
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
    bpp = channels * depth // 8
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev, i = [], bytearray(stride), 0
    for _ in range(h):
        f, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[x] = (line[x] + pr) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, bpp, rows, depth, ctype


def png_encode(w, h, depth, ctype, rows, filt=0):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    raw = b"".join(bytes([filt]) + r for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, ctype, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def crop(img, x0, y0, w, h):
    _, _, bpp, rows, _, _ = img
    return [r[x0 * bpp:(x0 + w) * bpp] for r in rows[y0:y0 + h]]


def write(target, name, data):
    d = REPO / "fuzz" / "corpus" / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--datasets", default=os.environ.get("ECVO_DATASETS", str(REPO.parent / "shared" / "datasets")))
    args = ap.parse_args()
    shared = Path(args.datasets)
    synth = REPO / "testdata" / "synth_phone_320x180"

    # --- PNGs: crops of real frames in every colour type the readers meet.
    pngs = []
    depth_files = sorted((synth / "depth").glob("*.png"))[:2]
    rgb_files = sorted((synth / "rgb").glob("*.png"))[:2]
    tum = shared / "tum_fr1_xyz_half"
    if tum.is_dir():
        depth_files += sorted((tum / "depth").glob("*.png"))[:1]
        rgb_files += sorted((tum / "rgb").glob("*.png"))[:1]
    crops = []
    for f in depth_files + rgb_files:
        img = png_decode(f.read_bytes())
        crops.append((f.name, img, crop(img, 100, 60, 24, 16)))
    for k, (name, img, rows) in enumerate(crops):
        _, _, bpp, _, depth, ctype = img
        pngs.append((f"crop{k}_{depth}bit.png", png_encode(24, 16, depth, ctype, rows, k % 5)))
        if depth == 8 and ctype == 0:
            rgb = [bytes(v for p in r for v in (p, p // 2, 255 - p)) for r in rows]
            rgba = [bytes(v for p in r for v in (p, p, p, 200)) for r in rows]
            la = [bytes(v for p in r for v in (p, 255)) for r in rows]
            pngs += [(f"crop{k}_rgb.png", png_encode(24, 16, 8, 2, rgb)),
                     (f"crop{k}_rgba.png", png_encode(24, 16, 8, 6, rgba)),
                     (f"crop{k}_la.png", png_encode(24, 16, 8, 4, la))]
    phone_png = shared / "phone_tof_samples" / "00003795_depth16.bin.png"
    if phone_png.is_file():
        img = png_decode(phone_png.read_bytes())
        pngs.append(("phone_crop.png", png_encode(24, 16, img[4], img[5], crop(img, 100, 80, 24, 16))))
    for name, data in pngs:
        write("io_png", name, data)

    # --- text parsers: the first byte picks camera.json, image list, associations, trajectory.
    write("io_text", "camera.json", b"\x00" + (synth / "camera.json").read_bytes())
    for k, lst in enumerate(["rgb.txt", "depth.txt"]):
        lines = (synth / lst).read_text().splitlines()[:12]
        write("io_text", f"list_{lst}", b"\x01" + "\n".join(lines).encode())
    assoc = "\n".join(f"{i} depth/{i}.png {i} rgb/{i}.png" for i in range(8))
    write("io_text", "associations.txt", b"\x02" + assoc.encode())
    gt = (synth / "groundtruth.txt").read_text().splitlines()[:12]
    write("io_text", "groundtruth.txt", b"\x03" + "\n".join(gt).encode())
    # Hostile text in messages (control bytes, a BOM, a long name), and lists that lead
    # out of the folder or start with a BOM.
    write("io_text", "shown", b"\x05" + "a\x00b\n\x1b[31m\ufeff".encode() + b"x" * 400)
    write("io_text", "list_escape", b"\x01" + b"1 ../outside.png\n2 /etc/passwd\n")
    write("io_text", "list_bom", b"\x01" + "\ufeff1 rgb/1.png\n".encode())

    # --- imu.txt (even first byte) and camera.json's imu object (odd).
    imu = "\n".join(f"{1.0 + i / 200:.6f} 0.1 -0.2 {0.3 + i / 100:.4f} 0 0 9.81" for i in range(12))
    write("io_imu", "imu.txt", b"\x00# simulated\n" + imu.encode())
    write("io_imu", "gyro_only", b"\x00" + b"1 0 0 1\n1.005 0 0 1\n1.5 0 0 1\n")
    write("io_imu", "calibration", b"\x01" + b'{"width": 8, "imu": {"camera_from_imu": [[1,0,0],[0,1,0],[0,0,1]], "time_offset": 0.01}}')

    # --- --levels
    for k, s in enumerate(["30mm:7deg,120mm:12deg", "0.03m:3deg,70mm:7deg", "none", "", " 1e-3 m : 1.5e1 deg "]):
        write("levels", f"levels{k}", s.encode())

    # --- nativeInit arguments (Unstructured bytes; any bytes are valid input).
    write("jni_args", "zeros", bytes(64))
    write("jni_args", "phone", struct.pack("<?hh", True, 240, 180) + struct.pack("<dddd", 178.0, 178.0, 119.5, 89.5) + bytes(16))

    # --- DEPTH16: first byte the minimum confidence, then a whole 240x180 plane.
    for f in sorted((shared / "phone_tof_samples").glob("*_depth16.bin")):
        plane = f.read_bytes()
        for c in (0, 1, 4):
            write("depth16", f"{f.stem}_conf{c}", bytes([c]) + plane)
    write("depth16", "small", bytes([2]) + bytes(range(256)))

    # --- prepare_motion: a small header, then crops of real intensity/depth pixels
    # interleaved as the target reads them (u8 intensity, u16 depth, per pixel).
    if crops:
        d_img = next(c for c in crops if c[1][4] == 16)[1]
        g_img = next(c for c in crops if c[1][4] == 8)[1]
        # (72x64 goes down the whole default pyramid, 3 levels.)
        for k, (w, h) in enumerate([(16, 12), (24, 16), (40, 30), (72, 64)]):
            head = bytes([w - 8, h - 8]) + struct.pack("<IIIII", 0xA0000000, 0xA0000000, 0x90000000, 0x90000000, 0x00100000)
            head += bytes([k % 2, k % 3, 150])
            # schedule (paper, pyramid, pyramid-stride2), bivariate weighting, a scalar
            # finest step or not, depth noise constant or quadratic
            head += bytes([(k + 2) % 3, 1, k % 2]) + (bytes([0]) if k % 2 else b"") + bytes([k % 2])
            body = b""
            for shift in (0, 1):
                body += struct.pack("<HH", 1000, 1)
                dr = crop(d_img, 100 + shift, 60, w, h)
                gr = crop(g_img, 100 + shift, 60, w, h)
                for y in range(h):
                    for x in range(w):
                        body += bytes([gr[y][x]]) + struct.pack("<H", struct.unpack(">H", dr[y][2 * x:2 * x + 2])[0])
            write("prepare_motion", f"real_{w}x{h}", head + bytes([2]) + body)
    print("seeds written to", REPO / "fuzz" / "corpus")


if __name__ == "__main__":
    main()
