#!/usr/bin/env python3
"""API-level check of an APK's dex: every reference into the platform (android.*, java.*,
javax.*, everything not defined in the dex itself) must exist at minSdk, or sit where an
SDK_INT check guarantees a high enough level. See docs/android-apk.md ("The API-level check").

Levels. A class or member is at level <= 23 when the API 23 android.jar (Debian's
libandroid-23-java) has it (exact JVM descriptor, inherited members included). Otherwise its
level is the `/** @since N */` of @nativescript/types-android's merged 21..37 declarations (the
member's, else its class's); a member there without any @since that is not in the API 23 jar is
taken as level 37 (the data has no @since 37: such members are new in 37 or not public).
Members are matched by name, arity and coarse types (the declarations are TypeScript: every
number is `number`); several equally matching overloads give the lowest of their levels.
A class or member found in neither is an error ("not in the Android API").

Guards. A reference is guarded at level N when every path to it in its method passes the true
side of a comparison of android.os.Build$VERSION.SDK_INT with a constant that implies
SDK_INT >= N (`if (SDK_INT >= 33) ...`, `> 32`, `== 33`, either operand order, and their
negations on the other branch). This is a dataflow over dexdump's instructions: a lower bound
on SDK_INT per instruction, the registers holding SDK_INT or constants tracked through const,
sget and move; meet = minimum; exception handlers and switch targets inherit the bound of every
instruction that may reach them (a switch conservatively reaches every instruction).
The AndroidX convention is honoured too: code inside a class whose binary name has a component
`Api<N>Impl` (e.g. `MainActivity$Api30Impl`) is checked at level N, and every call into such a
class counts as a reference of level N (so it must be guarded itself).
Not detected as guards: a check in a caller (guard the call site of a helper, or put the helper
in an Api<N>Impl class), SDK_INT read through a field or a helper method, try/catch of
NoClassDefFoundError / NoSuchMethodError, and class-loading checks (Class.forName).
A dex class whose superclass or interfaces need API L (e.g. an object implementing
OnBackInvokedCallback, 33) is treated the same way: its own code is checked at L, and every
reference to it (new-instance, calls, fields, const-class) must be guarded at L; ART loads such
a class lazily, at its first use. A supertype not in the Android API at all is an error.

Usage: api_levels.py DEX_OR_DEXDUMP --dts MERGED.d.ts --android-jar android-23.jar
           [--min-sdk 26] [--allow FILE] [--list-guarded]
Exit status 1 when there is a finding; the findings go to stdout, one a line.
"""
import argparse
import os
import re
import struct
import subprocess
import sys
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "android-stubs"))
from dts import parse as parse_dts  # noqa: E402  (the .d.ts parser, with @since)

NEWEST = 37
FLOOR = 23  # everything in the API 23 jar is taken as available at minSdk (>= 23)
SDK_INT = "Landroid/os/Build$VERSION;.SDK_INT:I"
API_IMPL = re.compile(r"(?:^|[/$])Api(\d+)Impl(?:$|\$)")


# --- the API 23 jar --------------------------------------------------------------------------
def read_jar(path):
    """{internal name: (super, [interfaces], {name+desc of methods and fields})}."""
    out = {}
    with zipfile.ZipFile(path) as z:
        for n in z.namelist():
            if n.endswith(".class"):
                c = parse_class(z.read(n))
                out[c[0]] = c[1:]
    return out


def parse_class(b):
    pos = 10
    (count,) = struct.unpack_from(">H", b, 8)
    cp = [None] * count
    i = 1
    while i < count:
        tag = b[pos]
        if tag == 1:
            (ln,) = struct.unpack_from(">H", b, pos + 1)
            cp[i] = b[pos + 3:pos + 3 + ln].decode("utf-8", "replace")
            pos += 3 + ln
        elif tag in (3, 4):
            pos += 5
        elif tag in (5, 6):
            pos += 9
            i += 1
        elif tag == 7 or tag == 8 or tag == 16 or tag == 19 or tag == 20:
            cp[i] = ("ref", struct.unpack_from(">H", b, pos + 1)[0]) if tag == 7 else None
            pos += 3
        elif tag in (9, 10, 11, 12, 17, 18):
            pos += 5
        elif tag == 15:
            pos += 4
        else:
            raise ValueError(f"constant pool tag {tag}")
        i += 1

    def cls(idx):
        return cp[cp[idx][1]] if idx else None

    this, sup, nif = struct.unpack_from(">HHH", b, pos + 2)
    pos += 8
    ifaces = [cls(struct.unpack_from(">H", b, pos + 2 * k)[0]) for k in range(nif)]
    pos += 2 * nif
    members = set()
    for _ in range(2):
        (n,) = struct.unpack_from(">H", b, pos)
        pos += 2
        for _ in range(n):
            _acc, name, desc, nattr = struct.unpack_from(">HHHH", b, pos)
            pos += 8
            members.add(cp[name] + ":" + cp[desc])
            for _ in range(nattr):
                (ln,) = struct.unpack_from(">I", b, pos + 2)
                pos += 6 + ln
    return cls(this), cls(sup), ifaces, members


