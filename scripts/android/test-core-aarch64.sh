#!/usr/bin/env bash
# Runs ecvo-core's tests for aarch64 (the CPU of arm64-v8a phones) under qemu-user, as
# shared/android/TOOLCHAIN.md describes: Debian's rustc-web/cargo-web (/usr/bin, 1.96) with
# Debian's arm64 std (libstd-rust-web-dev:arm64), linker aarch64-linux-gnu-gcc, runner
# qemu-aarch64 (no -L: with libc6:arm64 installed, -L makes threaded programs hang).
#
# Usage: scripts/android/test-core-aarch64.sh [extra `cargo test` args, e.g. -- --nocapture]
#        scripts/android/test-core-aarch64.sh --setup-only   (install and check the toolchain)
# Environment:
#   ECVO_QEMU_TARGET_DIR  target dir (default <repo>/target/aarch64-qemu). CARGO_TARGET_DIR is
#                         deliberately ignored: Debian's rustc 1.96 and rustup's 1.95 must not
#                         share a target dir.
#   ECVO_QEMU_PACKAGE     package to test (default ecvo-core)
# Installs (once; skipped when present): dpkg architecture arm64, rustc-web cargo-web
# gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user libstd-rust-web-dev:arm64.
# Cargo's default test selection; for this cross target the doctest harness reports 0 tests.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
# shellcheck source=lib.sh
. "$HERE/lib.sh"

PKG="${ECVO_QEMU_PACKAGE:-ecvo-core}"
TDIR="${ECVO_QEMU_TARGET_DIR:-$REPO/target/aarch64-qemu}"

PKGS=(rustc-web cargo-web gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user libstd-rust-web-dev:arm64)
if ! debs_installed "${PKGS[@]}"; then
  ensure_dpkg_arches arm64
  ensure_debs "${PKGS[@]}"
fi
v_host="$(dpkg-query -W -f='${Version}' rustc-web)"
v_std="$(dpkg-query -W -f='${Version}' libstd-rust-web-dev:arm64)"
[ "$v_host" = "$v_std" ] || die "rustc-web $v_host and libstd-rust-web-dev:arm64 $v_std differ; run apt-get install rustc-web libstd-rust-web-dev:arm64 to align them"
[ -x /usr/bin/rustc ] && [ -x /usr/bin/cargo ] || die "/usr/bin/rustc or /usr/bin/cargo missing (package rustc-web / cargo-web)"
command -v qemu-aarch64 >/dev/null || die "qemu-aarch64 missing (package qemu-user)"
/usr/bin/rustc --print sysroot >/dev/null
[ -d "$(/usr/bin/rustc --print sysroot)/lib/rustlib/aarch64-unknown-linux-gnu/lib" ] \
  || die "Debian rustc has no aarch64-unknown-linux-gnu std (libstd-rust-web-dev:arm64)"

log "$(/usr/bin/rustc --version) (Debian) + qemu-aarch64 $(qemu-aarch64 --version | head -1 | awk '{print $3}'); package $PKG; target dir $TDIR"
# --setup-only: install and check the toolchain, run nothing (bench-core-aarch64.sh).
[ "${1:-}" = --setup-only ] && exit 0
cd "$REPO"
# Drop rustup's toolchain selection so nothing reroutes /usr/bin/cargo's rustc.
env -u RUSTUP_TOOLCHAIN -u RUSTC_WRAPPER -u RUSTFLAGS -u CARGO_BUILD_TARGET \
  PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc \
  CARGO_TARGET_DIR="$TDIR" \
  CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
  CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER=qemu-aarch64 \
  /usr/bin/cargo test --target aarch64-unknown-linux-gnu -p "$PKG" "$@"
