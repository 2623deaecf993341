#!/usr/bin/env bash
# Verifies an Android JNI library built for one ABI.
#
# Usage: scripts/android/check-so.sh SO ABI KOTLIN_SRC_DIR
#   SO              the .so (e.g. android-app/app/src/main/jniLibs/arm64-v8a/libecvo_jni.so)
#   ABI             arm64-v8a | armeabi-v7a | x86_64 | x86
#   KOTLIN_SRC_DIR  folder searched recursively for *.kt files with `external fun`
# Environment:
#   ECVO_MIN_SDK       minSdk the symbols must exist at (default 26)
#   ECVO_BIONIC_TSV    symbol table (default: shared/android/bionic-ndk-symbols.tsv next to the repo,
#                      or /work/shared/android/bionic-ndk-symbols.tsv)
#   ECVO_PAGE_ALIGN    required LOAD alignment (default 0x4000 = 16 KB)
#
# Checks (all are run; every failure is reported, then exit 1):
#   1. ELF: `readelf -h` Machine is AArch64 / ARM / Advanced Micro Devices X86-64 / Intel 80386
#      for the ABI, class ELF64/ELF32 to match, type DYN.
#   2. Every PT_LOAD has p_align a multiple of 0x4000 (16 KB pages) and offset == vaddr mod align.
#   3. Every JNI name implied by the Kotlin `external fun` declarations is a defined, exported
#      (GLOBAL/WEAK, DEFAULT/PROTECTED) FUNC in .dynsym.  Supported Kotlin shapes:
#        - `external fun` members of a class or object (instance or @JvmStatic; same JNI name),
#          including nested classes/objects (Outer$Inner -> Outer_00024Inner);
#        - top-level `external fun` in File.kt -> class FileKt (or @file:JvmName("X"));
#        - @JvmName("x") on the function replaces its JVM name;
#        - short JNI names only (Java_<pkg>_<class>_<method>), mangled per the JNI spec:
#          '_' -> _1, ';' -> _2, '[' -> _3, '$' and non-ASCII -> _0xxxx, '.' -> '_'.
#      Rejected with a message (not silently mis-mapped): overloads (same class + JVM name twice:
#      give them distinct @JvmName), `internal` external funs without @JvmName (Kotlin mangles
#      their JVM name), external funs in companion objects, anonymous objects or local classes.
#      Comments and string literals are ignored.
#   4. Every undefined dynamic symbol (weak ones too) is provided to apps at minSdk, for this
#      ABI's architecture, by:
#        - bionic libc / libm / libdl, per bionic-ndk-symbols.tsv (introduced_api <= minSdk,
#          architecture column "all" or listing the ABI's arch);
#        - liblog: __android_log_* (all API levels);
#        - libandroid: ATrace_beginSection/endSection/isEnabled (API 23),
#          ATrace_beginAsyncSection/endAsyncSection/setCounter (API 29), and by prefix (API <= 26
#          for all of these families) AAsset*, AAssetManager_*, AAssetDir_*, ALooper_*,
#          ANativeWindow_*, AConfiguration_*, AChoreographer_* (API 24+: checked as 24),
#          ASharedMemory_* (API 26), AHardwareBuffer_* (API 26).
#      With ECVO_JNI_REGISTER_NATIVES=1, declared methods may instead be registered at run time
#      (RegisterNatives in an exported JNI_OnLoad, which is then required); those are listed, not checked.
#   5. DT_NEEDED only lists libc.so, libm.so, libdl.so, liblog.so, libandroid.so.
#   6. DT_SONAME is set, is a library file name (lib<name>.so), and equals the file's name when
#      the file is called lib*.so.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=lib.sh
. "$HERE/lib.sh"