# --- descriptors <-> TypeScript types ----------------------------------------------------------
def split_desc(desc):
    """'(I[Ljava/lang/String;)V' -> (['I', '[Ljava/lang/String;'], 'V'); a field type -> (None, T)."""
    if not desc.startswith("("):
        return None, desc
    params, i, end = [], 1, desc.index(")")
    while i < end:
        j = i
        while desc[j] == "[":
            j += 1
        j = desc.index(";", j) + 1 if desc[j] == "L" else j + 1
        params.append(desc[i:j])
        i = j
    return params, desc[end + 1:]


def ts_matches(ts, jt):
    """Does TypeScript type `ts` (from the declarations) fit JVM type `jt`?"""
    ts = ts.strip()
    if ts.endswith("..."):
        ts = "androidNative.Array<" + ts[:-3] + ">"
    ts = re.sub(r"\s*\|\s*null$", "", ts)
    if jt.startswith("["):
        m = re.match(r"^androidNative\.Array<(.*)>$", ts)
        return ts == "any" or (m is not None and ts_matches(m.group(1), jt[1:]))
    prim = {"I": "number", "J": "number", "F": "number", "D": "number", "S": "number", "B": "number",
            "Z": "boolean", "C": "string", "V": "void"}
    if jt in prim:
        return ts == prim[jt]
    name = jt[1:-1].replace("/", ".").replace("$", ".")
    base = re.sub(r"<.*>$", "", ts)
    if base in ("any", "java.lang.Object") or re.fullmatch(r"[A-Z]\w*", base):  # type parameter
        return True
    if base == "string":
        return name in ("java.lang.String", "java.lang.CharSequence")
    return base == name


# --- the declarations ---------------------------------------------------------------------------
class Platform:
    def __init__(self, dts, jar):
        self.jar = read_jar(jar)
        self.dts = {}
        for fqn, c in parse_dts(dts).items():
            self.dts[fqn] = c

    @staticmethod
    def dotted(internal):
        return internal.replace("/", ".").replace("$", ".")

    def dts_class(self, internal):
        return self.dts.get(self.dotted(internal))

    def known(self, internal):
        return internal in self.jar or self.dts_class(internal) is not None

    def class_level(self, internal):
        if internal in self.jar:
            return FLOOR
        c = self.dts_class(internal)
        if c is None:
            return None
        return c.since or NEWEST

    def jar_has(self, internal, key, seen=None):
        seen = seen if seen is not None else set()
        if internal is None or internal in seen or internal not in self.jar:
            return False
        seen.add(internal)
        sup, ifaces, members = self.jar[internal]
        if key in members:
            return True
        return any(self.jar_has(s, key, seen) for s in [sup] + ifaces)

    def dts_supers(self, c):
        out = []
        for t in ([c.extends] if c.extends else []) + list(c.implements):
            t = re.sub(r"<.*>$", "", t.strip())
            if t in self.dts:
                out.append(self.dts[t])
        return out

    def member_level(self, internal, name, desc):
        """(level, note) of a member reached through class `internal`, or (None, why)."""
        cl = self.class_level(internal)
        if cl is None:
            return None, "class not in the Android API"
        if self.jar_has(internal, name + ":" + desc):
            return FLOOR, ""
        if name == "<clinit>":
            return cl, ""
        params, ret = split_desc(desc)
        start = self.dts_class(internal)
        if start is None:
            return None, "member not in the API 23 jar, class not in the declarations"
        best, seen, todo = [], set(), [start]
        if "java.lang.Object" in self.dts:
            todo.append(self.dts["java.lang.Object"])
        while todo:
            c = todo.pop(0)
            if c.fqn in seen:
                continue
            seen.add(c.fqn)
            for m in c.members:
                if params is None:
                    ok = m.kind == "field" and m.name == name
                else:
                    ok = (m.name == name and m.kind in ("method", "ctor") and len(m.params) == len(params)
                          and all(ts_matches(t, j) for t, j in zip(m.params, params))
                          and (m.kind == "ctor" or ts_matches(m.ret, ret)))
                if ok:
                    best.append(m.since or c.since or NEWEST)
            if best or name == "<init>":
                break  # the nearest declaring class wins; constructors are not inherited
            todo.extend(self.dts_supers(c))
        if not best:
            return None, "member not in the Android API"
        return max(min(best), cl), ""


