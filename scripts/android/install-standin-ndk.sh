#!/usr/bin/env bash
# Installs the tools needed to link ecvo's Android library on a machine without the Android NDK,
# and builds a "stand-in NDK" that cargo-ndk accepts (see shared/android/TOOLCHAIN.md).
#
# Usage: scripts/android/install-standin-ndk.sh [DEST]
#   DEST defaults to $ECVO_STANDIN_NDK or $HOME/.cache/ecvo/standin-ndk.
#   Stdout gets exactly one line, `export ANDROID_NDK_HOME=DEST`, so
#   `eval "$(scripts/android/install-standin-ndk.sh)"` works; DEST/env.sh holds the same.
#   Everything else goes to stderr.
#
# Environment:
#   ECVO_STANDIN_ABIS   ABIs to build (default "arm64-v8a armeabi-v7a x86_64")
#   ECVO_MIN_SDK        minimum API level (default 26); stubs are made for 21..35 and it
#   ECVO_SKIP_RUST=1    do not touch rustup targets / cargo-ndk (only the NDK folder)
#
# What it does (each part is skipped when already done):
#   - apt: clang-22 lld-22 llvm-22 (one apt-get update if something is missing)
#   - apt-get download libunwind-22-dev:<arch> (arm64, armhf, amd64) with a private apt state
#     per architecture (no system-wide dpkg --add-architecture needed; see private_apt)
#   - rustup target add aarch64-linux-android armv7-linux-androideabi x86_64-linux-android
#   - cargo install cargo-ndk --locked (if `cargo ndk` is missing)
#   - DEST/toolchains/llvm/prebuilt/linux-x86_64/{bin,sysroot}: clang wrapper (lld, 16 KB
#     pages, libc/libm/libdl/liblog/libandroid always NEEDED), llvm-* links, empty bionic stub
#     libraries per ABI and API level, libunwind.a (+ 3 glibc shims) per ABI.
# An ABI that cannot be built is reported loudly and listed in DEST/abis.unsupported (with
# the reason); the script then exits 0 only if arm64-v8a and x86_64 are fine.
# DEST/abis.supported lists the ABIs that linked a smoke test.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=lib.sh
. "$HERE/lib.sh"

