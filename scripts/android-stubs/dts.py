"""A parser of the TypeScript declarations of @nativescript/types-android.

The package's `.d.ts` files declare every class of the Android platform (generated from
the real `android.jar`) as nested `declare module` / `export class` blocks, with a
`/** @since N */` comment before each class and member added after API level 1.
`parse` reads one such file into `{fqn: Cls}`: the classes with their type parameters,
supertypes and members (fields, methods and constructors, types kept as TypeScript
text). `gen_stubs.py` turns them into Java stubs and `../android/api_levels.py` checks
the app's API levels with the `since` fields.
"""

import re
from dataclasses import dataclass, field


@dataclass
class Member:
    kind: str  # "field", "method", "ctor"
    name: str
    static: bool
    params: list  # list of TS type strings
    ret: str  # TS type (field type for fields), "" for ctors
    literal: str = None  # constant value text for literal-typed static fields
    line: int = 0
    tparams: list = None  # a generic method's own type parameters
    since: int = None  # API level of a `/** @since N */` comment before it (None: no comment)


@dataclass
class Cls:
    fqn: str  # dotted, nested classes joined with '.'
    name: str
    tparams: list
    extends: str
    implements: list
    abstract: bool
    interface: bool = False
    enum: bool = False
    members: list = field(default_factory=list)
    outer: str = None  # fqn of the enclosing class, if nested
    line: int = 0
    since: int = None  # as Member.since


def split_top(s, sep=","):
    """Splits at `sep` outside <>, (), {}."""
    out, depth, cur = [], 0, []
    for ch in s:
        if ch in "<({[":
            depth += 1
        elif ch in ">)}]":
            depth -= 1
        if ch == sep and depth == 0:
            out.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if "".join(cur).strip():
        out.append("".join(cur).strip())
    return out


CLASS_RE = re.compile(
    r"^export (abstract )?class (\w+)(<[^{]*?>)?\s*(?:extends ([^{]*?))?\s*(?:implements ([^{]*?))?\s*\{$"
)


def parse(path):
    """Returns {fqn: Cls} for every class in a NativeScript .d.ts file."""
    classes = {}
    stack = []  # entries: ("module", name) or ("class", Cls) or ("block", None)
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    i = 0
    pending_interface = False
    pending_since = None
    since_re = re.compile(r"@since (\d+)")
    while i < len(lines):
        raw = lines[i]
        s = raw.strip()
        i += 1
        if not s or s.startswith("///") or s.startswith("import "):
            continue
        if s.startswith("/**") or s.startswith("*") or s.startswith("*/"):
            if "interface with the provided implementation" in s:
                pending_interface = True
            ms = since_re.search(s)
            if ms:
                pending_since = int(ms.group(1))
            continue
        if s.startswith("declare module ") or s.startswith("export module "):
            name = s.split()[2]
            stack.append(("module", name))
            continue
        m = CLASS_RE.match(s)
        if m:
            path_parts = [n if k == "module" else n.name for k, n in stack if k in ("module", "class")]
            # Module names that equal an enclosing class's name continue its nesting.
            fqn = ".".join(path_parts + [m.group(2)])
            outer = None
            if stack and stack[-1][0] == "module":
                maybe = ".".join(path_parts)
                if maybe in classes:
                    outer = maybe
            tparams = [t.strip() for t in split_top(m.group(3)[1:-1])] if m.group(3) else []
            ext = (m.group(4) or "").strip() or None
            impl = split_top(m.group(5)) if m.group(5) else []
            c = Cls(fqn, m.group(2), tparams, ext, impl, bool(m.group(1)), outer=outer, line=i,
                    since=pending_since)
            pending_since = None
            classes[fqn] = c
            stack.append(("class", c))
            continue
        if s == "}":
            if stack:
                stack.pop()
            continue
        if stack and stack[-1][0] == "class":
            c = stack[-1][1]
            # A member: may span lines (constructor(implementation: { ... })).
            stmt = s
            depth = stmt.count("{") - stmt.count("}")
            while depth > 0 and i < len(lines):
                nxt = lines[i].strip()
                i += 1
                stmt += " " + nxt
                depth += nxt.count("{") - nxt.count("}")
            if "implementation:" in stmt:
                c.interface = True
                continue
            if pending_interface:
                c.interface = True
                pending_interface = False
            mem = parse_member(stmt, i)
            if mem:
                mem.since = pending_since
                c.members.append(mem)
            pending_since = None
            continue
        # Something else opening a block (should not happen): track braces.
        if s.endswith("{"):
            stack.append(("block", None))
    for c in classes.values():
        names = {m.name for m in c.members if m.kind == "method" and m.static}
        if c.extends is None and "values" in names and "valueOf" in names and not c.interface:
            c.enum = True
    return classes


MEMBER_RE = re.compile(r"^public (static )?(?:readonly )?(constructor|[\w$]+)(<[^(]*>)?\s*(\(.*\))?\s*(?::\s*(.*))?;$")


def parse_member(stmt, line):
    m = MEMBER_RE.match(stmt)
    if not m:
        return None
    static, name, tp, params, typ = m.groups()
    mtp = [re.sub(r"\s+extends.*", "", t).strip() for t in split_top(tp[1:-1])] if tp else []
    if name == "class" and static:
        return None
    if params is not None:
        inner = params[1:-1].strip()
        ps = []
        for p in split_top(inner) if inner else []:
            if ":" not in p:
                return None
            pname, ptype = p.split(":", 1)
            if pname.strip().startswith("..."):
                ptype = ptype.strip() + "..."
            ps.append(ptype.strip())
        if name == "constructor":
            return Member("ctor", "<init>", False, ps, "", line=line)
        return Member("method", name, bool(static), ps, (typ or "void").strip(), line=line, tparams=mtp)
    typ = (typ or "any").strip()
    literal = None
    if re.match(r'^-?\d+(\.\d+)?([eE][-+]?\d+)?$', typ) or typ.startswith('"') or typ in ("true", "false"):
        literal = typ
    return Member("field", name, bool(static), [], typ, literal=literal, line=line)