# --- dexdump ----------------------------------------------------------------------------------
INSN = re.compile(r"^[0-9a-f]+: [0-9a-f ]+\|([0-9a-f]{4}): (\S+)\s*(.*)$")
REF = re.compile(r"(L[^;\s]+;)\.([^:\s]+):(\S+)")
TYPE_OPS = ("new-instance", "const-class", "check-cast", "instance-of", "new-array", "filled-new-array",
            "filled-new-array/range")
NO_DEST = ("if-", "iput", "sput", "aput", "invoke-", "return", "throw", "goto", "packed-switch",
           "sparse-switch", "monitor-", "fill-array-data", "nop", "filled-new-array")
FLIP = {"lt": "gt", "gt": "lt", "le": "ge", "ge": "le", "eq": "eq", "ne": "ne"}
NEG = {"lt": "ge", "ge": "lt", "le": "gt", "gt": "le", "eq": "ne", "ne": "eq"}


class Method:
    def __init__(self, cls, name, desc):
        self.cls, self.name, self.desc = cls, name, desc
        self.insns = []  # (addr, op, args)
        self.catches = []  # (start, end, handler)


def intern(d):
    """'Lpkg/Cls;' -> 'pkg/Cls'."""
    return d[1:-1] if d.startswith("L") and d.endswith(";") else d


def parse_dexdump(text):
    classes, methods = {}, []
    cur_cls = cur = None
    in_catches = False
    lines = text.split("\n")
    for k, line in enumerate(lines):
        s = line.strip()
        if s.startswith("Class descriptor"):
            cur_cls = intern(s.split("'")[1])
            classes[cur_cls] = {"super": None, "ifaces": [], "members": set()}
            section = None
            continue
        if cur_cls is None:
            continue
        if s.startswith("Superclass"):
            classes[cur_cls]["super"] = intern(s.split("'")[1]) if "'" in s else None
            continue
        if s.startswith("Interfaces"):
            section = "ifaces"
            continue
        if s.startswith(("Static fields", "Instance fields", "Direct methods", "Virtual methods")):
            section = "members"
            continue
        if section == "ifaces" and s.startswith("#") and "'" in s:
            classes[cur_cls]["ifaces"].append(intern(s.split("'")[1]))
            continue
        if s.startswith("name          :"):
            pending_name = s.split("'")[1]
            continue
        if s.startswith("type          :") and section == "members":
            classes[cur_cls]["members"].add(pending_name + ":" + s.split("'")[1])
            continue
        m = re.match(r"^[0-9a-f]+:\s+\|\[[0-9a-f]+\] (.*)\.([^.:]+):(\(.*)$", s)
        if m:
            cur = Method(cur_cls, m.group(2), m.group(3))
            methods.append(cur)
            in_catches = False
            continue
        if cur is None:
            continue
        mi = INSN.match(s)
        if mi:
            cur.insns.append((int(mi.group(1), 16), mi.group(2), mi.group(3)))
            continue
        if s.startswith("catches"):
            in_catches = "(none)" not in s
            rng = None
            continue
        if in_catches:
            mr = re.match(r"^0x([0-9a-f]+) - 0x([0-9a-f]+)$", s)
            if mr:
                rng = (int(mr.group(1), 16), int(mr.group(2), 16))
                continue
            mh = re.match(r"^\S+ -> 0x([0-9a-f]+)$", s)
            if mh and rng:
                cur.catches.append((rng[0], rng[1], int(mh.group(1), 16)))
                continue
            in_catches = False
    return classes, methods


def regs_of(args):
    part = args.split(" // ")[0]
    return re.findall(r"\bv(\d+)\b", part.split("}")[0] if "{" in part else part)


