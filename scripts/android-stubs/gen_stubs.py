#!/usr/bin/env python3
"""Java stubs of the Android platform API, generated from TypeScript declarations.

The npm package @nativescript/types-android holds `.d.ts` declarations of the Android
platform, generated from the real `android.jar`. This script turns the classes an app
uses into Java source stubs (every method body throws), so that the app's Kotlin can be
compiled against them on a machine without the Android SDK: a real compile check of
every class, method, field and constructor the app calls.

What the declarations do not carry, and how this handles it:

- Java primitive types are all `number`. Integer literals of constants give `int` (or
  `long`), a decimal literal `double`; every other `number` is `int` unless the
  overrides file says otherwise (`Class#member` -> Java type or whole signature).
- Method type parameters are erased to `any` (`<T> T get(Key<T>)` reads
  `get(key: Key<any>): any`): the overrides file restores the ones the app needs.
- Abstract methods are not marked: stub classes are concrete, interface methods are
  abstract only for one-method interfaces (so Kotlin lambdas convert), default otherwise.
  A missing override of an abstract method is therefore not caught here.

Classes: the *full* set (every member) is the classes named on the command line, their
outer classes and their supertypes; any other android.* type a full class mentions gets
an empty *shell* (right kind, no members). Calling a member of a shell class fails to
compile: add that class to the list.

The declarations are read by `dts.py`.

Usage: gen_stubs.py DTS OUT_DIR [--overrides FILE] [--classes FILE] [CLASS ...]
"""

import argparse
import os
import re
import sys

from dts import parse, split_top


