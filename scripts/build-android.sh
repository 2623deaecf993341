#!/usr/bin/env bash
# Builds ecvo's Android JNI library (crate rust/ecvo-jni, cdylib libecvo_jni.so) for the app:
#   cargo ndk -t <abi>... -P <minSdk> -o android-app/app/src/main/jniLibs build --release -p ecvo-jni
#
# Usage: scripts/build-android.sh [options] [-- extra cargo args]
#   -t, --abi ABI         ABI to build; repeatable or comma/space separated
#                         (default: $ECVO_ANDROID_ABIS or "arm64-v8a armeabi-v7a x86_64")
#   -P, --min-sdk N       minSdk / API level (default: $ECVO_MIN_SDK or 26)
#   -o, --out DIR         jniLibs folder (default: android-app/app/src/main/jniLibs in the repo)
#   -p, --package NAME    cargo package (default: ecvo-jni)
#   --manifest-path PATH  Cargo.toml to build (default: the repo's workspace)
#   --profile NAME        cargo profile (default: release)
#   -h, --help
# Environment:
#   ANDROID_NDK_HOME      the NDK (a real one, or the stand-in from
#                         scripts/android/install-standin-ndk.sh); ANDROID_NDK_ROOT is accepted too.
#   CARGO_TARGET_DIR      honoured as usual.
#
# DT_SONAME: every ABI's link gets -C link-arg=-Wl,-soname,lib<package>.so (see below).
#
# 16 KB pages: NDK r28+ links 64-bit ABIs with 16 KB max-page-size by default and cargo-ndk
# adds -Wl,-z,max-page-size=16384 for 64-bit ABIs with NDK <= r27. This script additionally
# passes -C link-arg=-Wl,-z,max-page-size=16384 for every ABI that neither covers (32-bit ABIs
# with any NDK; everything if the NDK version is unknown), so every LOAD segment of every ABI is
# 16 KB aligned, which scripts/android/check-so.sh verifies.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/.." && pwd)"
ECVO_LOG_TAG=build-android
# shellcheck source=android/lib.sh
. "$HERE/android/lib.sh"

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

ABIS_RAW="${ECVO_ANDROID_ABIS:-arm64-v8a armeabi-v7a x86_64}"
ABIS_CLI=""
MIN_SDK="$ECVO_MIN_SDK"
OUT="$REPO/android-app/app/src/main/jniLibs"
PACKAGE="ecvo-jni"
MANIFEST="$REPO/Cargo.toml"
PROFILE="release"
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    -t|--abi) ABIS_CLI="$ABIS_CLI ${2:?--abi needs a value}"; shift 2 ;;
    -P|--min-sdk|--platform) MIN_SDK="${2:?}"; shift 2 ;;
    -o|--out) OUT="${2:?}"; shift 2 ;;
    -p|--package) PACKAGE="${2:?}"; shift 2 ;;
    --manifest-path) MANIFEST="${2:?}"; shift 2 ;;
    --profile) PROFILE="${2:?}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    --) shift; EXTRA=("$@"); break ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[ -n "$ABIS_CLI" ] && ABIS_RAW="$ABIS_CLI"
read -r -a ABIS <<<"$(echo "$ABIS_RAW" | tr ',' ' ')"
[ ${#ABIS[@]} -gt 0 ] || die "no ABI given"
for abi in "${ABIS[@]}"; do abi_rust_target "$abi" >/dev/null; done
case "$MIN_SDK" in ''|*[!0-9]*) die "min SDK must be a number, got '$MIN_SDK'" ;; esac
case "$OUT" in /*) ;; *) OUT="$PWD/$OUT" ;; esac
case "$MANIFEST" in /*) ;; *) MANIFEST="$PWD/$MANIFEST" ;; esac
[ -f "$MANIFEST" ] || die "no Cargo.toml at $MANIFEST"

NDK="${ANDROID_NDK_HOME:-${ANDROID_NDK_ROOT:-}}"
[ -n "$NDK" ] || die "ANDROID_NDK_HOME is not set. Point it at an Android NDK (r27+ recommended), or on a machine without one run: eval \"\$(scripts/android/install-standin-ndk.sh)\""
[ -f "$NDK/source.properties" ] || die "ANDROID_NDK_HOME=$NDK has no source.properties: not an NDK"
export ANDROID_NDK_HOME="$NDK"
NDK_REV="$(sed -n 's/^ *Pkg.Revision *= *\([0-9.]*\).*/\1/p' "$NDK/source.properties" | head -1)"
NDK_MAJOR="${NDK_REV%%.*}"
case "$NDK_MAJOR" in ''|*[!0-9]*) NDK_MAJOR=0 ;; esac
KIND="real NDK"
[ -f "$NDK/ECVO_STANDIN_NDK" ] && KIND="ecvo stand-in NDK (link check only, not for release)"
if [ -f "$NDK/abis.supported" ]; then
  for abi in "${ABIS[@]}"; do
    grep -qx "$abi" "$NDK/abis.supported" || die "the stand-in NDK at $NDK cannot build $abi: $(grep "^$abi"$'\t' "$NDK/abis.unsupported" 2>/dev/null | cut -f2- || echo 'not built')"
  done