[ $# -eq 3 ] || { sed -n '3,8p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
SO="$1"; ABI="$2"; KT="$3"
[ -f "$SO" ] || die "no such file: $SO"
[ -d "$KT" ] || die "no such Kotlin source folder: $KT"
abi_rust_target "$ABI" >/dev/null
TSV="${ECVO_BIONIC_TSV:-}"
if [ -z "$TSV" ]; then
  for c in "$HERE/../../../shared/android/bionic-ndk-symbols.tsv" "$HERE/../../shared/android/bionic-ndk-symbols.tsv" \
           /work/shared/android/bionic-ndk-symbols.tsv; do
    [ -f "$c" ] && { TSV="$c"; break; }
  done
fi
[ -n "$TSV" ] && [ -f "$TSV" ] || die "bionic-ndk-symbols.tsv not found (set ECVO_BIONIC_TSV)"
READELF="$(command -v readelf || command -v llvm-readelf-22 || command -v llvm-readelf || true)"
[ -n "$READELF" ] || die "readelf not found (apt-get install binutils)"
command -v python3 >/dev/null || die "python3 not found"

tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
LC_ALL=C "$READELF" -hW "$SO" >"$tmp/h" 2>"$tmp/err" || die "readelf -h failed on $SO: $(cat "$tmp/err")"
LC_ALL=C "$READELF" -lW "$SO" >"$tmp/l"
LC_ALL=C "$READELF" -dW "$SO" >"$tmp/d"
LC_ALL=C "$READELF" --dyn-syms -W "$SO" >"$tmp/s"

python3 - "$SO" "$ABI" "$KT" "$TSV" "$ECVO_MIN_SDK" "${ECVO_PAGE_ALIGN:-0x4000}" \
  "$(abi_elf_machine "$ABI")" "$(abi_bionic_arch "$ABI")" "$tmp" <<'PY'
import os, re, sys
so, abi, ktdir, tsv, min_sdk, align_req, want_machine, arch, tmp = sys.argv[1:]
min_sdk = int(min_sdk); align_req = int(align_req, 0)
errors, notes = [], []
def read(n): return open(os.path.join(tmp, n), encoding="utf-8", errors="replace").read()

# 1. ELF header -------------------------------------------------------------------------
h = read("h")
def hfield(name):
    m = re.search(r"^\s*" + re.escape(name) + r":\s*(.*?)\s*$", h, re.M)
    return m.group(1) if m else "?"
machine, klass, etype = hfield("Machine"), hfield("Class"), hfield("Type")
want_class = "ELF64" if abi in ("arm64-v8a", "x86_64") else "ELF32"
if machine != want_machine:
    errors.append(f"ELF machine is '{machine}', expected '{want_machine}' for {abi}")
if klass != want_class:
    errors.append(f"ELF class is {klass}, expected {want_class} for {abi}")
if not etype.startswith("DYN"):
    errors.append(f"ELF type is '{etype}', expected DYN (shared object)")

# 2. LOAD segments ----------------------------------------------------------------------
loads = []
for line in read("l").splitlines():
    f = line.split()
    if f and f[0] == "LOAD":
        off, vaddr, align = int(f[1], 16), int(f[2], 16), int(f[-1], 16)
        loads.append(align)
        if align == 0 or align % align_req:
            errors.append(f"LOAD segment at offset {f[1]} vaddr {f[2]} has alignment {f[-1]}, "
                          f"expected a multiple of {align_req:#x} (16 KB pages: link with -Wl,-z,max-page-size=16384)")
        elif off % align != vaddr % align:
            errors.append(f"LOAD segment at offset {f[1]}: offset and vaddr not congruent modulo {f[-1]}")
if not loads:
    errors.append("no LOAD segments found")

# 5. NEEDED -----------------------------------------------------------------------------
allowed_needed = ["libc.so", "libm.so", "libdl.so", "liblog.so", "libandroid.so"]
needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", read("d"))
for n in needed:
    if n not in allowed_needed:
        errors.append(f"NEEDED {n} is not allowed (only {', '.join(allowed_needed)}; "
                      "libc++_shared.so etc. would have to be shipped in the APK)")

# 6. SONAME ---------------------------------------------------------------------------------
# Android's linker identifies a loaded library by DT_SONAME (required for apps targeting API
# 23+; without it the linker falls back to the file name and warns). It must name the file
# the APK ships (lib<crate>.so): when the checked file is called lib*.so, the same name.
sonames = re.findall(r"\(SONAME\)\s+Library soname: \[([^\]]+)\]", read("d"))
base = os.path.basename(so)
if not sonames:
    errors.append("no DT_SONAME: link with -Wl,-soname,<file name> (scripts/build-android.sh passes "
                  "-C link-arg=-Wl,-soname,lib<crate>.so; the NDK's build systems do the same)")
elif not re.fullmatch(r"lib[A-Za-z0-9_]+\.so", sonames[0]):
    errors.append(f"DT_SONAME is '{sonames[0]}', not a library file name lib<name>.so")
elif base.startswith("lib") and base.endswith(".so") and sonames[0] != base:
    errors.append(f"DT_SONAME is '{sonames[0]}' but the file is {base}")

# dynamic symbols ---------------------------------------------------------------------------
defined, undefined = {}, {}
for line in read("s").splitlines():
    f = line.split()
    if len(f) < 8 or not f[0].rstrip(":").isdigit():
        continue
    typ, bind, vis, ndx, name = f[3], f[4], f[5], f[6], f[7]
    name = name.split("@")[0]
    if ndx == "UND":
        undefined[name] = bind
    elif bind in ("GLOBAL", "WEAK") and vis in ("DEFAULT", "PROTECTED"):
        defined[name] = typ

# 3. Kotlin external funs -> JNI names ----------------------------------------------------
def mangle(s):
    out = []
    for ch in s:
        if ch.isascii() and ch.isalnum(): out.append(ch)
        elif ch in "./": out.append("_")
        elif ch == "_": out.append("_1")
        elif ch == ";": out.append("_2")
        elif ch == "[": out.append("_3")
        else:
            b = ch.encode("utf-16-be")
            out.extend("_0" + b[k:k+2].hex() for k in range(0, len(b), 2))
    return "".join(out)

def strip_code(src):
    """Blank out comments and string/char literals, keeping offsets and newlines."""
    out, i, n = [], 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i); j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j): depth += 1; j += 2
                elif src.startswith("*/", j): depth -= 1; j += 2
                else: j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j])); i = j
        elif src.startswith('"""', i):
            j = src.find('"""', i + 3); j = n if j < 0 else j + 3
            out.append('""' + re.sub(r"[^\n]", " ", src[i+2:j-1]) + '"'); i = j
        elif c in "\"'":
            j = i + 1
            while j < n and src[j] != c and src[j] != "\n":
                j += 2 if src[j] == "\\" else 1
            j = min(j + 1, n)
            # blank the contents; annotation arguments are read from the raw text at the same offsets
            out.append(c + re.sub(r"[^\n]", " ", src[i+1:j-1]) + (c if j - 1 > i else "")); i = j
        else:
            out.append(c); i += 1
    return "".join(out)