class Generator:
    super_call = ""

    def __init__(self, classes, overrides):
        self.classes = classes
        self.overrides = overrides  # key "fqn#name" or "fqn#name(n)" -> java text
        self.full = set()
        self.shells = set()

    # --- type mapping -------------------------------------------------------------------

    def resolve(self, name):
        """A TS dotted name to a Java one (nested classes keep dots)."""
        return name

    def java_type(self, t, ctx_tparams=(), for_super=False):
        t = t.strip()
        varargs = t.endswith("...")
        if varargs:
            t = t[:-3].strip()
        # T | null -> T
        parts = [p.strip() for p in split_top(t, "|")]
        parts = [p for p in parts if p not in ("null", "undefined")]
        t = parts[0] if parts else "any"
        out = self._java_type(t, ctx_tparams, for_super)
        if out == "java.lang.Object" and t.startswith("{"):
            out = "java.lang.Object"
        return out + ("..." if varargs else "")

    def _java_type(self, t, ctx_tparams, for_super):
        if t == "number":
            return "int"
        if t == "boolean":
            return "boolean"
        if t == "string":
            return "java.lang.String"
        if t in ("any", "unknown", "object"):
            return "java.lang.Object"
        if t == "void":
            return "void"
        if t in ctx_tparams:
            return t
        m = re.match(r"^androidNative\.Array<(.*)>$", t)
        if m:
            inner = self._java_type(m.group(1).strip(), ctx_tparams, False)
            return inner + "[]"
        m = re.match(r"^([\w.$]+)<(.*)>$", t)
        if m:
            base, args = m.group(1), split_top(m.group(2))
            if not self.known(base):
                return "java.lang.Object"
            self.note_type(base)
            if for_super and any(a.strip() == "any" for a in args):
                return base  # raw: the declarations lost the arguments (no wildcard in extends)
            jargs = []
            for a in args:
                if a.strip() == "any":
                    jargs.append("?")  # lost: a wildcard accepts whatever the real type is
                    continue
                j = self._java_type(a.strip(), ctx_tparams, False)
                jargs.append(box(j))
            return base + "<" + ", ".join(jargs) + ">"
        if re.match(r"^[\w.$]+$", t):
            if not self.known(t):
                return "java.lang.Object"  # not declared, or a javax.* class the JDK may lack
            self.note_type(t)
            return t
        # Function types, object literals: Object.
        return "java.lang.Object"

    def known(self, fqn):
        """A type the stubs can name: the JDK's java.*, or a declared non-JDK class (stubbed)."""
        return fqn.startswith("java.") or (fqn in self.classes and not fqn.startswith("javax."))

    def note_type(self, fqn):
        if not fqn.startswith(("java.", "javax.")) and fqn in self.classes and fqn not in self.full:
            self.shells.add(fqn)

    # --- class sets -----------------------------------------------------------------------

    def close(self, roots):
        """The full set: roots, their outer classes and supertypes (android.* only)."""
        todo = list(roots)
        while todo:
            fqn = todo.pop()
            if fqn in self.full:
                continue
            if fqn not in self.classes:
                raise SystemExit(f"gen_stubs: no class {fqn} in the declarations")
            self.full.add(fqn)
            c = self.classes[fqn]
            todo += [f for f, n in self.classes.items() if n.outer == fqn]
            if c.outer:
                todo.append(c.outer)
            for sup in ([c.extends] if c.extends else []) + c.implements:
                base = re.sub(r"<.*$", "", sup.strip())
                if base.startswith("android.") and base in self.classes:
                    todo.append(base)

    # --- emission ---------------------------------------------------------------------------

    def top_of(self, fqn):
        c = self.classes[fqn]
        while c.outer:
            c = self.classes[c.outer]
        return c

    def emit_all(self, out_dir):
        # Shells are discovered while emitting full classes; emit until stable.
        emitted_tops = {}
        done_shells = set()
        while True:
            tops = {self.top_of(f).fqn for f in self.full | self.shells}
            pending = [t for t in sorted(tops) if t not in emitted_tops or
                       emitted_tops[t] != self.signature_of_top(t)]
            if not pending:
                break
            for t in pending:
                before = self.signature_of_top(t)
                src = self.emit_top(t)
                emitted_tops[t] = before
                pkg, name = t.rsplit(".", 1)
                d = os.path.join(out_dir, *pkg.split("."))
                os.makedirs(d, exist_ok=True)
                with open(os.path.join(d, name + ".java"), "w", encoding="utf-8") as f:
                    f.write(src)
            done_shells |= self.shells
        return sorted(emitted_tops)

    def signature_of_top(self, top):
        """Which of a top class's nested classes are full or shell (re-emit when it changes)."""
        inside = sorted(f for f in self.full | self.shells if f == top or f.startswith(top + "."))
        return tuple((f, f in self.full) for f in inside)

    def nested_of(self, fqn):
        return sorted(f for f, c in self.classes.items() if c.outer == fqn and (f in self.full or f in self.shells or self.has_descendant(f)))

    def has_descendant(self, fqn):
        return any(f.startswith(fqn + ".") for f in self.full | self.shells)

    def emit_top(self, fqn):
        pkg = fqn.rsplit(".", 1)[0]
        body = self.emit_class(fqn, 0, nested=False)
        return f"// Generated by scripts/android-stubs/gen_stubs.py: a compile-time stub, not Android.\npackage {pkg};\n\n{body}"

    def emit_class(self, fqn, indent, nested):
        c = self.classes[fqn]
        full = fqn in self.full
        pad = "    " * indent
        mods = "public " + ("static " if nested else "")
        tp = ("<" + ", ".join(re.sub(r"\s+extends.*", "", t) for t in c.tparams) + ">") if c.tparams else ""
        lines = []
        if c.interface and any(i.strip() == "java.lang.annotation.Annotation" for i in c.implements):
            lines.append(f"{pad}{mods}@interface {c.name} {{")
            if full:
                for m in c.members:
                    if m.kind == "method" and not m.static and m.name not in ("equals", "hashCode", "toString", "annotationType"):
                        lines.append(f"{pad}    {self.java_type(m.ret, c.tparams)} {m.name}();")
        elif c.enum:
            consts = [m.name for m in c.members if m.kind == "field" and m.static and m.ret.strip() == fqn]
            lines.append(f"{pad}{mods}enum {c.name} {{")
            lines.append(f"{pad}    " + ", ".join(consts) + ";")
            if full:
                lines += self.emit_members(c, indent + 1, skip_enum=True)
        else:
            kind = "interface" if c.interface else ("abstract class" if c.abstract and not full else "class")
            sup = ""
            supers = [s for s in ([c.extends] if c.extends else []) if s.strip() != "java.lang.Object"]
            ifaces = list(c.implements) + split_top(self.overrides.get(f"{fqn}#<implements>", ""))
            if c.interface:
                allsup = [self.super_type(s, c) for s in supers + ifaces]
                allsup = [s for s in allsup if s and self.is_interface(s)]
                if allsup:
                    sup = " extends " + ", ".join(allsup)
            else:
                ext = [self.super_type(s, c) for s in supers]
                ext = [s for s in ext if s and not self.is_interface(s)]
                if ext:
                    sup += " extends " + ext[0]
                imp = [self.super_type(s, c) for s in ifaces]
                imp = [s for s in imp if s and self.is_interface(s)]
                if imp:
                    sup += " implements " + ", ".join(imp)
            lines.append(f"{pad}{mods}{kind} {c.name}{tp}{sup} {{")
            jdk_super = (c.extends or "").strip()
            self.super_call = JDK_SUPER_CALLS.get(re.sub(r"<.*$", "", jdk_super), "")
            if not c.interface:
                # Subclasses' constructors call super(): give every stub a no-arg one.
                has_noarg = full and any(m.kind == "ctor" and not m.params for m in c.members)
                if not has_noarg:
                    lines.append(f"{pad}    protected {c.name}() {{ {self.super_call}throw new RuntimeException(\"stub\"); }}")
            if full:
                lines += self.emit_members(c, indent + 1)
            if not c.interface:
                lines += self.missing_abstract(c, indent + 1, full)
        for n in self.nested_of(fqn):
            lines.append(self.emit_class(n, indent + 1, nested=True))
        lines.append(f"{pad}}}")
        return "\n".join(lines) + "\n"

    def super_type(self, s, c):
        s = s.strip()
        base = re.sub(r"<.*$", "", s)
        if base.startswith("android.") and base not in self.classes:
            return None
        j = self.java_type(s, c.tparams, for_super=True)
        return j

    def is_interface(self, java_name):
        base = re.sub(r"<.*$", "", java_name)
        if base in self.classes:
            return self.classes[base].interface
        try:
            import importlib  # noqa: F401
        except ImportError:
            pass
        return base in JDK_INTERFACES

    def override(self, c, m):
        keys = (f"{c.fqn}#{m.name}({','.join(m.params)})", f"{c.fqn}#{m.name}({len(m.params)})", f"{c.fqn}#{m.name}")
        for key in keys:
            if key in self.overrides:
                return self.overrides[key]
        return None

    def emit_members(self, c, indent, skip_enum=False):
        pad = "    " * indent
        out = []
        seen = set()
        methods = [m for m in c.members if m.kind == "method"]
        single_abstract = c.interface and len({m.name for m in methods if not m.static and m.name not in ("equals", "hashCode", "toString")}) == 1
        for m in c.members:
            ov = self.override(c, m)
            if m.kind == "field":
                if skip_enum and m.static and m.ret.strip() == c.fqn:
                    continue
                if m.name in seen:
                    continue
                seen.add(m.name)
                typ = ov if ov and not ov.startswith("!") else self.field_type(m, c)
                if m.static:
                    init = runtime_value(typ) if m.literal is None else literal_java(m.literal, typ)
                    out.append(f"{pad}public static final {typ} {m.name} = {init};")
                elif not c.interface:
                    out.append(f"{pad}public {typ} {m.name};")
                continue
            if ov and ov.startswith("!"):
                sig = ov[1:].strip()
                key = re.sub(r"\s+", " ", sig)
                if key in seen:
                    continue
                seen.add(key)
                out.append(f"{pad}{sig} {self.body_for(sig, c)}")
                continue
            ctx = list(c.tparams) + (m.tparams or [])
            ret = ov if ov else self.java_type(m.ret, ctx)
            params = [self.java_type(p, ctx) for p in m.params]
            gen = ("<" + ", ".join(m.tparams) + "> ") if m.tparams else ""
            # Variadic only in last position.
            params = [p.replace("...", "[]") if k < len(params) - 1 else p for k, p in enumerate(params)]
            if m.kind == "ctor":
                if c.interface or c.enum:
                    continue
                key = ("<init>", tuple(erase(p) for p in params))
                if key in seen:
                    continue
                seen.add(key)
                ps = ", ".join(f"{p} p{k}" for k, p in enumerate(params))
                out.append(f"{pad}public {c.name}({ps}) {{ {self.super_call}throw new RuntimeException(\"stub\"); }}")
                continue
            if skip_enum and m.static and m.name in ("values", "valueOf"):
                continue
            key = (m.name, tuple(erase(p) for p in params))
            if key in seen:
                continue
            seen.add(key)
            ps = ", ".join(f"{p} p{k}" for k, p in enumerate(params))
            if c.interface and not m.static:
                if m.name in ("equals", "hashCode", "toString") or (m.name == "clone" and not params):
                    continue
                if single_abstract:
                    out.append(f"{pad}{gen}{ret} {m.name}({ps});")
                else:
                    out.append(f"{pad}default {gen}{ret} {m.name}({ps}) {{ throw new RuntimeException(\"stub\"); }}")
                continue
            st = "static " if m.static else ""
            out.append(f"{pad}public {st}{gen}{ret} {m.name}({ps}) {{ throw new RuntimeException(\"stub\"); }}")
        return out

    def missing_abstract(self, c, indent, full):
        """Methods a concrete stub must have for its supertypes (JDK abstract ones, and
        the single method of an android interface it implements) but does not declare."""
        pad = "    " * indent
        declared = {m.name for m in c.members if m.kind == "method"} if full else set()
        need = []
        chain, cur = [], c
        while cur is not None:
            chain.append(cur)
            sup = re.sub(r"<.*$", "", (cur.extends or "").strip())
            if sup in JDK_ABSTRACT:
                need += JDK_ABSTRACT[sup]
            cur = self.classes.get(sup)
            if cur is not None and cur.fqn in self.full:
                declared |= {m.name for m in cur.members if m.kind == "method"}
        for k in chain:
            for i in list(k.implements) + split_top(self.overrides.get(f"{k.fqn}#<implements>", "")):
                base = re.sub(r"<.*$", "", i.strip())
                need += JDK_ABSTRACT.get(base, [])
                if base == "java.lang.Comparable" and "<" in i:
                    arg = self.java_type(i.strip()[i.index("<") + 1:-1], k.tparams)
                    need.append(("compareTo", f"public int compareTo({arg} p0)"))
                ic = self.classes.get(base)
                if ic is not None and ic.fqn in self.full and ic.interface:
                    ms = [m for m in ic.members if m.kind == "method" and not m.static and m.name not in ("equals", "hashCode", "toString")]
                    if len({m.name for m in ms}) == 1:
                        m = ms[0]
                        ps = ", ".join(f"{self.java_type(p, ic.tparams)} p{n}" for n, p in enumerate(m.params))
                        need.append((m.name, f"public {self.java_type(m.ret, ic.tparams)} {m.name}({ps})"))
        out, seen = [], set()
        for name, sig in need:
            if name in declared or name in seen:
                continue
            seen.add(name)
            out.append(f"{pad}{sig} {{ throw new RuntimeException(\"stub\"); }}")
        return out

    def body_for(self, sig, c):
        return "{ throw new RuntimeException(\"stub\"); }"

    def field_type(self, m, c):
        if m.literal is not None:
            lit = m.literal
            if lit.startswith('"'):
                return "java.lang.String"
            if lit in ("true", "false"):
                return "boolean"
            if "." in lit or "e" in lit.lower():
                return "double"
            v = int(lit)
            return "int" if -2**31 <= v < 2**31 else "long"
        return self.java_type(m.ret, c.tparams)