DEST="${1:-${ECVO_STANDIN_NDK:-$HOME/.cache/ecvo/standin-ndk}}"
case "$DEST" in /*) ;; *) DEST="$PWD/$DEST" ;; esac
ABIS="${ECVO_STANDIN_ABIS:-arm64-v8a armeabi-v7a x86_64}"
REQUIRED_ABIS="arm64-v8a x86_64"
CACHE="${ECVO_CACHE:-$HOME/.cache/ecvo}"
LLVM_VER=22
API_LEVELS="$(seq 21 35) $ECVO_MIN_SDK"
API_LEVELS="$(printf '%s\n' $API_LEVELS | sort -un | tr '\n' ' ')"
NDK_REVISION="27.0.12077973"   # what cargo-ndk reads; the stand-in behaves like r27 (no 16 KB default)
CARGO_NDK_VERSION="${ECVO_CARGO_NDK_VERSION:-^4.1}"

# ---------------------------------------------------------------- host packages
install_host_tools() {
  ensure_debs clang-$LLVM_VER lld-$LLVM_VER llvm-$LLVM_VER binutils
  for t in clang-$LLVM_VER ld.lld-$LLVM_VER llvm-ar-$LLVM_VER llvm-ranlib-$LLVM_VER llvm-nm-$LLVM_VER; do
    command -v "$t" >/dev/null || die "$t not found after installing clang-$LLVM_VER lld-$LLVM_VER llvm-$LLVM_VER"
  done
}

install_rust_bits() {
  use_rustup_toolchain
  local want=(aarch64-linux-android armv7-linux-androideabi x86_64-linux-android) have missing=() t
  have="$(rustup target list --installed)"
  for t in "${want[@]}"; do grep -qx "$t" <<<"$have" || missing+=("$t"); done
  if [ ${#missing[@]} -gt 0 ]; then
    log "rustup target add ${missing[*]}"
    rustup target add "${missing[@]}" >&2
  fi
  if cargo ndk --version >/dev/null 2>&1; then
    log "cargo-ndk present: $(cargo ndk --version 2>&1 | head -1)"
  else
    log "cargo install cargo-ndk --locked --version '$CARGO_NDK_VERSION' (takes ~2 min)"
    env -u CARGO_TARGET_DIR -u CARGO_BUILD_TARGET cargo install cargo-ndk --locked --version "$CARGO_NDK_VERSION" >&2
  fi
}

# ---------------------------------------------------------------- libunwind per ABI
# Foreign-architecture .debs are fetched with a private apt state (one per Debian architecture,
# under $CACHE/apt-<arch>) instead of `dpkg --add-architecture` + the system's lists: on these
# machines' mirror the bookworm-security armhf index has been seen broken ("File has unexpected
# size"), and apt then drops *every* index of that release, arm64's included. A private state
# per architecture keeps such a failure local to that architecture.
private_apt() {   # $1 = Debian arch, $2 = apt-get|apt-cache, rest = its args
  local arch="$1" tool="$2"; shift 2
  local d="$CACHE/apt-$arch"
  mkdir -p "$d/lists/partial" "$d/cache/archives/partial"
  cat >"$d/apt.conf" <<C
APT::Architecture "$(dpkg --print-architecture)";
APT::Architectures { "$arch"; };
Dir::State::Lists "$d/lists";
Dir::Cache "$d/cache";
Dir::State::status "/dev/null";
C
  APT_CONFIG="$d/apt.conf" "$tool" "$@"
}

# Prints the path of a Debian LLVM libunwind.a for the ABI (download + unpack into the cache once).
# Prefers libunwind-$LLVM_VER-dev; if that architecture's index lacks it (see above), falls back
# to the newest libunwind-N-dev (N = 21..16) that is there; the _Unwind_* ABI is the same.
debian_libunwind() {
  local abi="$1" arch dir deb v pkg=""
  arch="$(abi_deb_arch "$abi")"
  dir="$CACHE/debs/libunwind-$arch"
  if [ ! -f "$dir/.done" ]; then
    rm -rf "$dir"; mkdir -p "$dir"
    if ! private_apt "$arch" apt-get update -qq >"$dir/apt-update.log" 2>&1; then
      echo "note: apt-get update for $arch reported errors: $(grep '^E:' "$dir/apt-update.log" | head -1)" >&2
    fi
    for v in $LLVM_VER 21 20 19 18 17 16; do
      if private_apt "$arch" apt-cache show "libunwind-$v-dev:$arch" >/dev/null 2>&1; then pkg="libunwind-$v-dev:$arch"; break; fi
    done
    [ -n "$pkg" ] || { echo "no libunwind-N-dev:$arch (N=$LLVM_VER..16) in apt's $arch index; $(grep '^E:' "$dir/apt-update.log" | head -1)" >&2; return 1; }
    [ "$pkg" = "libunwind-$LLVM_VER-dev:$arch" ] || echo "note: libunwind-$LLVM_VER-dev:$arch is not in apt's $arch index ($(grep '^E:' "$dir/apt-update.log" | head -1 | cut -c1-160)); using $pkg" >&2
    ( cd "$dir" && private_apt "$arch" apt-get download "$pkg" >/dev/null ) || { echo "apt-get download $pkg failed" >&2; return 1; }
    deb="$(ls "$dir"/*.deb)"
    dpkg-deb -x "$deb" "$dir/root"
    echo "$pkg" >"$dir/package"
    touch "$dir/.done"
  fi
  local a
  a="$(find "$dir/root" -name libunwind.a -print -quit)"
  [ -n "$a" ] || { echo "no libunwind.a in $(cat "$dir/package")" >&2; return 1; }
  echo "libunwind from $(cat "$dir/package")" >&2
  echo "$a"
}

SHIM_C='/* glibc entry points that Debian'"'"'s LLVM libunwind calls; bionic names them differently. */
typedef struct FILE FILE;
typedef __builtin_va_list va_list;
extern int *__errno(void);
extern void abort(void) __attribute__((noreturn));
extern int vfprintf(FILE *, const char *, va_list);
__attribute__((visibility("hidden"))) int *__errno_location(void) { return __errno(); }
__attribute__((visibility("hidden"), noreturn)) void __assert_fail(const char *a, const char *f,
    unsigned l, const char *fn) { (void)a; (void)f; (void)l; (void)fn; abort(); }
__attribute__((visibility("hidden"))) int __fprintf_chk(FILE *fp, int flag, const char *fmt, ...) {
  va_list ap; int r; (void)flag; __builtin_va_start(ap, fmt); r = vfprintf(fp, fmt, ap);
  __builtin_va_end(ap); return r; }
'