def guard_bounds(m, floor):
    """Lower bound on SDK_INT before each instruction (by index), from the method's branches."""
    n = len(m.insns)
    index = {a: i for i, (a, _, _) in enumerate(m.insns)}
    state = [None] * n  # (bound, frozenset of (reg, value)) or None = unreached
    state[0] = (floor, frozenset()) if n else None

    def meet(a, b):
        if a is None:
            return b
        return (min(a[0], b[0]), a[1] & b[1])

    work = [0] if n else []
    while work:
        i = work.pop()
        bound, regs = state[i]
        addr, op, args = m.insns[i]
        regd = dict(regs)
        rs = regs_of(args)
        outs = []  # (index, state)
        # register transfer
        if op == "sget" and SDK_INT in args:
            regd[rs[0]] = "sdk"
        elif op.startswith("const") and not op.startswith(("const-string", "const-class")) and "#int" in args:
            regd.pop(rs[0], None)
            regd.pop(str(int(rs[0]) + 1), None)
            mv = re.search(r"#int (-?\d+)", args)
            if mv and "wide" not in op:
                regd[rs[0]] = int(mv.group(1))
        elif op.startswith("move") and not op.startswith(("move-result", "move-exception")) and len(rs) >= 2:
            v = regd.get(rs[1])
            regd.pop(rs[0], None)
            if v is not None and "wide" not in op:
                regd[rs[0]] = v
        elif rs and not op.startswith(NO_DEST):
            regd.pop(rs[0], None)
            regd.pop(str(int(rs[0]) + 1), None)
        after = frozenset(regd.items())
        taken = fall = bound
        target = None
        if op.startswith("if-"):
            target = int(args.split(",")[-1].split("//")[0].strip(), 16)
            cmp_op = op[3:]
            if len(rs) == 2 and cmp_op in FLIP:
                a, b = regd.get(rs[0]), regd.get(rs[1])
                cond = None
                if a == "sdk" and isinstance(b, int):
                    cond = (cmp_op, b)
                elif b == "sdk" and isinstance(a, int):
                    cond = (FLIP[cmp_op], a)
                if cond:
                    taken = max(bound, implied(*cond))
                    fall = max(bound, implied(NEG[cond[0]], cond[1]))
        if op.startswith("goto"):
            outs.append((index.get(int(args.split()[0], 16)), bound))
        elif op.startswith(("return", "throw")):
            pass
        elif op.startswith(("packed-switch", "sparse-switch")):
            outs += [(j, bound) for j in range(n)]
        else:
            if i + 1 < n and not op.endswith("-data"):
                outs.append((i + 1, fall))
            if target is not None:
                outs.append((index.get(target), taken))
        for s_, e_, h in m.catches:
            if s_ <= addr < e_:
                outs.append((index.get(h), bound))
        for j, b in outs:
            if j is None:
                continue
            new = meet(state[j], (b, after if not m.insns[j][1].startswith("move-exception") else frozenset()))
            if new != state[j]:
                state[j] = new
                work.append(j)
    return [s[0] if s else None for s in state]


def implied(op, n):
    return {"ge": n, "gt": n + 1, "eq": n}.get(op, 0)


def api_impl_level(internal):
    m = API_IMPL.findall(internal)
    return int(m[-1]) if m else None