# Constructor calls for JDK superclasses without a no-arg constructor.
JDK_SUPER_CALLS = {
    "java.io.FileInputStream": "super((java.io.FileDescriptor) null); ",
    "java.io.FileOutputStream": "super((java.io.FileDescriptor) null); ",
    "java.io.FilterInputStream": "super(null); ",
    "java.io.FilterOutputStream": "super(null); ",
    "java.io.PrintWriter": "super((java.io.Writer) null); ",
    "java.io.InputStreamReader": "super((java.io.InputStream) null); ",
}

# Abstract methods of JDK types a concrete stub must implement.
JDK_ABSTRACT = {
    "java.lang.AutoCloseable": [("close", "public void close()")],
    "java.io.Closeable": [("close", "public void close()")],
    "java.lang.Number": [("intValue", "public int intValue()"), ("longValue", "public long longValue()"),
                         ("floatValue", "public float floatValue()"), ("doubleValue", "public double doubleValue()")],
    "java.lang.Runnable": [("run", "public void run()")],
    "java.io.InputStream": [("read", "public int read()")],
    "java.io.OutputStream": [("write", "public void write(int p0)")],
}

JDK_INTERFACES = {
    "java.lang.Runnable", "java.lang.AutoCloseable", "java.io.Closeable", "java.lang.Cloneable",
    "java.io.Serializable", "java.lang.Comparable", "java.lang.CharSequence", "java.lang.Iterable",
    "java.util.Collection", "java.util.List", "java.util.Map", "java.util.Set", "java.util.Iterator",
    "java.util.EventListener", "java.lang.Appendable", "java.lang.Readable", "java.io.Flushable",
    "java.util.concurrent.Executor", "java.lang.reflect.AnnotatedElement", "java.io.Externalizable",
    "java.util.RandomAccess", "java.util.Queue", "java.util.Deque", "java.util.function.Consumer",
    "java.lang.reflect.Type", "java.lang.reflect.GenericDeclaration", "java.nio.channels.Channel",
}