build_abi() {   # $1 = ABI, $2 = new NDK root
  local abi="$1" root="$2" triple ctarget libdir tmp src lvl l
  triple="$(abi_ndk_triple "$abi")"
  ctarget="$(abi_clang_target "$abi")"
  libdir="$root/toolchains/llvm/prebuilt/linux-x86_64/sysroot/usr/lib/$triple"
  tmp="$root/.work/$abi"
  mkdir -p "$libdir" "$tmp"
  # 1. empty stub libraries with bionic's sonames (only their names matter at link time)
  : >"$tmp/empty.c"
  for l in c m dl log android; do
    clang-$LLVM_VER --target="${ctarget}21" -nostdlib -shared -fuse-ld=lld \
      -Wl,-soname,lib$l.so "$tmp/empty.c" -o "$tmp/lib$l.so" || return 1
  done
  for lvl in $API_LEVELS; do
    mkdir -p "$libdir/$lvl"
    for l in c m dl log android; do cp "$tmp/lib$l.so" "$libdir/$lvl/"; done
  done
  # 2. libunwind.a from Debian + glibc shims
  src="$(debian_libunwind "$abi")" || return 1
  cp "$src" "$libdir/libunwind.a"
  printf '%s' "$SHIM_C" >"$tmp/ecvo_glibc_shims.c"
  clang-$LLVM_VER --target="${ctarget}$ECVO_MIN_SDK" -O2 -fPIC -ffreestanding -c \
    "$tmp/ecvo_glibc_shims.c" -o "$tmp/ecvo_glibc_shims.o" || return 1
  llvm-ar-$LLVM_VER r "$libdir/libunwind.a" "$tmp/ecvo_glibc_shims.o" || return 1
  llvm-ranlib-$LLVM_VER "$libdir/libunwind.a"
  # 3. smoke test: a shared library that pulls in the unwinder links with the wrapper
  cat >"$tmp/smoke.c" <<'C'
typedef int (*trace_fn)(void *, void *);
extern int _Unwind_Backtrace(trace_fn, void *);
static int cb(void *ctx, void *arg) { (void)ctx; ++*(int *)arg; return 0; }
__attribute__((visibility("default"))) int ecvo_smoke(void) { int n = 0; _Unwind_Backtrace(cb, &n); return n; }
C
  "$root/toolchains/llvm/prebuilt/linux-x86_64/bin/clang" --target="${ctarget}$ECVO_MIN_SDK" -fPIC -shared \
    -nodefaultlibs "$tmp/smoke.c" -Wl,--whole-archive -l:libunwind.a -Wl,--no-whole-archive -o "$tmp/smoke.so" >"$tmp/smoke.log" 2>&1 \
    || { cat "$tmp/smoke.log" >&2; return 1; }
  local machine
  machine="$(readelf -h "$tmp/smoke.so" | sed -n 's/^ *Machine: *//p')"
  [ "$machine" = "$(abi_elf_machine "$abi")" ] || { echo "smoke.so machine '$machine'" >&2; return 1; }
  readelf -lW "$tmp/smoke.so" | awk '$1=="LOAD" && $NF!="0x4000"{bad=1} END{exit bad}' \
    || { echo "smoke.so LOAD segments not 16 KB aligned" >&2; return 1; }
}

write_skeleton() {   # $1 = new NDK root
  local root="$1" bin t
  bin="$root/toolchains/llvm/prebuilt/linux-x86_64/bin"
  mkdir -p "$bin" "$root/toolchains/llvm/prebuilt/linux-x86_64/sysroot/usr/include"
  cat >"$root/source.properties" <<P
Pkg.Desc = Android NDK (ecvo stand-in: link checks only; no headers, no C runtime)
Pkg.Revision = $NDK_REVISION
P
  cat >"$root/ECVO_STANDIN_NDK" <<P
This is not the Android NDK. It is a stand-in made by scripts/android/install-standin-ndk.sh
so that cargo-ndk can link ecvo's cdylib for Android on machines without the NDK:
clang-$LLVM_VER + lld-$LLVM_VER, empty bionic stub libraries, Debian's LLVM libunwind.
It cannot compile C code that includes system headers. Use a real NDK for release builds.
P
  # The compiler/linker wrapper. Link flags are only added when linking.
  local clang_bin
  clang_bin="$(command -v clang-$LLVM_VER)"
  for t in clang clang++; do
    local real="$clang_bin"
    [ "$t" = clang++ ] && real="$(command -v clang++-$LLVM_VER)"
    cat >"$bin/$t" <<W
#!/bin/sh
# ecvo stand-in NDK $t: clang-$LLVM_VER with a stub bionic sysroot (see ../../../../ECVO_STANDIN_NDK).
here=\$(cd "\$(dirname "\$0")" && pwd)
sysroot="\$here/../sysroot"
link=1
for a in "\$@"; do
  case "\$a" in -c|-S|-E|-M|-MM|--version|-dumpversion|-dumpmachine|-print-*|--print-*) link=0 ;; esac
