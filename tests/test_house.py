"""The house's size limits, read from the source with ``ast``: no module over 600 lines, no class
over 300, no function over 80. The largest of each is printed (``pytest -s``) so a change that
grows one toward its limit shows."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "lanelib"
LIMITS = {"module": 600, "class": 300, "function": 80}


def sizes() -> dict[str, list[tuple[int, str]]]:
    """Return (lines, where) of every module, class and function of lanelib, largest first."""
    out: dict[str, list[tuple[int, str]]] = {kind: [] for kind in LIMITS}
    for path in sorted(PACKAGE.rglob("*.py")):
        source = path.read_text()
        name = str(path.relative_to(PACKAGE.parent))
        out["module"].append((source.count("\n"), name))
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ClassDef):
                out["class"].append((node.end_lineno - node.lineno + 1, f"{name}:{node.name}"))
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out["function"].append((node.end_lineno - node.lineno + 1, f"{name}:{node.name}"))
    return {kind: sorted(found, reverse=True) for kind, found in out.items()}


@pytest.mark.parametrize("kind", sorted(LIMITS))
def test_nothing_is_over_its_size_limit(kind):
    found = sizes()[kind]
    print(f"largest {kind}: {found[0][1]} ({found[0][0]} lines, limit {LIMITS[kind]})")
    over = [f"{where} ({n} lines)" for n, where in found if n > LIMITS[kind]]
    assert not over, f"over the {LIMITS[kind]}-line limit for a {kind}: " + ", ".join(over)


def test_the_size_reader_counts_a_known_module(tmp_path):
    """A known answer: this file's own test function spans 5 lines, as ``sizes`` counts them."""
    tree = ast.parse(Path(__file__).read_text())
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef)
              and n.name == "test_nothing_is_over_its_size_limit")
    assert fn.end_lineno - fn.lineno + 1 == 5
    assert any(where.endswith("tracking/tracker.py:LaneTracker") for _, where in sizes()["class"])
