#!/usr/bin/env python3
"""Import circles between the files of a Rust crate (issue 46: "leave no import circle").

A file `a.rs` depends on `b.rs` when it names `crate::b` (in a `use` or a path), or
`super::b` from a child module; a module file depends on nothing through its own `mod`
declarations (a parent owning a child is not an import). Prints every strongly
connected component of more than one file and exits 1 if there is one.

    python3 scripts/dev/module_cycles.py rust/ecvo-core/src
"""
import re
import sys
import os
STRICT = os.environ.get("STRICT") == "1"
from pathlib import Path


def module_of(src: Path, f: Path) -> tuple:
    parts = list(f.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def strip_comments(text: str) -> str:
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//")[0] for line in text.splitlines())


def test_cfg_spans(text: str) -> str:
    """Drops `#[cfg(test)] mod x { ... }` blocks: tests may import anything."""
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text):
        if m.start() < i:
            continue
        out.append(text[i:m.start()])
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        i = j
    out.append(text[i:])
    return "".join(out)


def paths_named(text: str):
    """Every `crate::a::b` / `super::a` path, with `use` groups expanded one level."""
    for m in re.finditer(r"\b(crate|super|self)((?:::\w+)*)(::\{([^}]*)\})?", text):
        base = [m.group(1)] + [p for p in m.group(2).split("::") if p]
        if m.group(4):
            for item in m.group(4).split(","):
                item = item.strip().split("::")[0].split(" ")[0]
                if item and item != "self":
                    yield base + [item]
                elif item == "self":
                    yield base
        else:
            yield base


def main() -> int:
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "rust/ecvo-core/src")
    files = sorted(p for p in src.rglob("*.rs") if "tests" not in p.relative_to(src).parts
                   and p.name not in ("tests.rs",))
    mods = {module_of(src, f): f for f in files}
    edges = {m: set() for m in mods}
    for m, f in mods.items():
        text = test_cfg_spans(strip_comments(f.read_text()))
        # `use child::X` (a path relative to this module) names a child module.
        rel = [["self"] + [p for p in g.split("::") if p]
               for g in re.findall(r"\buse\s+((?:\w+::)+)", text)
               if g.split("::")[0] not in ("crate", "super", "self", "std", "core")]
        for path in list(paths_named(text)) + rel:
            if path[0] == "crate":
                parts = path[1:]
            elif path[0] == "self":
                parts = list(m) + path[1:]
            else:
                parts = list(m[:-1]) + path[1:]
            # The longest prefix that is a module file.
            for k in range(len(parts), 0, -1):
                t = tuple(parts[:k])
                if t in mods:
                    if t != m and (STRICT or t != m[: len(t)]):
                        edges[m].add(t)
                    break
    # Tarjan's strongly connected components.
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(comp)

    sys.setrecursionlimit(10000)
    for v in mods:
        if v not in index:
            visit(v)
    circles = [c for c in comps if len(c) > 1]
    for c in circles:
        names = sorted(str(mods[m].relative_to(src)) for m in c)
        print(f"import circle of {len(c)} files: {', '.join(names)}")
    print(f"{len(mods)} files, {sum(len(e) for e in edges.values())} imports, "
          f"{len(circles)} import circle(s)")
    return 1 if circles else 0


if __name__ == "__main__":
    sys.exit(main())
