"""lanelib's import graph, read from the source with ``ast``: no cycles, no late imports, layers.

The layers, bottom to top (``docs/architecture.md``, ``LAYERS`` below): errors; params (every
parameter record); io; the stages on arrays (thresholds, records, fit, search, checks, result, draw,
and the hard-road parts they call: roads); geometry (camera, perspective, autogeometry, and every
line in the lines view, a view made from the ego perspective: lines); data; config; the one-frame
engines (pipeline, the basic hough pipeline); the tracker; batch (folders, videos, predict),
cluster, evaluate, bench, synth, benchmarks; the scoreboard; widgets; cli.
A module imports only from its own layer or below, never from above, and every import is at
module level (a function-level import hides a cycle instead of removing it). An import under
``if TYPE_CHECKING:`` is an edge like any other: a cycle that only type checkers follow is still
a cycle of the design.
"""
from __future__ import annotations

import ast
import functools
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "lanelib"


def module_name(path: Path, package: Path = PACKAGE) -> str:
    rel = path.relative_to(package.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def resolve(node: ast.ImportFrom, current: str, is_package: bool) -> list[str]:
    """Return the lanelib modules an ``import from`` names (absolute names)."""
    if node.level:
        base = current.split(".") if is_package else current.split(".")[:-1]
        base = base[:len(base) - (node.level - 1)]
        prefix = ".".join(base + ([node.module] if node.module else []))
    else:
        prefix = node.module or ""
    root = prefix.split(".")[0]
    if not prefix or root != current.split(".")[0]:
        return []
    # the bare package (``from . import io`` names the package itself) is imported first in any case
    return [f"{prefix}.{a.name}" for a in node.names] + ([prefix] if prefix != root else [])


def read_graph(package: Path) -> tuple[dict[str, set[str]], list[str]]:
    """Return {module: modules of ``package`` it imports at module level} and the late imports.

    An import under ``if TYPE_CHECKING:`` at module level counts as an edge: it is there for
    the type checkers only, but a cycle through it is a cycle of the design all the same.
    """
    files = {module_name(p, package): p for p in package.rglob("*.py")}
    edges: dict[str, set[str]] = {m: set() for m in files}
    late = []
    for mod, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        is_package = path.name == "__init__.py"
        toplevel = {id(n) for n in _module_level(tree.body)}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                targets = resolve(node, mod, is_package)
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == package.name]
            else:
                continue
            targets = [t for t in targets if t in files]
            if not targets:
                continue
            if id(node) not in toplevel:
                late.append(f"{path.relative_to(package.parent)}:{node.lineno} imports "
                            f"{', '.join(sorted(set(targets)))} inside a function")
                continue
            edges[mod].update(t for t in targets if t != mod)
    return edges, late


@functools.lru_cache(maxsize=1)
def graph() -> tuple[dict[str, set[str]], list[str]]:
    """Return lanelib's import graph and its late imports (``read_graph``)."""
    return read_graph(PACKAGE)


def _module_level(body: list[ast.stmt]):
    """Yield the import statements at module level (not inside a function), those under
    ``if TYPE_CHECKING:`` included."""
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        else:
            for field in ("body", "orelse", "finalbody", "handlers"):
                inner = getattr(node, field, None)
                if isinstance(inner, list):
                    yield from _module_level([n for n in inner if isinstance(n, ast.AST)])


