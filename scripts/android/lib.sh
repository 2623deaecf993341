# shellcheck shell=bash
# Shared helpers for scripts/android/*.sh and scripts/build-android.sh.
# Source it; it defines functions only (plus a few defaults), no side effects.

ECVO_MIN_SDK="${ECVO_MIN_SDK:-26}"

# ABI <-> Rust target <-> clang triple <-> Debian architecture <-> readelf machine.
abi_rust_target() {
  case "$1" in
    arm64-v8a) echo aarch64-linux-android ;;
    armeabi-v7a) echo armv7-linux-androideabi ;;
    x86_64) echo x86_64-linux-android ;;
    x86) echo i686-linux-android ;;
    *) die "unknown Android ABI '$1' (expected arm64-v8a, armeabi-v7a, x86_64 or x86)" ;;
  esac
}
# Directory name under sysroot/usr/lib (the NDK's multiarch triple).
abi_ndk_triple() {
  case "$1" in
    arm64-v8a) echo aarch64-linux-android ;;
    armeabi-v7a) echo arm-linux-androideabi ;;
    x86_64) echo x86_64-linux-android ;;
    x86) echo i686-linux-android ;;
    *) die "unknown Android ABI '$1'" ;;
  esac
}
# clang --target prefix (API level appended).
abi_clang_target() {
  case "$1" in
    arm64-v8a) echo aarch64-linux-android ;;
    armeabi-v7a) echo armv7a-linux-androideabi ;;
    x86_64) echo x86_64-linux-android ;;
    x86) echo i686-linux-android ;;
    *) die "unknown Android ABI '$1'" ;;
  esac
}
abi_deb_arch() {
  case "$1" in
    arm64-v8a) echo arm64 ;;
    armeabi-v7a) echo armhf ;;
    x86_64) echo amd64 ;;
    x86) echo i386 ;;
    *) die "unknown Android ABI '$1'" ;;
  esac
}
# Column 4 of bionic-ndk-symbols.tsv.
abi_bionic_arch() {
  case "$1" in
    arm64-v8a) echo arm64 ;;
    armeabi-v7a) echo arm ;;
    x86_64) echo x86_64 ;;
    x86) echo x86 ;;
    *) die "unknown Android ABI '$1'" ;;
  esac
}
# "Machine:" line of readelf -h.
abi_elf_machine() {
  case "$1" in
    arm64-v8a) echo AArch64 ;;
    armeabi-v7a) echo ARM ;;
    x86_64) echo 'Advanced Micro Devices X86-64' ;;
    x86) echo 'Intel 80386' ;;
    *) die "unknown Android ABI '$1'" ;;
  esac
}

_ecvo_tag="${ECVO_LOG_TAG:-$(basename "${0:-ecvo}" .sh)}"
log() { printf '[%s] %s\n' "$_ecvo_tag" "$*" >&2; }
warn() { printf '[%s] WARNING: %s\n' "$_ecvo_tag" "$*" >&2; }
die() { printf '[%s] ERROR: %s\n' "$_ecvo_tag" "$*" >&2; exit 1; }

need_root_or_sudo() {
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
    die "need root (or sudo) to install Debian packages"; fi
}

# True if every given Debian package (pkg or pkg:arch) is installed.
debs_installed() {
  local p st
  for p in "$@"; do
    st="$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)"
    [ "$st" = "install ok installed" ] || return 1
  done
}

# Adds foreign dpkg architectures that are missing; sets _ECVO_APT_STALE=1 if any was added.
ensure_dpkg_arches() {
  local native a
  native="$(dpkg --print-architecture)"
  for a in "$@"; do
    [ "$a" = "$native" ] && continue
    if ! dpkg --print-foreign-architectures | grep -qx "$a"; then
      need_root_or_sudo
      log "dpkg --add-architecture $a"
      $SUDO dpkg --add-architecture "$a"
      _ECVO_APT_STALE=1
    fi
  done
}

# apt-get update at most once per process (and again only if an architecture was added since).
apt_update_once() {
  if [ "${_ECVO_APT_UPDATED:-0}" = 1 ] && [ "${_ECVO_APT_STALE:-0}" != 1 ]; then return 0; fi
  need_root_or_sudo
  log "apt-get update"
  # A partly failed update (one broken mirror index) still leaves usable lists: warn, go on, and
  # let the install say what is really missing.
  $SUDO apt-get update -qq || warn "apt-get update reported errors (see above); continuing with the lists apt has"
  _ECVO_APT_UPDATED=1
  _ECVO_APT_STALE=0
}

# Installs the given Debian packages if any is missing (one apt-get update first, once).
ensure_debs() {
  if debs_installed "$@"; then return 0; fi
  local missing=() p
  for p in "$@"; do debs_installed "$p" || missing+=("$p"); done
  apt_update_once
  need_root_or_sudo
  log "apt-get install ${missing[*]}"
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null \
    || die "apt-get install ${missing[*]} failed"
}

# Runs a command and records "label seconds" in the global STEP_TIMES array.
STEP_TIMES=()
timed() {
  local label="$1"; shift
  local t0 t1 rc=0
  t0=$EPOCHREALTIME
  log "=== step: $label"
  "$@" || rc=$?
  t1=$EPOCHREALTIME
  STEP_TIMES+=("$(printf '%-44s %7.1f s  %s' "$label" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{print b-a}')" "$([ $rc -eq 0 ] && echo ok || echo "FAILED (exit $rc)")")")
  return $rc
}
print_times() {
  local l
  printf '\n%-44s %9s\n' "step" "time"
  for l in "${STEP_TIMES[@]}"; do printf '%s\n' "$l"; done
}

# Puts rustup's cargo first (the Debian rustc-web cargo lives in /usr/bin).
use_rustup_toolchain() {
  if [ -d "$HOME/.cargo/bin" ]; then PATH="$HOME/.cargo/bin:$PATH"; fi
  command -v rustup >/dev/null || die "rustup not found (expected in ~/.cargo/bin)"
}
