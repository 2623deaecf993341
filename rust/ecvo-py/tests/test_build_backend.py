"""A source build without a Rust toolchain stops at once and says so (instead of
maturin downloading one)."""

import subprocess
import sys
import time
from pathlib import Path

BACKEND = Path(__file__).resolve().parents[1] / "build_backend"

SNIPPET = """
import sys
sys.path.insert(0, sys.argv[1])
import ecvo_build
for hook in ("get_requires_for_build_wheel", "prepare_metadata_for_build_wheel", "build_wheel"):
    try:
        getattr(ecvo_build, hook)(*(["."] if hook != "get_requires_for_build_wheel" else []))
    except RuntimeError as e:
        print(hook, e)
    else:
        raise SystemExit(hook + " went on without cargo")
"""


def test_no_cargo_fails_at_once(tmp_path):
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-c", SNIPPET, str(BACKEND)],
        env={"PATH": str(tmp_path)},  # no cargo on it
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert time.perf_counter() - t0 < 10
    lines = p.stdout.splitlines()
    assert len(lines) == 3
    assert all("needs a Rust toolchain" in line and "rustup" in line for line in lines)
