"""The type stubs and the runtime agree: every class, attribute and parameter, every
key of the returned dicts, every docstring (help() shows what the stubs say); and
mypy --strict accepts the examples against them."""

import ast
import inspect
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ecvo
from ecvo import _ecvo

PKG = Path(__file__).resolve().parents[1]
STUB = PKG / "python" / "ecvo" / "_ecvo.pyi"
INIT_STUB = PKG / "python" / "ecvo" / "__init__.pyi"
EXAMPLES = sorted((PKG / "examples").glob("*.py"))


def stub_tree():
    return ast.parse(STUB.read_text())


def stub_classes():
    return {n.name: n for n in stub_tree().body if isinstance(n, ast.ClassDef)}


def stub_functions():
    return {n.name: n for n in stub_tree().body if isinstance(n, ast.FunctionDef)}


def members(cls_node):
    """Names defined in a stub class body (methods, properties; overloads once)."""
    return {n.name for n in cls_node.body if isinstance(n, ast.FunctionDef)}


def typed_dict_keys(name):
    node = stub_classes()[name]
    return {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}


def public(names):
    return {n for n in names if not (n.startswith("__") and n.endswith("__"))}


RUNTIME_CLASSES = ["Camera", "FrameResult", "Tracker", "Sequence", "SequenceIterator"]


def test_module_names_agree():
    tree = stub_tree()
    stub_all = next(
        ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "__all__"
    )
    assert set(stub_all) - {"__version__"} == public(dir(_ecvo)) - {"_ecvo"}
    init = ast.parse(INIT_STUB.read_text())
    init_all = next(
        ast.literal_eval(n.value) for n in init.body if isinstance(n, ast.Assign) and n.targets[0].id == "__all__"
    )
    assert init_all == ecvo.__all__


@pytest.mark.parametrize("name", RUNTIME_CLASSES)
def test_class_attributes_agree(name):
    stub = public(members(stub_classes()[name]))
    runtime = public(dir(getattr(_ecvo, name)))
    assert stub == runtime, f"stub only: {stub - runtime}, runtime only: {runtime - stub}"


def stub_params(fn):
    a = fn.args
    names = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
    names = [n for n in names if n not in ("self", "cls")]
    return names, a.vararg is not None, a.kwarg is not None


def runtime_params(obj):
    sig = inspect.signature(obj)
    names = [
        p.name
        for p in sig.parameters.values()
        if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name not in ("self", "cls", "$self", "$cls")
    ]
    kinds = {p.kind for p in sig.parameters.values()}
    return names, inspect.Parameter.VAR_POSITIONAL in kinds, inspect.Parameter.VAR_KEYWORD in kinds


def callables():
    """(label, runtime object, stub FunctionDef) for every function and method."""
    out = [(n, getattr(_ecvo, n), f) for n, f in stub_functions().items()]
    for cname, node in stub_classes().items():
        if cname not in RUNTIME_CLASSES:
            continue
        cls = getattr(_ecvo, cname)
        for f in node.body:
            if not isinstance(f, ast.FunctionDef) or f.name.startswith("__"):
                continue
            if any(isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list):
                continue
            out.append((f"{cname}.{f.name}", getattr(cls, f.name), f))
        new = next((f for f in node.body if isinstance(f, ast.FunctionDef) and f.name == "__new__"), None)
        if new is not None:
            out.append((cname, cls, new))
    return out


@pytest.mark.parametrize("label, obj, fn", callables(), ids=lambda x: x if isinstance(x, str) else "")
def test_parameters_agree(label, obj, fn):
    assert runtime_params(obj) == stub_params(fn), label


def docs():
    """(label, runtime docstring, stub docstring) for everything the stub documents."""
    out = []
    for name, f in stub_functions().items():
        d = ast.get_docstring(f)
        if d:
            out.append((name, inspect.getdoc(getattr(_ecvo, name)), d))
    for cname, node in stub_classes().items():
        if cname not in RUNTIME_CLASSES:
            continue
        cls = getattr(_ecvo, cname)
        d = ast.get_docstring(node)
        if d:
            out.append((cname, inspect.getdoc(cls), d))
        for f in node.body:
            if isinstance(f, ast.FunctionDef) and ast.get_docstring(f):
                out.append((f"{cname}.{f.name}", inspect.getdoc(getattr(cls, f.name)), ast.get_docstring(f)))
    return out


@pytest.mark.parametrize("label, runtime, stub", docs(), ids=lambda x: x if isinstance(x, str) and "\n" not in x and len(x) < 40 else "")
def test_help_shows_the_stub_docstrings(label, runtime, stub):
    assert runtime == stub, f"{label}: run scripts/python/sync_docs.py"


def test_every_public_callable_is_documented():
    for cname in RUNTIME_CLASSES[:-1]:
        cls = getattr(_ecvo, cname)
        assert inspect.getdoc(cls), cname
        for n in public(dir(cls)):
            assert inspect.getdoc(getattr(cls, n)), f"{cname}.{n}"
    for n in ("read_sequence", "run_sequence", "ate"):
        assert inspect.getdoc(getattr(_ecvo, n)), n
    text = inspect.getdoc(_ecvo.Tracker.push)
    for word in ("uint8", "uint16", "float32", "metres", "(height, width", "TypeError", "ValueError", "rgb", "bgr"):
        assert word in text, word
    text = inspect.getdoc(_ecvo.Tracker)
    for key in ("memory_budget", "keyframe_spread", "depth_noise", "RuntimeError"):
        assert key in text, key


def test_returned_dicts_have_the_stub_keys(synth):
    seq = ecvo.read_sequence(synth, max_frames=5)
    tracker = ecvo.Tracker(seq.camera)
    for f in seq:
        tracker.push(*f)
    counters = tracker.counters()
    assert set(counters) == typed_dict_keys("_Counters")
    for k in ("keyframe_fallbacks", "overlap_keyframes", "keyframe_spread_refusals", "keyframe_fusions"):
        assert k in counters
    run = ecvo.run_sequence(synth, max_frames=5)
    assert set(run) == typed_dict_keys("_RunResult")
    assert set(run["counters"]) == typed_dict_keys("_Counters")
    assert set(run["ate"]) == typed_dict_keys("_Ate")
    assert set(ecvo.ate(seq.groundtruth, seq.groundtruth)) == typed_dict_keys("_Ate")


def test_properties_have_the_stub_types(synth):
    seq = ecvo.read_sequence(synth, max_frames=3)
    tracker = ecvo.Tracker(seq.camera)
    rs = [tracker.push(*f) for f in seq]
    r = rs[-1]
    assert isinstance(r.pose, np.ndarray) and r.pose.dtype == np.float64
    assert isinstance(r.information, np.ndarray) and r.information.shape == (6, 6)
    assert isinstance(r.point_fraction, float) and isinstance(r.valid_points, int)
    assert isinstance(r.template_points, int) and isinstance(r.reference_levels, int)
    assert isinstance(r.recovered, bool) and isinstance(r.timestamp, float) and isinstance(r.index, int)
    c = seq.camera
    for k in ("width", "height"):
        assert isinstance(getattr(c, k), int)
    for k in ("fx", "fy", "cx", "cy", "depth_scale"):
        assert isinstance(getattr(c, k), float)
    assert isinstance(tracker.closed, bool) and isinstance(tracker._last_engine_s, float)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_mypy_strict_accepts_the_examples(example, tmp_path):
    p = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "--cache-dir", str(tmp_path), str(example)],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stdout + p.stderr