def find_cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """Return one import cycle as a list of modules (first == last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for n in sorted(edges.get(m, ())):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state:
                found = visit(n)
                if found:
                    return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def test_find_cycle_finds_a_cycle_and_only_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"a2"}, "a2": set(), "b": {"c"}, "c": {"b"}}) == ["b", "c", "b"]


def test_resolve_relative_imports():
    node = ast.parse("from ..camera import Calibration").body[0]
    assert "lanelib.camera" in resolve(node, "lanelib.synth.truth", False)
    node = ast.parse("from . import io, draw").body[0]
    assert {"lanelib.io", "lanelib.draw"} <= set(resolve(node, "lanelib.pipeline", False))
    node = ast.parse("from .base import Tuner").body[0]
    assert "lanelib.widgets.base" in resolve(node, "lanelib.widgets", True)


def test_the_graph_counts_type_checking_imports_and_finds_their_cycle(tmp_path):
    pkg = tmp_path / "toy"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("from typing import TYPE_CHECKING\n"
                              "if TYPE_CHECKING:\n    from .a import Thing\n")
    (pkg / "c.py").write_text("def f():\n    from . import a\n")
    edges, late = read_graph(pkg)
    assert edges == {"toy": set(), "toy.a": {"toy.b"}, "toy.b": {"toy.a"}, "toy.c": set()}
    assert find_cycle(edges) == ["toy.a", "toy.b", "toy.a"]
    assert late == ["toy/c.py:2 imports toy.a inside a function"]


def test_lanelib_has_no_import_cycle():
    edges, _ = graph()
    assert len(edges) > 15
    cycle = find_cycle(edges)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


# imported only by the one function that needs them: each costs about 1 s at every command's start
HEAVY_IMPORTS = ("scipy.optimize", "scipy.interpolate", "dask", "distributed")


def test_the_command_line_starts_without_the_heavy_imports():
    code = ("import sys, lanelib.cli, lanelib.evaluate, lanelib.batch; "
            f"print([m for m in {HEAVY_IMPORTS!r} if m in sys.modules])")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert p.stdout.strip() == "[]", p.stdout


def test_lanelib_has_no_function_level_imports():
    _, late = graph()
    assert not late, "late imports (move them to the top of the module):\n" + "\n".join(late)


LAYERS = [
    {"lanelib.errors"},
    {"lanelib.params"},                     # every parameter record (imports only errors)
    {"lanelib.io"},
    {"lanelib.thresholds", "lanelib.records", "lanelib.fit", "lanelib.search", "lanelib.checks",
     "lanelib.result", "lanelib.draw", "lanelib.proposers", "lanelib.bands",  # stages
     "lanelib.roads"},                      # hard-road parts
    {"lanelib.camera", "lanelib.perspective", "lanelib.autogeometry",
     "lanelib.lines"},                      # every line in view: its view is made from the perspective
    {"lanelib.data"},
    {"lanelib.config"},                     # nests the records of params; JSON and presets
    {"lanelib.pipeline", "lanelib.hough"},  # the one-frame engines: advanced, basic
    {"lanelib.tracking"},                   # the tracker loop over a LanePipeline
    {"lanelib.batch", "lanelib.cluster", "lanelib.evaluate", "lanelib.compare", "lanelib.bench",
     "lanelib.synth",
     "lanelib.benchmarks", "lanelib.benchmarks.why", "lanelib.benchmarks.why_images"},  # why: predict's frames explained
    {"lanelib.scoreboard", "lanelib.ablation"},  # measure with batch, evaluate and the benchmarks
    {"lanelib.widgets"},
    {"lanelib.cli", "lanelib.__main__", "lanelib"},  # cli: a package, argument parsing only
]


def layer_of(module: str) -> int:
    """Return the layer index of a module (a subpackage's modules share its layer)."""
    for i, layer in enumerate(LAYERS):
        for name in layer:
            if module == name or (name != "lanelib" and module.startswith(name + ".")):
                return i
    raise AssertionError(f"{module}: not in any layer; add it to LAYERS and docs/architecture.md")


@pytest.mark.parametrize("module", sorted(graph()[0]))
def test_imports_go_down_the_layers(module):
    edges = graph()[0]
    up = sorted(t for t in edges[module] if layer_of(t) > layer_of(module))
    assert not up, f"{module} (layer {layer_of(module)}) imports from a layer above it: {up}"


# the core (docs/architecture.md): what the notebooks 01-07 teach; extensions plug into it.
# ``lanelib.hough`` is not in it: the basic pipeline people learn first (notebook 00: Canny,
# region of interest, Hough), its own engine beside the core; no core module imports it.
CORE = {"lanelib.errors", "lanelib.io", "lanelib.thresholds", "lanelib.records", "lanelib.fit",
        "lanelib.search", "lanelib.checks", "lanelib.proposers", "lanelib.bands",
        "lanelib.result", "lanelib.draw", "lanelib.camera", "lanelib.perspective", "lanelib.data",
        "lanelib.config", "lanelib.pipeline", "lanelib.tracking", "lanelib.tracking.state",
        "lanelib.tracking.judge", "lanelib.tracking.proposers", "lanelib.tracking.update",
        "lanelib.tracking.start",
        "lanelib.tracking.tracker"}
EXTENSIONS = ("lanelib.autogeometry", "lanelib.roads", "lanelib.lines")
# the core modules that still call a hard-road or every-line part, and which: the search
# narrows a double line to its inner stripe (``SearchConfig.double_line_px``), the pipeline takes
# its proposers from ``roads.proposers`` (``DETECT``) and hands ``detect_lines`` to ``lines``
# (the lines view, its setup, the search and the ``LinesResult``), the tracker takes its
# hard-road proposers from ``roads.proposers`` (``TRACKER_FIRST``, ``TRACKER_LATER``) and
# measures the shoulder and the stripes' spread, its checks ask ``roads.checks`` (near gap, grade
# pair, restart from one line) and its update keeps the width seen at the car off a line joined
# over a bend's gap (``roads.checks``). Each hard-road part changes nothing while its switch is
# off. Nothing else of the core may reach them.
CORE_CALLS = {"lanelib.search": {"lanelib.roads"}, "lanelib.pipeline": {"lanelib.roads", "lanelib.lines"},
              "lanelib.tracking.tracker": {"lanelib.roads"}, "lanelib.tracking.judge": {"lanelib.roads"},
              "lanelib.tracking.update": {"lanelib.roads"}}


# the core stays small enough for a student to read (the issue "a thin core": about 5,000 lines)
CORE_MAX_LINES = 5100


def core_files(core=CORE, package: Path = PACKAGE) -> set[Path]:
    """Return the files of the core's modules (every file of a package module)."""
    files: set[Path] = set()
    for m in core:
        p = package.parent.joinpath(*m.split("."))
        files.update(p.rglob("*.py") if p.is_dir() else {p.with_suffix(".py")})
    return files


def test_the_core_stays_small():
    files = core_files()
    sizes = {f.relative_to(PACKAGE.parent): len(f.read_text(encoding="utf-8").splitlines()) for f in files}
    total = sum(sizes.values())
    largest = max(sizes, key=sizes.get)
    print(f"core: {total} lines in {len(files)} files (limit {CORE_MAX_LINES}); largest {largest} ({sizes[largest]})")
    assert all(f.is_file() for f in files), "a CORE module names no file"
    assert total <= CORE_MAX_LINES, (f"the core has {total} lines, over {CORE_MAX_LINES}: move a part into an "
                                     "extension (roads/, lines/, autogeometry/) or make it shorter")


@pytest.mark.parametrize("module", sorted(CORE))
def test_the_core_reaches_no_extension(module):
    """No core module imports an extension, directly or through another module, but for the
    calls ``CORE_CALLS`` names."""
    edges = graph()[0]
    seen, todo = set(), [module]
    while todo:
        m = todo.pop()
        for t in edges.get(m, ()):
            if any(t == e or t.startswith(e + ".") for e in CORE_CALLS.get(m, ())):
                continue
            if t not in seen:
                seen.add(t)
                todo.append(t)
    reached = sorted(t for t in seen if any(t == e or t.startswith(e + ".") for e in EXTENSIONS))
    assert not reached, f"{module} (core) imports the extension modules {reached}"