def box(j):
    return {"int": "java.lang.Integer", "long": "java.lang.Long", "float": "java.lang.Float",
            "double": "java.lang.Double", "boolean": "java.lang.Boolean", "short": "java.lang.Short",
            "byte": "java.lang.Byte", "char": "java.lang.Character"}.get(j, j)


def erase(j):
    return re.sub(r"<.*>", "", j).replace("...", "[]")


def default_value(t):
    if t == "boolean":
        return "false"
    if t in ("int", "short", "byte", "char"):
        return "0"
    if t == "long":
        return "0L"
    if t == "float":
        return "0f"
    if t == "double":
        return "0.0"
    return "null"


BOXES = {"boolean": "Boolean", "int": "Integer", "short": "Short", "byte": "Byte", "char": "Character",
         "long": "Long", "float": "Float", "double": "Double"}


def runtime_value(t):
    """The initialiser of a static final field the declarations give no value for (such as
    Build.VERSION.SDK_INT): not a compile-time constant, so that Kotlin and javac read the
    field at run time instead of inlining the stub's value (which would fold away every
    `if (Build.VERSION.SDK_INT >= N)` branch)."""
    if t in BOXES:
        return f"{BOXES[t]}.valueOf(({t}) {default_value(t)})"
    if t in ("java.lang.String", "String"):
        return "String.valueOf((Object) null)"
    return "null"