# --- the check --------------------------------------------------------------------------------
def check(dexdump_text, platform, min_sdk, allow=(), guarded=None):
    """Findings (sorted lines) and the number of methods; references above min_sdk that a
    guard (or an Api<N>Impl class) covers are appended to `guarded` when it is a list."""
    classes, methods = parse_dexdump(dexdump_text)
    findings = []
    cache = {}

    def resolve(cls, name, desc):
        key = (cls, name, desc)
        if key in cache:
            return cache[key]
        c, seen = cls, set()
        res = None
        while c in classes and c not in seen:
            seen.add(c)
            if name is None:
                res = (0, "")
                break
            if name + ":" + desc in classes[c]["members"]:
                # a member of the dex itself: available, except inside an Api<N>Impl class
                res = (api_impl_level(c) or 0, "")
                break
            # an inherited member: look in the interfaces defined in the dex, then the superclass
            c = classes[c]["super"]
        if res is None:
            if c is None:
                res = (None, "not found")
            elif name is None:
                lv = platform.class_level(c)
                res = (lv, "" if lv else "class not in the Android API")
            else:
                res = platform.member_level(c, name, desc)
                if res[0] is None and c != cls:
                    # maybe declared by an interface of a dex class (default / abstract member)
                    for i in all_ifaces(cls):
                        if i not in classes:
                            r2 = platform.member_level(i, name, desc)
                            if r2[0] is not None:
                                res = r2
                                break
        cache[key] = res
        return res

    def all_ifaces(c, seen=None):
        seen = seen if seen is not None else set()
        out = []
        while c in classes and c not in seen:
            seen.add(c)
            for i in classes[c]["ifaces"]:
                out.append(i)
                out += all_ifaces(i, seen)
            c = classes[c]["super"]
        if c and c not in classes:
            out.append(c)
        return out

    def report(where, ref, level, why, have):
        line = f"{where}: {ref} "
        if level is None:
            line += f"-- {why}"
        else:
            line += f"needs API {level}{' (no @since data; assumed newest)' if level == NEWEST else ''}, " \
                    f"guaranteed here: {have}"
        if not any(a and a in line for a in allow):
            findings.append(line)

    # A dex class whose supertypes need API L loads only from L on: its code is checked at L and
    # every reference to it counts as level L (like an Api<N>Impl class, with N inferred).
    need = {}

    def class_need(c, seen=()):
        if c not in classes or c in seen:
            return 0
        if c not in need:
            lv = api_impl_level(c) or 0
            for s in [classes[c]["super"]] + classes[c]["ifaces"]:
                if not s:
                    continue
                sl = class_need(s, seen + (c,)) if s in classes else (platform.class_level(s) or 0)
                lv = max(lv, sl)
            need[c] = lv
        return need[c]

    for c, info in classes.items():
        for s in [info["super"]] + info["ifaces"]:
            if s and s not in classes and platform.class_level(s) is None:
                report(f"{c} (class header)", s, None, "class not in the Android API", min_sdk)
    for m in methods:
        floor = max(min_sdk, class_need(m.cls))
        bounds = guard_bounds(m, floor)
        for i, (addr, op, args) in enumerate(m.insns):
            have = bounds[i]
            if have is None:
                continue  # unreachable
            body = args.split(" // ")[0]
            refs = []
            r = REF.search(body)
            if r and (op.startswith(("invoke-", "iget", "iput", "sget", "sput"))):
                refs.append((r.group(1), r.group(2), r.group(3)))
            elif op in TYPE_OPS or op.startswith("filled-new-array"):
                t = re.search(r"(\[*L[^;\s]+;)", body)
                if t:
                    refs.append((t.group(1).lstrip("["), None, None))
            for cls, name, desc in refs:
                lvl, why = resolve(cls[1:-1] if cls.startswith("L") else cls, name, desc)
                # a reference to a dex class that loads only from API N on counts as level N
                target = cls[1:-1] if cls.startswith("L") else cls
                if lvl is not None and class_need(target) > min_sdk:
                    lvl = max(lvl, class_need(target))
                ref = f"{cls}" + (f".{name}:{desc}" if name else "")
                if lvl is None or lvl > have:
                    report(f"{m.cls}.{m.name} @{addr:04x}", ref, lvl, why, have)
                elif lvl > min_sdk and guarded is not None:
                    guarded.append(f"{m.cls}.{m.name} @{addr:04x}: {ref} (API {lvl}) guarded at {have}")
    return sorted(set(findings)), len(methods)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dex", help="classes.dex, an .apk, or a dexdump -d text file")
    ap.add_argument("--dts", required=True)
    ap.add_argument("--android-jar", required=True)
    ap.add_argument("--min-sdk", type=int, default=26)
    ap.add_argument("--allow", help="file of substrings; a finding containing one is not reported")
    ap.add_argument("--list-guarded", action="store_true",
                    help="also list (stderr) the references above minSdk that a guard covers")
    a = ap.parse_args(argv)
    if a.dex.endswith((".dex", ".apk")):
        text = subprocess.run(["dexdump", "-d", a.dex], check=True, capture_output=True, text=True).stdout
    else:
        with open(a.dex, encoding="utf-8", errors="replace") as f:
            text = f.read()
    allow = []
    if a.allow:
        with open(a.allow) as f:
            allow = [ln.split("#")[0].strip() for ln in f if ln.split("#")[0].strip()]
    platform = Platform(a.dts, a.android_jar)
    guarded = [] if a.list_guarded else None
    findings, n = check(text, platform, a.min_sdk, allow, guarded)
    for g in sorted(set(guarded or [])):
        print("guarded: " + g, file=sys.stderr)
    for f in findings:
        print(f)
    print(f"api-levels: {n} methods checked at minSdk {a.min_sdk}: {len(findings)} finding(s)", file=sys.stderr)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