decl_re = re.compile(r"(?<!::)\b(?:(companion)\s+object|(object)|(class|interface))\b(?:\s+(`[^`]+`|\w+))?")
fun_re = re.compile(r"((?:@[\w.:]+(?:\([^)]*\))?\s*|\b(?:public|private|internal|protected|open|final|override|"
                    r"suspend|inline|tailrec|operator|infix|actual|expect|external)\s+)*)"
                    r"\bfun\s+(?:<[^>]*>\s*)?(?:[\w.<>?, ]+\.)?(`[^`]+`|\w+)\s*\(")
def header_ok(t):
    """Text between `class X` and `{`: constructor, supertypes, where-clauses; nothing else."""
    prev = None
    while prev != t:
        prev, t = t, re.sub(r"\([^()]*\)|<[^<>]*>", " ", t)
    return re.fullmatch(r"[^{};=()]*", t) is not None and not re.search(r"\b(fun|val|var|init|class|object|interface)\b", t)
expected = {}   # jni name -> origin
decl_errors = []
kt_files = sorted(os.path.join(d, f) for d, _, fs in os.walk(ktdir) for f in fs if f.endswith(".kt"))
for path in kt_files:
    raw = open(path, encoding="utf-8").read()
    src = strip_code(raw)
    rel = os.path.relpath(path, ktdir)
    m = re.search(r"^\s*package\s+([\w.]+)", src, re.M)
    pkg = m.group(1) if m else ""
    m = re.search(r'@file\s*:\s*JvmName\(\s*"([^"]+)"\s*\)', src)
    base = os.path.basename(path)[:-3]
    facade = m.group(1) if m else (base[:1].upper() + base[1:] + "Kt")
    # Walk braces, tracking class/object scopes.
    events = []
    for dm in decl_re.finditer(src):
        kind = "companion" if dm.group(1) else ("object" if dm.group(2) else dm.group(3))
        name = (dm.group(4) or "").strip("`")
        if kind == "companion": name = name or "Companion"
        # anonymous object expression (`object : Foo`, `= object {`): no name
        events.append((dm.start(), "decl", kind, name, dm.end()))
    for fm in fun_re.finditer(src):
        mods = raw[fm.start(1):fm.end(1)] if fm.group(1) else ""
        if re.search(r"\bexternal\b", mods):
            events.append((fm.start(2), "fun", mods, fm.group(2).strip("`"), fm.end()))
    for i, ch in enumerate(src):
        if ch in "{}": events.append((i, ch, None, None, None))
    events.sort(key=lambda e: (e[0], 0 if e[1] in ("decl", "fun") else 1))
    stack, pending, depth = [], None, 0   # stack entries: (depth_inside, kind, name)
    fun_depth = []                        # depths of function bodies / other blocks
    for pos, what, a, b, end in events:
        if what == "decl":
            pending = (a, b, end)
        elif what == "{":
            depth += 1
            if pending is not None and header_ok(src[pending[2]:pos]):
                stack.append((depth, pending[0], pending[1]))
            pending = None
        elif what == "}":
            if stack and stack[-1][0] == depth: stack.pop()
            depth -= 1
        elif what == "fun":
            pending = None
            line = src.count("\n", 0, pos) + 1
            where = f"{rel}:{line}"
            mods, name = a, b
            scopes = [s for s in stack]
            inner_depth = scopes[-1][0] if scopes else 0
            if depth != inner_depth:
                decl_errors.append(f"{where}: external fun {name} is inside a function, lambda or "
                                   "anonymous object: not supported"); continue
            if any(s[1] == "companion" for s in scopes):
                decl_errors.append(f"{where}: external fun {name} is in a companion object: not supported "
                                   "(its JNI name depends on @JvmStatic handling); put it in a top-level object"); continue
            if any(not s[2] for s in scopes):
                decl_errors.append(f"{where}: external fun {name} is in an anonymous object: not supported"); continue
            jm = re.search(r'@JvmName\(\s*"([^"]+)"\s*\)', mods)
            jvm_name = jm.group(1) if jm else name
            if re.search(r"\binternal\b", mods) and not jm:
                decl_errors.append(f"{where}: internal external fun {name} without @JvmName: Kotlin mangles "
                                   "its JVM name (name$module); make it non-internal or add @JvmName"); continue
            cls = "$".join(s[2] for s in scopes) if scopes else facade
            fq = (pkg + "." if pkg else "") + cls
            jni = "Java_" + mangle(fq) + "_" + mangle(jvm_name)
            origin = f"{where} {fq}.{jvm_name}"
            if jni in expected:
                decl_errors.append(f"{where}: external fun {name} overloads {expected[jni]} (same class and JVM "
                                   f"name -> long JNI name with signature, not supported): give each overload "
                                   "a distinct @JvmName")
                continue
            expected[jni] = origin