def literal_java(lit, typ):
    if typ == "java.lang.String":
        return lit
    if typ == "long":
        return lit + "L"
    if typ == "float":
        return lit + "f"
    if typ in ("int", "double", "boolean"):
        return lit
    if typ == "short":
        return f"(short) {lit}"
    if typ == "byte":
        return f"(byte) {lit}"
    return default_value(typ)


def read_overrides(path):
    """`Class#member[(arity)] = java type` (field type or method return), or
    `Class#member[(arity)] = !full Java declaration` (a whole method)."""
    ov = {}
    if not path:
        return ov
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.split(" //", 1)[0].strip()
            if not line or line.startswith("#"):
                continue
            if "=" not in line:
                raise SystemExit(f"{path}:{n}: expected `Class#member = type`")
            k, v = line.split("=", 1)
            ov[k.strip()] = v.strip()
    return ov


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dts")
    ap.add_argument("out")
    ap.add_argument("--overrides")
    ap.add_argument("--classes", action="append", default=[])
    ap.add_argument("names", nargs="*")
    a = ap.parse_intermixed_args(argv)
    roots = list(a.names)
    for cf in a.classes:
        with open(cf, encoding="utf-8") as f:
            roots += [l.split("#")[0].strip() for l in f if l.split("#")[0].strip()]
    classes = parse(a.dts)
    g = Generator(classes, read_overrides(a.overrides))
    # Overrides may name methods of classes the app reaches only through them.
    g.close(roots)
    tops = g.emit_all(a.out)
    print(f"gen_stubs: {len(g.full)} full classes, {len(g.shells - g.full)} shells, {len(tops)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
