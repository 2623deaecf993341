#!/usr/bin/env python3
"""Copies the docstrings of the type stubs (rust/ecvo-py/python/ecvo/_ecvo.pyi) into
the Rust doc comments of the native module (rust/ecvo-py/src/*.rs), so that help()
on the installed package shows what the stubs say. The stubs are the one source:
edit a docstring there and run

    python3 scripts/python/sync_docs.py          # rewrite the Rust doc comments
    python3 scripts/python/sync_docs.py --check  # exit 1 if any differs

A class's docstring goes on the struct with #[pyclass(name = "...")], a method's or
property's on the fn of that name in the class's #[pymethods] impl, a function's on
the #[pyfunction] fn of that name. tests/test_stubs.py checks the result at run time.
"""

import argparse
import ast
import inspect
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STUB = ROOT / "rust/ecvo-py/python/ecvo/_ecvo.pyi"
SRC = ROOT / "rust/ecvo-py/src"


def stub_docs():
    """{(class or None, name or None): docstring} from the stub."""
    tree = ast.parse(STUB.read_text())
    docs = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            d = ast.get_docstring(node)
            if d and not node.name.startswith("_"):
                docs[(node.name, None)] = d
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    d = ast.get_docstring(item)
                    if d:
                        docs[(node.name, item.name)] = d
        elif isinstance(node, ast.FunctionDef):
            d = ast.get_docstring(node)
            if d:
                docs[(None, node.name)] = d
    return docs


def doc_lines(text, indent):
    return [f"{indent}///" + (f" {line}" if line else "") for line in inspect.cleandoc(text).splitlines()]


PYCLASS = re.compile(r'#\[pyclass\(.*name = "(\w+)"')
STRUCT = re.compile(r"^pub struct (\w+)")
IMPL = re.compile(r"^impl (\w+) \{")
FN = re.compile(r"^(\s*)(?:pub )?fn (\w+)")


def rewrite(path, docs, class_of_struct, used):
    lines = path.read_text().splitlines()

    def block_start(idx):
        """Index where the doc comment + attributes before lines[idx] begin, and where
        the doc comment ends (attributes start)."""
        j = idx
        while j > 0 and lines[j - 1].strip().startswith("#["):
            j -= 1
        attrs = j
        while j > 0 and lines[j - 1].strip().startswith("///"):
            j -= 1
        return j, attrs

    edits = []  # (start, end, new lines)
    methods = False  # a #[pymethods] seen, its impl not yet
    in_methods = None  # the Python class of the #[pymethods] impl we are in
    for idx, line in enumerate(lines):
        s = line.strip()
        if s == "#[pymethods]":
            methods = True
            continue
        m = IMPL.match(line)
        if m:
            in_methods = class_of_struct.get(m.group(1)) if methods else None
            methods = False
            continue
        if line.startswith("}"):
            in_methods = None
        m = STRUCT.match(line)
        if m and m.group(1) in class_of_struct:
            key = (class_of_struct[m.group(1)], None)
            if key in docs:
                start, attrs = block_start(idx)
                edits.append((start, attrs, doc_lines(docs[key], "")))
                used.add(key)
            continue
        m = FN.match(line)
        if m:
            indent, name = m.group(1), m.group(2)
            start, attrs = block_start(idx)
            attr_text = "\n".join(lines[attrs:idx])
            if in_methods and indent == "    ":
                key = (in_methods, name)
            elif not indent and "#[pyfunction]" in attr_text:
                key = (None, name)
            else:
                continue
            if key in docs:
                edits.append((start, attrs, doc_lines(docs[key], indent)))
                used.add(key)
    for start, end, new in reversed(edits):
        lines[start:end] = new
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    docs = stub_docs()
    class_of_struct = {}
    files = sorted(SRC.glob("*.rs"))
    for f in files:
        text = f.read_text().splitlines()
        for idx, line in enumerate(text):
            m = PYCLASS.search(line)
            if m:
                for later in text[idx + 1 : idx + 4]:
                    s = STRUCT.match(later)
                    if s:
                        class_of_struct[s.group(1)] = m.group(1)
                        break
    used = set()
    changed = []
    for f in files:
        new = rewrite(f, docs, class_of_struct, used)
        if new != f.read_text():
            changed.append(f)
            if not args.check:
                f.write_text(new)
    missing = sorted(set(docs) - used, key=str)
    for key in missing:
        print(f"sync_docs: no Rust item for {key}", file=sys.stderr)
    for f in changed:
        print(f"sync_docs: {'differs' if args.check else 'rewrote'} {f.relative_to(ROOT)}")
    return 1 if missing or (args.check and changed) else 0


if __name__ == "__main__":
    sys.exit(main())