errors += decl_errors
register = os.environ.get("ECVO_JNI_REGISTER_NATIVES") == "1"
if register and "JNI_OnLoad" not in defined:
    errors.append("ECVO_JNI_REGISTER_NATIVES=1 but the library does not export JNI_OnLoad")
for jni, origin in sorted(expected.items()):
    if register and jni not in defined:
        continue   # registered at run time by JNI_OnLoad: not checkable here
    if jni not in defined:
        how = "is undefined (imported!)" if jni in undefined else "is not exported"
        hint = ("; the library exports JNI_OnLoad: if it registers this method with RegisterNatives, "
                "set ECVO_JNI_REGISTER_NATIVES=1") if "JNI_OnLoad" in defined else ""
        errors.append(f"JNI symbol {jni} ({origin}) {how}{hint}")
    elif defined[jni] != "FUNC":
        errors.append(f"JNI symbol {jni} ({origin}) is a {defined[jni]}, not a FUNC")
if not kt_files:
    errors.append(f"no .kt files under {ktdir}")
elif not expected and not decl_errors:
    errors.append(f"no `external fun` declarations found under {ktdir}")
extra_jni = sorted(s for s in defined if s.startswith("Java_") and s not in expected)

# 4. undefined symbols ----------------------------------------------------------------------
bionic = {}
for line in open(tsv, encoding="utf-8"):
    if line.startswith("#") or not line.strip(): continue
    f = line.rstrip("\n").split("\t")
    if len(f) < 4: continue
    sym, lib, api, arches = f[0], f[1], int(f[2]), f[3].split(",")
    if "all" in arches or arch in arches:
        old = bionic.get(sym)
        if old is None or api < old[1]:
            bionic[sym] = (lib, api)
