"""The committed notebooks: executed top to bottom, and outputs that replay on any machine.

nbval (``make test``) replays every cell and compares what it prints. That only proves the outputs
on the machine that runs it; these checks catch, where a notebook is written, the kinds of output
that replay differently elsewhere: float noise whose last digits depend on the CPU's BLAS or SIMD
kernel (``7e-15`` on one machine, ``9e-16`` on the next), absolute paths, timings, and cells run
out of order. ``make test`` also replays the notebooks under other BLAS and OpenCV kernels and one
thread (the Makefile's ``portability`` target). A committed notebook also stays small: what it
embeds (figures, a video widget's bytes) is what a clone downloads.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
MAX_NOTEBOOK_BYTES = 1_500_000
# notebooks held to less: 07's video widget embeds its clip (VideoTuner.play(seconds=, width_px=))
MAX_BYTES = {"07_video.ipynb": 1_000_000}

# a number in scientific notation below 1e-9: float noise, not a figure
FLOAT_NOISE = re.compile(r"\d(?:\.\d+)?e-(?:0*(?:[1-9]\d+))\b", re.IGNORECASE)
# machine-specific text: absolute paths, timings, memory addresses
MACHINE_SPECIFIC = [
    (re.compile(r"(?<![\w.])/(?:home|root|tmp|work|Users|usr|opt|var)/"), "an absolute path"),
    (re.compile(r"[A-Za-z]:\\\\"), "a Windows path"),
    (re.compile(r"\b\d+(?:\.\d+)?\s?(?:ms|µs|us)\b(?! ?per)"), "a timing"),
    (re.compile(r"\b0x[0-9a-f]{6,}\b"), "a memory address"),
]


def _printed(cell) -> str:
    """Return the text a code cell printed (streams and plain-text results)."""
    parts = []
    for out in cell.get("outputs", []):
        if out["output_type"] == "stream":
            parts.append("".join(out["text"]))
        elif "data" in out:
            parts.append("".join(out["data"].get("text/plain", "")))
    return "".join(parts)


def _code_cells(path: Path):
    return [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 9, NOTEBOOKS


def test_float_noise_pattern_catches_noise_and_spares_figures():
    assert FLOAT_NOISE.search("largest relative difference: 7e-15")
    assert FLOAT_NOISE.search("residual 1.23e-10 px")
    for fine in ("curvature 7.5e-05 1/m", "k1 -3.0e-05", "2.5e-4", "1e-9"):
        assert not FLOAT_NOISE.search(fine), fine


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_the_committed_notebook_is_small(path):
    limit = MAX_BYTES.get(path.name, MAX_NOTEBOOK_BYTES)
    size = path.stat().st_size
    assert size <= limit, (f"{path.name} is {size:,} bytes, over its {limit:,}: show smaller figures "
                           "(JPEG, lower dpi) or a shorter, smaller clip, then re-execute it")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_executed_top_to_bottom_in_one_kernel(path):
    counts = [c.get("execution_count") for c in _code_cells(path) if "".join(c["source"]).strip()]
    assert counts == list(range(1, len(counts) + 1)), (
        f"{path.name}: execution counts {counts}; re-execute it top to bottom (README, 'nbval')")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_no_errors_and_no_machine_specific_output(path):
    problems = []
    for i, cell in enumerate(_code_cells(path)):
        if any(o["output_type"] == "error" for o in cell.get("outputs", [])):
            problems.append(f"code cell {i}: an error output")
        text = _printed(cell)
        source = "".join(cell["source"])
        if "NBVAL_IGNORE_OUTPUT" in source:
            continue
        for m in FLOAT_NOISE.finditer(text):
            if "below" not in text[max(0, m.start() - 8):m.start()]:
                problems.append(f"code cell {i}: float noise {m.group()!r} (print what it means, "
                                "e.g. 'below 1e-12')")
        for pattern, what in MACHINE_SPECIFIC:
            for m in pattern.finditer(text):
                problems.append(f"code cell {i}: {what} {m.group()!r}")
    assert not problems, f"{path.name}:\n" + "\n".join(problems)