fi

use_rustup_toolchain
command -v cargo-ndk >/dev/null || die "cargo-ndk is not installed: cargo install cargo-ndk --locked"
installed_targets="$(rustup target list --installed 2>/dev/null || true)"
for abi in "${ABIS[@]}"; do
  t="$(abi_rust_target "$abi")"
  grep -qx "$t" <<<"$installed_targets" || die "Rust target $t is not installed: rustup target add $t"
  # Page size: see the header comment.
  case "$abi" in arm64-v8a|x86_64) [ "$NDK_MAJOR" -ge 1 ] && continue ;; esac
  var="CARGO_TARGET_$(echo "$t" | tr 'a-z-' 'A-Z_')_RUSTFLAGS"
  if [ -n "${RUSTFLAGS:-}" ]; then
    # RUSTFLAGS wins over target rustflags in cargo, so the flag has to go there.
    [[ "$RUSTFLAGS" == *max-page-size=16384* ]] || export RUSTFLAGS="$RUSTFLAGS -C link-arg=-Wl,-z,max-page-size=16384"
  else
    cur="${!var:-}"
    [[ "$cur" == *max-page-size=16384* ]] || export "$var=${cur:+$cur }-C link-arg=-Wl,-z,max-page-size=16384"
  fi
done

# DT_SONAME: rustc links a cdylib without -soname, and neither the NDK's clang nor cargo-ndk adds
# one (the NDK's CMake and ndk-build do). Android identifies a loaded library by it
# (scripts/android/check-so.sh requires it), so every ABI's link sets it to the file's name.
lib="lib$(echo "$PACKAGE" | tr '-' '_').so"
for abi in "${ABIS[@]}"; do
  t="$(abi_rust_target "$abi")"
  var="CARGO_TARGET_$(echo "$t" | tr 'a-z-' 'A-Z_')_RUSTFLAGS"
  if [ -n "${RUSTFLAGS:-}" ]; then
    [[ "$RUSTFLAGS" == *-soname* ]] || export RUSTFLAGS="$RUSTFLAGS -C link-arg=-Wl,-soname,$lib"
  else
    cur="${!var:-}"
    [[ "$cur" == *-soname* ]] || export "$var=${cur:+$cur }-C link-arg=-Wl,-soname,$lib"
  fi
done

args=()
for abi in "${ABIS[@]}"; do args+=(-t "$abi"); done
prof_args=(--profile "$PROFILE"); [ "$PROFILE" = release ] && prof_args=(--release)
log "NDK: $NDK ($KIND, Pkg.Revision $NDK_REV); ABIs: ${ABIS[*]}; minSdk $MIN_SDK; out: $OUT"
mkdir -p "$OUT"
# cargo-ndk reads `cargo metadata` of the current directory, so run from the manifest's folder.
cd "$(dirname "$MANIFEST")"
set -x
cargo ndk "${args[@]}" -P "$MIN_SDK" -o "$OUT" --manifest-path "$MANIFEST" build "${prof_args[@]}" -p "$PACKAGE" ${EXTRA[@]+"${EXTRA[@]}"}
{ set +x; } 2>/dev/null
for abi in "${ABIS[@]}"; do
  [ -f "$OUT/$abi/$lib" ] || die "cargo ndk finished but $OUT/$abi/$lib is missing (is $PACKAGE a cdylib?)"
  log "built $OUT/$abi/$lib ($(stat -c %s "$OUT/$abi/$lib") bytes)"
done
