"""Methods compared: each set of config overrides scored on each source against its truth.

``compare_methods`` runs every method on every source (folders of images detected one by one,
videos tracked) with the source's true camera, so the figures are the lane finding's alone;
``format_comparison`` prints them as one table with each method's change from a baseline.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

from .config import PipelineConfig, override
from .evaluate import EvalReport, calibration_from_truth, evaluate_images, evaluate_video_many, format_cell
from .pipeline import LanePipeline


@dataclass(frozen=True)
class MethodScore:
    """One method (a set of config overrides) scored on one source: its report, or why it was not run."""

    source: str
    method: str
    settings: tuple[str, ...]
    report: EvalReport | None
    skipped: str = ""


def applies(settings: Sequence[str], detector: str) -> bool:
    """Return False for settings that change nothing for ``detector``: only ``tracking.*`` keys,
    on single frames (a mix, such as a preset's, changes single frames by its other keys).

    Examples
    --------
    >>> applies(["tracking.hold_frames=3"], "frame"), applies(["tracking.hold_frames=3", "search.minpix=9"], "frame")
    (False, True)
    """
    return detector == "tracker" or not settings or not all(s.startswith("tracking.") for s in settings)


def compare_methods(methods: Mapping[str, Sequence[str]], sources: Sequence[str | os.PathLike],
                    config: PipelineConfig = PipelineConfig(),
                    max_frames: int | None = None, on_frame: Callable | None = None) -> list[MethodScore]:
    """Return every method scored on every source, each against the truth beside the source.

    Parameters
    ----------
    methods : method name -> its ``config.override`` settings (``"search.trim_outliers_pct=95"``);
        a method with no settings is ``config`` itself (the baseline to compare against).
    sources : folders of images (each detected on its own, ``evaluate_images``) and videos
        (tracked, ``evaluate_video``), each with its ground truth beside it.
    config : the config the settings change.
    max_frames : score only the first this many images or frames of each source.
    on_frame : ``on_frame(source, index, raw, {method: (pipeline, result)})`` is called on each
        frame of a video as it is scored, e.g. to draw chosen frames without tracking them again.

    Each source is scored with its true camera (``calibration_from_truth``), so the figures are
    the lane finding's alone. A method whose settings only touch the tracker is not run on images
    (its score says so). Bad settings raise ``ConfigError`` before anything runs.
    """
    configs = {name: override(config, settings) for name, settings in methods.items()}
    out = []
    for source in sources:
        path = Path(source)
        camera = calibration_from_truth(path)
        detector = "frame" if path.is_dir() else "tracker"
        run = [n for n, settings in methods.items() if applies(settings, detector)]
        pipes = [LanePipeline(configs[n], camera, size=camera.image_size) for n in run]
        if detector == "frame":
            reports = [evaluate_images(path, p, max_frames) for p in pipes]
        else:  # the clip decoded once, every method tracking it in step
            seen = None if on_frame is None else (
                lambda i, raw, results, path=path, run=run, pipes=pipes:
                on_frame(path, i, raw, dict(zip(run, zip(pipes, results)))))
            reports = evaluate_video_many(path, pipes, True, max_frames, seen)
        got = dict(zip(run, reports))
        for name, settings in methods.items():
            out.append(MethodScore(str(path), name, tuple(settings), got.get(name),
                                   "" if name in got else "tracker only"))
    return out


_COMPARED = (  # (column, summary key, format)
    ("found %", "found_rate", "pct"),
    ("points %", "point_accuracy", "pct"),
    ("FP %", "fp_rate", "pct"),
    ("FN %", "fn_rate", "pct"),
    ("offset cm", "offset_err_cm_median", "{:.1f}"),
    ("curv. 1/m", "curvature_err_median", "{:.1e}"),
)


def format_comparison(scores: Sequence[MethodScore], baseline: str | None = None) -> str:
    """Return ``compare_methods``' scores as one plain-text table, a block of rows per source.

    Columns: lane found, point accuracy, false-positive and false-negative lines (all %), the
    median |offset error| (cm) and |curvature error| (1/m), and ``Δ points``: the point accuracy
    minus that of ``baseline`` (default: the first method) on the same source, in points.
    """
    if not scores:
        return "(nothing compared)"
    baseline = baseline if baseline is not None else scores[0].method
    base = {s.source: s.report.summary() for s in scores if s.method == baseline and s.report}
    rows = []
    for s in scores:
        detector = s.report.detector if s.report else "frame"
        label = f"{Path(s.source).name} ({detector})"
        if s.report is None:
            rows.append([label, s.method] + ["-"] * len(_COMPARED) + [s.skipped])
            continue
        summary = s.report.summary()
        cells = [format_cell(summary[key], fmt) for _, key, fmt in _COMPARED]
        ref = base.get(s.source)
        delta = "" if s.method == baseline or ref is None else _delta(summary["point_accuracy"],
                                                                       ref["point_accuracy"])
        rows.append([label, s.method, *cells, delta])
    head = ["source", "method", *(c for c, _, _ in _COMPARED), "Δ points"]
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(len(head))]
    line = lambda r: "  ".join(  # noqa: E731
        (c.ljust(w) if i < 2 else c.rjust(w)) for i, (c, w) in enumerate(zip(r, widths))).rstrip()
    out = [line(head)]
    for i, r in enumerate(rows):
        if i and r[0] != rows[i - 1][0]:
            out.append("")
        out.append(line(r if i == 0 or r[0] != rows[i - 1][0] else [""] + r[1:]))
    return "\n".join(out)


def _delta(value: float, ref: float) -> str:
    """Return ``value - ref`` in percentage points, signed, one decimal ("-" if either is NaN)."""
    if not (math.isfinite(value) and math.isfinite(ref)):
        return "-"
    return f"{round(100.0 * (value - ref), 1) + 0.0:+.1f}"
