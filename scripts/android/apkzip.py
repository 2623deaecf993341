#!/usr/bin/env python3
"""Assembles the unsigned APK: aapt's package (manifest, resources.arsc, res/, assets/) plus
classes.dex and lib/<abi>/*.so, with every stored entry's data 4-byte aligned and every stored
.so 16 KB aligned (what `zipalign -P 16` does in build-tools 35+; Debian's zipalign 10 only
knows 4 KB pages). The padding goes into an extra field with Android's zipalign id 0xD935.
apksigner's v2/v3 signing block goes before the central directory, so it keeps these offsets.

Usage: apkzip.py OUT.apk BASE.apk --dex classes.dex --libs DIR   (DIR/<abi>/*.so)
"""
import argparse
import os
import struct
import sys
import zipfile

SO_ALIGN = 16384
ALIGN = 4
EXTRA_ID = 0xD935


def write_entry(out, name, data, stored):
    info = zipfile.ZipInfo(name, date_time=(2008, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    if stored:
        align = SO_ALIGN if name.endswith(".so") else ALIGN
        header_end = out.fp.tell() + 30 + len(name.encode())
        pad = (-(header_end + 6)) % align
        info.extra = struct.pack("<HHH", EXTRA_ID, 2 + pad, align) + b"\0" * pad
    out.writestr(info, data)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("base")
    ap.add_argument("--dex", required=True)
    ap.add_argument("--libs", required=True)
    a = ap.parse_args()
    with zipfile.ZipFile(a.base) as base, zipfile.ZipFile(a.out, "w") as out:
        names = set()
        for info in base.infolist():
            write_entry(out, info.filename, base.read(info), info.compress_type == zipfile.ZIP_STORED)
            names.add(info.filename)
        with open(a.dex, "rb") as f:
            write_entry(out, "classes.dex", f.read(), False)
        n = 0
        for abi in sorted(os.listdir(a.libs)):
            for so in sorted(os.listdir(os.path.join(a.libs, abi))):
                if so.endswith(".so"):
                    with open(os.path.join(a.libs, abi, so), "rb") as f:
                        write_entry(out, f"lib/{abi}/{so}", f.read(), True)
                    n += 1
        if n == 0:
            sys.exit(f"apkzip: no .so under {a.libs}")
        if "classes.dex" in names:
            sys.exit("apkzip: the base package already has a classes.dex")
    # Self-check: every stored .so starts on a 16 KB boundary.
    with zipfile.ZipFile(a.out) as z, open(a.out, "rb") as f:
        for info in z.infolist():
            f.seek(info.header_offset)
            h = f.read(30)
            start = info.header_offset + 30 + struct.unpack("<H", h[26:28])[0] + struct.unpack("<H", h[28:30])[0]
            need = SO_ALIGN if info.filename.endswith(".so") else ALIGN
            if info.compress_type == zipfile.ZIP_STORED and start % need:
                sys.exit(f"apkzip: {info.filename} data at {start}, not {need}-aligned")


if __name__ == "__main__":
    main()