done
if [ \$link = 0 ]; then exec "$real" --sysroot="\$sysroot" "\$@"; fi
# 16 KB pages come before "\$@" so that an explicit later -z max-page-size wins (selftest uses that).
exec "$real" --sysroot="\$sysroot" -fuse-ld=lld -nostartfiles -Wl,--no-dependent-libraries \\
  -Wl,-z,max-page-size=16384 -Wl,-z,common-page-size=16384 \\
  "\$@" -Wl,--no-as-needed -landroid -llog -ldl -lm -lc
W
    chmod +x "$bin/$t"
  done
  for t in ar ranlib nm objcopy objdump readelf strip strings size symbolizer; do
    if command -v "llvm-$t-$LLVM_VER" >/dev/null; then ln -sfn "$(command -v "llvm-$t-$LLVM_VER")" "$bin/llvm-$t"; fi
  done
  ln -sfn "$(command -v ld.lld-$LLVM_VER)" "$bin/ld.lld"
  ln -sfn "$(command -v ld.lld-$LLVM_VER)" "$bin/lld"
}

recipe_stamp() {
  {
    cat "$HERE/install-standin-ndk.sh" "$HERE/lib.sh"
    clang-$LLVM_VER --version | head -1
    echo "$ABIS|$API_LEVELS|$ECVO_MIN_SDK"
  } | sha256sum | cut -d' ' -f1
}

build_ndk() {
  local stamp
  stamp="$(recipe_stamp)"
  if [ -f "$DEST/.ecvo-stamp" ] && [ "$(cat "$DEST/.ecvo-stamp")" = "$stamp" ]; then
    log "stand-in NDK at $DEST is up to date (supported: $(cat "$DEST/abis.supported" | tr '\n' ' '))"
    return 0
  fi
  local new="$DEST.new.$$" abi
  rm -rf "$new"; mkdir -p "$new"
  trap 'rm -rf "$new"' EXIT
  write_skeleton "$new"
  : >"$new/abis.supported"; : >"$new/abis.unsupported"
  for abi in $ABIS; do
    log "building stand-in sysroot for $abi"
    local errlog="$new/.work/$abi.log"
    mkdir -p "$new/.work"
    if ( set -e; build_abi "$abi" "$new" ) 2>"$errlog"; then
      echo "$abi" >>"$new/abis.supported"
      log "  $abi: OK ($(grep -h '^libunwind from' "$errlog" | head -1); stubs for API $(echo $API_LEVELS | awk '{print $1".."$NF}'), libunwind.a, smoke link, 16 KB LOAD)"
    else
      local reason
      reason="$(grep -v '^\s*$' "$errlog" | tail -3 | tr '\n' ' ' | cut -c1-400)"
      printf '%s\t%s\n' "$abi" "${reason:-unknown error}" >>"$new/abis.unsupported"
      warn "$abi: stand-in NDK CANNOT link this ABI: ${reason:-unknown error} (full log: $DEST/.work/$abi.log)"
    fi
  done
  # Only a complete build is stamped: an ABI that failed is retried on the next run.
  if [ ! -s "$new/abis.unsupported" ]; then echo "$stamp" >"$new/.ecvo-stamp"; fi
  printf 'export ANDROID_NDK_HOME=%q\nexport ANDROID_NDK_ROOT=%q\n' "$DEST" "$DEST" >"$new/env.sh"
  rm -rf "$DEST.old"
  [ -e "$DEST" ] && mv "$DEST" "$DEST.old"
  mkdir -p "$(dirname "$DEST")"
  mv "$new" "$DEST"
  rm -rf "$DEST.old"
  trap - EXIT
}

main() {
  log "stand-in NDK -> $DEST (ABIs: $ABIS; minSdk $ECVO_MIN_SDK)"
  install_host_tools
  if [ "${ECVO_SKIP_RUST:-0}" != 1 ]; then install_rust_bits; fi
  build_ndk
  local abi failed=0
  for abi in $REQUIRED_ABIS; do
    if [[ " $ABIS " == *" $abi "* ]] && ! grep -qx "$abi" "$DEST/abis.supported"; then
      warn "required ABI $abi is not supported by the stand-in"; failed=1
    fi
  done
  if [ -s "$DEST/abis.unsupported" ]; then
    warn "unsupported ABIs (see $DEST/abis.unsupported):"; sed 's/^/    /' "$DEST/abis.unsupported" >&2
  fi
  [ $failed = 0 ] || die "stand-in NDK incomplete"
  log "done; supported ABIs: $(tr '\n' ' ' <"$DEST/abis.supported")"
  log "source $DEST/env.sh   (or eval the line below)"
  printf 'export ANDROID_NDK_HOME=%q\n' "$DEST"
}
main "$@"
