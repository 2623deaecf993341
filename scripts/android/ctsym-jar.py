#!/usr/bin/env python3
"""Writes the JDK's API signatures of one Java release (from lib/ct.sym, what `javac --release N`
compiles against) as a jar of class files, for tools that need a Java library classpath (ProGuard
in build-apk.sh). ct.sym's folders are named by the releases they hold ('8' = 8, '9' = 9,
'A' = 10, ...); a .sig file is a class file; its version is set to 52 (Java 8) so that older
readers (ProGuard 6.2) accept it.

Usage: ctsym-jar.py RELEASE OUT.jar [--jdk JAVA_HOME]
"""
import argparse
import os
import shutil
import subprocess
import sys
import zipfile


def release_letter(n):
    return str(n) if n < 10 else chr(ord("A") + n - 10)


def java_home():
    javac = shutil.which("javac")
    if not javac:
        sys.exit("ctsym-jar: no javac on PATH")
    return os.path.dirname(os.path.dirname(os.path.realpath(javac)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("release", type=int)
    ap.add_argument("out")
    ap.add_argument("--jdk", default=None)
    a = ap.parse_args()
    ct = os.path.join(a.jdk or java_home(), "lib", "ct.sym")
    letter = release_letter(a.release)
    seen = set()
    with zipfile.ZipFile(ct) as src, zipfile.ZipFile(a.out, "w", zipfile.ZIP_DEFLATED) as out:
        for n in src.namelist():
            if not n.endswith(".sig"):
                continue
            parts = n.split("/")
            if letter not in parts[0]:
                continue
            rest = parts[1:]
            # From release 9 on, ct.sym has a module folder (java.base/...); release 8 may too.
            if len(rest) > 1 and "." in rest[0] and rest[0].startswith(("java.", "jdk.")):
                rest = rest[1:]
            name = "/".join(rest)[:-4] + ".class"
            if name in seen:
                continue
            seen.add(name)
            b = bytearray(src.read(n))
            if b[:4] != b"\xca\xfe\xba\xbe":
                sys.exit(f"ctsym-jar: {n} is not a class file")
            b[6:8] = (52).to_bytes(2, "big")
            out.writestr(name, bytes(b))
    if len(seen) < 1000 or "java/lang/Object.class" not in seen:
        sys.exit(f"ctsym-jar: only {len(seen)} classes for release {a.release} in {ct}")
    print(f"ctsym-jar: {len(seen)} classes of Java {a.release} -> {a.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
