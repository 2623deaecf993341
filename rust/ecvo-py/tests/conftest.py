"""Shared fixtures: the repository's test stream, the `ecvo` command to compare with."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
SYNTH = REPO / "testdata" / "synth_phone_320x180"


def _ecvo_bin():
    explicit = os.environ.get("ECVO_BIN")
    if explicit:
        return Path(explicit)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "release" / "ecvo"


@pytest.fixture(scope="session")
def synth():
    return SYNTH


@pytest.fixture(scope="session")
def ecvo_bin():
    """The `ecvo` binary (scripts/python/test-python.sh builds it first)."""
    path = _ecvo_bin()
    if not path.is_file():
        pytest.fail(
            f"{path} not found: build it with `cargo build --release -p ecvo-cli` "
            "or set ECVO_BIN (scripts/python/test-python.sh does)"
        )
    return path


@pytest.fixture(scope="session")
def cli(ecvo_bin, tmp_path_factory):
    """Runs `ecvo ARGS...` and returns its stdout; fails the test on an error."""

    def run(*args):
        p = subprocess.run(
            [str(ecvo_bin), *map(str, args)], capture_output=True, text=True, check=False
        )
        if p.returncode != 0:
            pytest.fail(f"ecvo {' '.join(map(str, args))} failed:\n{p.stderr}")
        return p.stdout

    return run


def read_tum(path):
    """The rows of a TUM trajectory file, every number parsed to the full precision
    the file has (ecvo writes round-trip precision)."""
    rows = []
    for line in Path(path).read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        rows.append([float(x) for x in line.split()])
    return rows


@pytest.fixture(scope="session")
def cli_run(cli, synth, tmp_path_factory):
    """`ecvo run` on the test stream with the given flags: its output folder."""
    cache = {}

    def run(*flags):
        if flags not in cache:
            out = tmp_path_factory.mktemp("run")
            cli("run", synth, "--out", out, *flags)
            cache[flags] = out
        return cache[flags]

    yield run
    for out in cache.values():
        shutil.rmtree(out, ignore_errors=True)