libandroid_exact = {"ATrace_beginSection": 23, "ATrace_endSection": 23, "ATrace_isEnabled": 23,
                    "ATrace_beginAsyncSection": 29, "ATrace_endAsyncSection": 29, "ATrace_setCounter": 29}
libandroid_prefix = [("AAssetManager_", 9), ("AAssetDir_", 9), ("AAsset_", 9), ("ALooper_", 9),
                     ("ANativeWindow_", 9), ("AConfiguration_", 9), ("AChoreographer_", 24),
                     ("ASharedMemory_", 26), ("AHardwareBuffer_", 26)]
def provider(sym):
    if sym in bionic:
        lib, api = bionic[sym]
        return (lib, api)
    if sym.startswith("__android_log_"): return ("liblog", 1)
    if sym in libandroid_exact: return ("libandroid", libandroid_exact[sym])
    for p, api in libandroid_prefix:
        if sym.startswith(p): return ("libandroid", api)
    return None
by_lib = {}
for sym, bind in sorted(undefined.items()):
    if not sym: continue
    p = provider(sym)
    weak = " (weak)" if bind == "WEAK" else ""
    if p is None:
        other = [l for l in open(tsv, encoding="utf-8") if l.split("\t")[0] == sym]
        hint = f"; bionic has it only for {other[0].split(chr(9))[3].strip()}" if other else ""
        errors.append(f"undefined symbol {sym}{weak} is not provided by bionic libc/libm/libdl, liblog or "
                      f"libandroid for {abi} ({arch}){hint}")
    elif p[1] > min_sdk:
        errors.append(f"undefined symbol {sym}{weak} needs API {p[1]} ({p[0]}), but minSdk is {min_sdk}")
    else:
        by_lib.setdefault(p[0], []).append(sym)

name = os.path.basename(so)
if errors:
    print(f"check-so: {name} [{abi}]: FAILED ({len(errors)} problem{'s' if len(errors) > 1 else ''})", file=sys.stderr)
    for e in errors: print(f"  - {e}", file=sys.stderr)
    sys.exit(1)
print(f"check-so: {name} [{abi}] OK")
print(f"  machine   {machine} ({klass})")
print(f"  LOAD      {len(loads)} segments, alignments {', '.join(sorted({hex(a) for a in loads}))}")
print(f"  NEEDED    {', '.join(needed)}")
missing = sorted(j for j in expected if j not in defined)
if missing:
    print(f"  JNI       {len(expected)} declared; {len(missing)} not exported, assumed registered by JNI_OnLoad "
          f"(ECVO_JNI_REGISTER_NATIVES=1): {', '.join(missing)}")
else:
    print(f"  JNI       {len(expected)} declared in {len(kt_files)} .kt file(s), all exported: {', '.join(sorted(expected))}")
if extra_jni: print(f"  note      exported Java_ symbols without a Kotlin declaration: {', '.join(extra_jni)}")
print(f"  undefined {sum(len(v) for v in by_lib.values())} symbols, all available at API {min_sdk}: " +
      ", ".join(f"{k} {len(v)}" for k, v in sorted(by_lib.items())))
PY
