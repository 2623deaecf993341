"""The package's PEP 517 build backend: maturin's, after checking that a Rust
toolchain is there. Without cargo, maturin would download a Rust toolchain (about
940 MB) into a cache without a word; a source build here stops at once instead and
says what to do. ECVO_ALLOW_RUST_DOWNLOAD=1 restores maturin's behaviour.
"""

import os
import shutil

MESSAGE = (
    "ecvo: building from source needs a Rust toolchain (cargo was not found on PATH). "
    "Install one (https://rustup.rs, Rust 1.85 or later) and retry, or install a "
    "prebuilt wheel (scripts/python/build-wheels.sh makes them). "
    "ECVO_ALLOW_RUST_DOWNLOAD=1 lets maturin download a toolchain (~940 MB) instead."
)


def _check():
    if os.environ.get("ECVO_ALLOW_RUST_DOWNLOAD") == "1":
        return
    if shutil.which("cargo") is None:
        raise RuntimeError(MESSAGE)
    # Never the silent download, even if cargo disappears between the hooks.
    os.environ.setdefault("MATURIN_NO_INSTALL_RUST", "1")


def _maturin():
    import maturin

    return maturin


def get_requires_for_build_wheel(config_settings=None):
    _check()
    return _maturin().get_requires_for_build_wheel(config_settings)


def get_requires_for_build_editable(config_settings=None):
    _check()
    return _maturin().get_requires_for_build_wheel(config_settings)


def get_requires_for_build_sdist(config_settings=None):
    return _maturin().get_requires_for_build_sdist(config_settings)


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    _check()
    return _maturin().prepare_metadata_for_build_wheel(metadata_directory, config_settings)


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _check()
    return _maturin().build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _check()
    return _maturin().build_editable(wheel_directory, config_settings, metadata_directory)


def build_sdist(sdist_directory, config_settings=None):
    return _maturin().build_sdist(sdist_directory, config_settings)
