"""Why, frame by frame: what became of each labelled line of a benchmark frame, and of each line
reported where none is labelled.

``explain_frame`` runs ``LanePipeline.detect_lines`` on one labelled frame as ``predict`` does
(the frame on its own, every line seen sampled at the label rows by ``batch.seen_lines``, the lines the
benchmark labels, ``benchmarks.written``; TuSimple at the official 1280x720, ``tusimple.full_size``),
matches the predicted lines to the labels by the benchmark's official rule
(``metrics.iou_matrix`` and ``metrics.matched_pair_indices`` for CULane, ``metrics.line_accuracy``
for TuSimple) and gives each label line one class (``classify``):

- **found**: a predicted line matches it;
- **reported but off**: a predicted line that matches no other label lies on it (a mean |dx| over
  the label's rows below ``NEAR_PX``, scaled to the frame's width) but fails the match: it stops
  short of the label's extent, or runs beside it;
- **refused**: no reported line lies on it, but a line the vote weighed and refused does
  (``lines.vote.vote_candidates``; or a line seen but not written, beyond the lines the
  benchmark labels, ``benchmarks.written``): the refusal's reason;
- **missed**: nothing near it. The label mapped into the lines view says where it was lost
  (``paint_share``): no paint in the mask along it (the mask lost it), a mask as busy beside it as
  along it (texture, no line stands out), or paint along it and no candidate (the vote lost it).

Each predicted line that matches no label is a **false line**, off a label line (the line of a
"reported but off" label) or where no line is labelled. ``draw_why`` draws it all on the frame;
``explain_set`` counts the classes and the reasons, by kind (``reason_kind``), over a dev set
(``python -m lanelib why culane|tusimple [FRAME ...]``).
"""
from __future__ import annotations

import dataclasses
import functools
import os
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Callable, Iterable, Sequence

import numpy as np

from .. import batch, data, io
from ..batch.refine import PointsRefinement, sequence_refinement, shifted_points
from ..config import PipelineConfig
from ..errors import InputError
from ..pipeline import LanePipeline
from . import WRITTEN, culane, metrics, tusimple

FOUND, OFF, REFUSED, MISSED, FALSE = "found", "reported but off", "refused", "missed", "false line"
CLASSES = (FOUND, OFF, REFUSED, MISSED, FALSE)
BENCHMARKS = ("culane", "tusimple")
NEAR_PX = 30.0           # a line lies on a label when its mean |dx| over the label's rows is below
NEAR_AT_WIDTH_PX = 1640  # this many px at this frame width (scaled to the frame's width)
SHORT_SHARE = 0.7        # a reported line over less than this share of its label's rows stops short
NO_PAINT = 0.1           # paint along less than this share of a label's rows in view is "no paint"
BUSIER_BY = 0.15         # a label's line stands out where its share of rows with paint is this much
BESIDE_M = 1.5           # above the share this far beside it, on either side (between two lines)
PAINT_TOLERANCE_M = 0.3  # paint within this distance across the road of the label lies on it
NOT_WRITTEN = "seen but not written: the benchmark labels {which}"


# --------------------------------------------------------------------------- records

@dataclass(frozen=True)
class LineWhy:
    """What became of one label line (``label`` its index, left to right as labelled) or of one
    false line (``label`` None, ``prediction`` its index): its class (``CLASSES``), the reason,
    and the matched or nearest predicted line's index (None without)."""

    category: str
    reason: str
    label: int | None = None
    prediction: int | None = None

    def text(self) -> str:
        """Return one line of text: which line, its class and the reason."""
        which = f"label {self.label + 1}" if self.label is not None else f"line {self.prediction + 1}"
        return f"{which}: {self.category}" + (f" - {self.reason}" if self.reason else "")


@dataclass(frozen=True)
class FrameWhy:
    """One frame explained: its labels and predicted lines in frame pixels, the refused lines,
    what became of each line (``lines``: the labels in order, then the false lines), and the
    lines view's mask with the labels mapped into it (``mask``, ``view_labels``; None when not
    kept).

    ``labels`` are (n, 2) x, y points; ``predictions`` and each refused line are x at ``rows_px``
    (NaN where the line is not seen), as ``predict`` writes them.
    """

    benchmark: str
    name: str
    size: tuple[int, int]
    rows_px: np.ndarray = field(repr=False)
    labels: tuple[np.ndarray, ...] = field(repr=False)
    predictions: tuple[np.ndarray, ...] = field(repr=False)
    refused: tuple[tuple[np.ndarray, str], ...] = field(repr=False)
    lines: tuple[LineWhy, ...] = ()
    mask: np.ndarray | None = field(default=None, repr=False)
    view_labels: tuple[np.ndarray, ...] = field(default=(), repr=False)

    def of(self, category: str) -> tuple[LineWhy, ...]:
        """Return the lines of one class."""
        return tuple(w for w in self.lines if w.category == category)

    def summary(self) -> list[str]:
        """Return one text line per label line and per false line."""
        return [w.text() for w in self.lines]


def reason_kind(reason: str) -> str:
    """Return a reason's kind: its figures replaced by N and its parenthesised details dropped,
    so that reasons of one kind read alike.

    Examples
    --------
    >>> reason_kind("its paint spans 3.9 m along the road, less than min_span_m 6.0 m")
    'its paint spans N m along the road, less than min_span_m N m'
    >>> reason_kind("no candidate near it, though the mask has paint along it (paint along 60 %)")
    'no candidate near it, though the mask has paint along it'
    """
    return re.sub(r"\d+(?:\.\d+)?", "N", re.sub(r"\s*\([^)]*\)", "", reason))


# --------------------------------------------------------------------------- classification

def _x_along(xs: np.ndarray, rows_px: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Return a line given as x at ``rows_px`` interpolated at rows ``ys`` (NaN off its span)."""
    ok = np.isfinite(xs)
    if ok.sum() < 2:
        return np.full(len(ys), np.nan)
    order = np.argsort(rows_px[ok])
    return np.interp(ys, rows_px[ok][order], xs[ok][order], left=np.nan, right=np.nan)


def nearness(label: np.ndarray, xs: np.ndarray, rows_px: np.ndarray) -> tuple[float, float]:
    """Return the mean |dx| (px) of a line (x at ``rows_px``) from a label's points over the label
    rows where both are, and the share of the label's points it covers (inf, 0 with fewer than 2).

    Examples
    --------
    >>> label = np.array([[100.0, 500], [110, 490], [120, 480], [130, 470]])
    >>> nearness(label, np.array([104.0, 114.0, np.nan]), np.array([500.0, 490.0, 480.0]))
    (4.0, 0.5)
    """
    at = _x_along(np.asarray(xs, float), np.asarray(rows_px, float), label[:, 1])
    ok = np.isfinite(at)
    if ok.sum() < 2:
        return float("inf"), 0.0
    return float(np.mean(np.abs(at[ok] - label[ok, 0]))), float(ok.mean())


def written_points(xs: np.ndarray, rows_px: np.ndarray) -> np.ndarray:
    """Return a line given as x at ``rows_px`` as ``predict`` writes it for CULane: (x, y) points
    where it is seen, x to 0.01 px.

    Examples
    --------
    >>> written_points(np.array([1.234, np.nan]), np.array([580.0, 570.0])).tolist()
    [[1.23, 580.0]]
    """
    ok = np.isfinite(xs)
    return np.column_stack([np.round(xs[ok], 2), rows_px[ok]])


def _at_rows(label: np.ndarray, rows_px: np.ndarray) -> np.ndarray:
    """Return a TuSimple label's x at each of ``rows_px`` (NaN where it has no point)."""
    out = np.full(len(rows_px), np.nan)
    index = {float(y): float(x) for x, y in label}
    for k, y in enumerate(rows_px):
        out[k] = index.get(float(y), np.nan)
    return out


def match(benchmark: str, labels: Sequence[np.ndarray], predictions: Sequence[np.ndarray],
          rows_px: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, dict[int, int]]:
    """Return the (label, prediction) scores by the official rule and the matched pairs
    {label: prediction}.

    CULane: the IoU of the 30 px lines (``metrics.iou_matrix``) and the Hungarian pairs above 0.5
    (``metrics.matched_pair_indices``) on a canvas of ``size``. TuSimple: each prediction's
    accuracy on each label (``metrics.line_accuracy`` over every row, the label's threshold
    ``metrics.line_threshold_px``); a label matches its best prediction at
    ``metrics.MATCH_ACCURACY`` or more.
    """
    scores = np.zeros((len(labels), len(predictions)))
    if not len(labels) or not len(predictions):
        return scores, {}
    if benchmark == "culane":
        scores = metrics.iou_matrix(list(labels), [written_points(p, rows_px) for p in predictions], size)
        return scores, dict(metrics.matched_pair_indices(scores))
    pairs = {}
    for i, label in enumerate(labels):
        gt = _at_rows(label, rows_px)
        threshold = metrics.line_threshold_px(gt, rows_px)
        scores[i] = [metrics.line_accuracy(p, gt, threshold, every_row=True) for p in predictions]
        if scores[i].max() >= metrics.MATCH_ACCURACY:
            pairs[i] = int(np.argmax(scores[i]))
    return scores, pairs


def _score_text(benchmark: str, score: float) -> str:
    if benchmark == "culane":
        return f"IoU {score:.2f}, needs above {metrics.CULANE_IOU}"
    return f"accuracy {score:.2f}, needs {metrics.MATCH_ACCURACY}"


def _nearest(label: np.ndarray, lines: Sequence[np.ndarray], rows_px: np.ndarray, near_px: float,
             allowed: Iterable[int]) -> tuple[int, float, float] | None:
    """Return (index, mean |dx|, share covered) of the nearest allowed line within ``near_px``."""
    best = None
    for j in allowed:
        dx, share = nearness(label, lines[j], rows_px)
        if dx < near_px and (best is None or dx < best[1]):
            best = (j, dx, share)
    return best


def _missed_reason(paint: tuple[float, float] | None) -> str:
    if paint is None:
        return "no candidate near it: it lies outside the lines view"
    along, beside = paint
    if along < NO_PAINT:
        return "no candidate near it: no paint in the mask along it"
    shares = f"paint along {100 * along:.0f} % of it, {100 * beside:.0f} % beside it"
    if along < beside + BUSIER_BY:
        return f"no candidate near it: the mask is as busy beside it ({shares})"
    return f"no candidate near it, though the mask has paint along it ({shares})"


def classify(benchmark: str, labels: Sequence[np.ndarray], predictions: Sequence[np.ndarray],
             refused: Sequence[tuple[np.ndarray, str]], rows_px: Sequence[float],
             size: tuple[int, int], paint: Sequence[tuple[float, float] | None] | None = None) -> tuple[LineWhy, ...]:
    """Return what became of each label line, in order, then of each false line.

    Parameters
    ----------
    benchmark : "culane" or "tusimple": the official rule that matches lines (``match``).
    labels : the label lines, each (n, 2) x, y points (px).
    predictions : the predicted lines, each x (px) at ``rows_px``, NaN where not seen.
    refused : (line, reason) of each line weighed and refused, the line as a prediction.
    rows_px : the rows the lines are given at (TuSimple: the label's ``h_samples``).
    size : (width, height) px of the frame; ``NEAR_PX`` is scaled to its width.
    paint : per label, the share of its rows in the lines view with paint in the mask along it
        and ``BESIDE_M`` beside it (``paint_share``; None: outside the view), for the reason of a
        missed line; without it a missed line just has no candidate near it.

    Examples
    --------
    A label matched exactly, one with a refused line on it, one with nothing near it, and a
    predicted line where none is labelled:

    >>> rows = np.arange(580.0, 300.0, -10.0)
    >>> labels = [np.column_stack([x + 0.5 * (rows - 580), rows]) for x in (300.0, 800.0, 1300.0)]
    >>> found, false = labels[0][:, 0], np.full(len(rows), 1000.0)
    >>> refused = [(labels[1][:, 0] + 5, "its paint spans 3.9 m along the road")]
    >>> for w in classify("culane", labels, [found, false], refused, rows, (1640, 590)):
    ...     print(w.text())
    label 1: found - IoU 1.00, needs above 0.5
    label 2: refused - its paint spans 3.9 m along the road
    label 3: missed - no candidate near it
    line 2: false line - no label near it
    """
    rows = np.asarray(rows_px, np.float64)
    near_px = NEAR_PX * size[0] / NEAR_AT_WIDTH_PX
    scores, pairs = match(benchmark, labels, predictions, rows, size)
    matched = set(pairs.values())
    out, off_of = [], {}
    for i, label in enumerate(labels):
        if i in pairs:
            out.append(LineWhy(FOUND, _score_text(benchmark, scores[i, pairs[i]]), i, pairs[i]))
            continue
        free = [j for j in range(len(predictions)) if j not in matched]
        near = _nearest(label, predictions, rows, near_px, free)
        if near is not None:
            j, dx, share = near
            how = (f"it stops short: reported over {100 * share:.0f} % of the label's rows"
                   if share < SHORT_SHARE else f"it runs {dx:.0f} px beside it")
            off_of.setdefault(j, i)
            out.append(LineWhy(OFF, f"{how}; {_score_text(benchmark, scores[i, j])}", i, j))
            continue
        near = _nearest(label, [line for line, _ in refused], rows, near_px, range(len(refused)))
        if near is not None:
            out.append(LineWhy(REFUSED, refused[near[0]][1], i))
            continue
        out.append(LineWhy(MISSED, _missed_reason(paint[i]) if paint is not None
                           else "no candidate near it", i))
    for j in range(len(predictions)):
        if j not in matched:
            why = f"off label {off_of[j] + 1}" if j in off_of else "no label near it"
            out.append(LineWhy(FALSE, why, None, j))
    return tuple(out)


# --------------------------------------------------------------------------- one frame

def view_points(pipeline: LanePipeline, points: np.ndarray) -> np.ndarray:
    """Return a line's raw-frame points (n, 2) mapped into the lines view where the map is valid
    and the point falls inside the view (the view of ``pipeline.lines_view``)."""
    view = pipeline.lines_view()[0]
    p, ok = (pipeline.lens.inverse + view).checked(np.asarray(points, np.float64).reshape(-1, 2))
    w, h = view.size
    ok &= (p[:, 0] >= 0) & (p[:, 0] <= w - 1) & (p[:, 1] >= 0) & (p[:, 1] <= h - 1)
    return p[ok]


def paint_share(mask: np.ndarray, line: np.ndarray, tolerance_px: float) -> float | None:
    """Return the share of the view rows of a line in the view (points (n, 2)) that have paint in
    the 0/255 ``mask`` within ``tolerance_px`` across; None for a line with fewer than 2 points.

    Examples
    --------
    >>> m = np.zeros((100, 50), np.uint8); m[60:100, 20:23] = 255
    >>> paint_share(m, np.array([[25.0, 0.0], [25.0, 99.0]]), 4)
    0.4
    """
    if len(line) < 2:
        return None
    order = np.argsort(line[:, 1])
    ys = np.arange(int(np.ceil(line[order[0], 1])), int(np.floor(line[order[-1], 1])) + 1)
    if not len(ys):
        return None
    xs = np.rint(np.interp(ys, line[order, 1], line[order, 0])).astype(int)
    tol = int(np.ceil(tolerance_px))
    hits = sum(bool(mask[y, max(0, x - tol):max(0, x + tol + 1)].any()) for x, y in zip(xs, ys))
    return hits / len(ys)


def _paint(mask: np.ndarray, line: np.ndarray, xm_per_px: float) -> tuple[float, float] | None:
    """Return the share of a view line's rows with paint along it, and the mean share ``BESIDE_M``
    beside it on either side (None outside the view)."""
    tol = PAINT_TOLERANCE_M / xm_per_px
    along = paint_share(mask, line, tol)
    if along is None:
        return None
    side = [paint_share(mask, line + [d * BESIDE_M / xm_per_px, 0.0], tol) for d in (-1, 1)]
    return along, float(np.mean([s for s in side if s is not None] or [0.0]))


def label_lines(benchmark: str, labels) -> tuple[list[np.ndarray], np.ndarray]:
    """Return the label lines as (n, 2) points and the rows predictions are given at."""
    if benchmark == "tusimple":
        if not isinstance(labels, tusimple.TuSimpleRecord):
            raise InputError("explain_frame tusimple: pass the frame's labels as a TuSimpleRecord "
                             "(tusimple.read_labels) at the official 1280x720 rows")
        rows = np.asarray(labels.h_samples, np.float64)
        lines = []
        for lane in labels.lanes:
            x = metrics.tusimple_x(lane)
            lines.append(np.column_stack([x[np.isfinite(x)], rows[np.isfinite(x)]]))
        return [p for p in lines if len(p)], rows
    return [np.asarray(p, np.float64).reshape(-1, 2) for p in labels], np.asarray(culane.SAMPLE_ROWS_PX, float)


def _written(found, rows: np.ndarray, w: int, benchmark: str) -> tuple[list, list]:
    """Return the lines ``predict`` writes (x at rows) and the lines seen but not written, with why."""
    written = batch.seen_lines(found, rows, w, benchmark)
    dropped = []
    for line in found.lines:
        xs = batch.seen_lines(dataclasses.replace(found, lines=(line,)), rows, w)
        if xs and not any(np.array_equal(xs[0], p, equal_nan=True) for p in written):
            dropped.append((xs[0], NOT_WRITTEN.format(which=WRITTEN.get(benchmark, ""))))
    return written, dropped


def explain_frame(benchmark: str, image, labels, config: PipelineConfig | None = None, *,
                  name: str = "", pipeline: LanePipeline | None = None, keep_mask: bool = True) -> FrameWhy:
    """Return what became of each labelled line of one frame (``classify``), as ``predict`` runs it.

    Parameters
    ----------
    benchmark : "culane" or "tusimple".
    image : the frame (a path, or an RGB array). A TuSimple frame stored smaller than 1280x720 is
        upscaled to it first (``tusimple.full_size``), as the scoreboard does.
    labels : CULane: the frame's lines, each (n, 2) x, y (``culane.read_lines``); TuSimple: its
        ``TuSimpleRecord`` at the official 1280x720 rows.
    config : the pipeline's config (default: ``batch.benchmark_config(benchmark)``).
    name : what the frame is called in the record (default: the path).
    pipeline : a pipeline for this frame's size and ``config`` to reuse (it keeps its maps).
    keep_mask : keep the lines view's mask and the labels mapped into it (for ``draw_why``).

    Examples
    --------
    >>> rows = np.arange(580.0, 200.0, -10.0)
    >>> road = np.full((590, 1640, 3), 70, np.uint8)
    >>> why = explain_frame("culane", road, [np.column_stack([600 + 0.6 * (rows - 580), rows])])
    >>> why.summary()
    ['label 1: missed - no candidate near it: no paint in the mask along it']
    """
    if benchmark not in BENCHMARKS:
        raise InputError(f"{benchmark!r}: not a benchmark; choose one of {', '.join(BENCHMARKS)}")
    config = batch.benchmark_config(benchmark) if config is None else config
    rgb = read_frame(benchmark, image)
    size = (rgb.shape[1], rgb.shape[0])
    points, rows = label_lines(benchmark, labels)
    pipe = pipeline if pipeline is not None else LanePipeline(config, None, size=size)
    found = pipe.detect_lines(rgb, ego=False, keep_images=True)
    written, dropped = _written(found, rows, size[0], benchmark)
    refused = [(xs, why) for xs, why in dropped]
    for line, why in found.refused:
        xs = line.x_at_rows(rows)
        xs[~((xs >= 0) & (xs <= size[0] - 1))] = np.nan
        refused.append((xs, why))
    view = pipe.lines_view()[0]
    mask = found.images["lines_binary"]
    in_view = [view_points(pipe, p) for p in points]
    paint = [_paint(mask, v, view.xm_per_px) for v in in_view]
    lines = classify(benchmark, points, written, refused, rows, size, paint)
    return FrameWhy(benchmark, name or str(image if not isinstance(image, np.ndarray) else ""), size, rows,
                    tuple(points), tuple(written), tuple(refused), lines,
                    mask if keep_mask else None, tuple(in_view) if keep_mask else ())


# --------------------------------------------------------------------------- a set of frames

@dataclass(frozen=True)
class SetWhy:
    """A set of frames explained (``explain_set``): each frame's ``FrameWhy`` without its mask."""

    benchmark: str
    source: str
    frames: tuple[FrameWhy, ...]

    def counts(self) -> dict[str, tuple[int, int]]:
        """Return {class: (lines, frames with such a line)} for every class of ``CLASSES``."""
        return {c: (sum(len(f.of(c)) for f in self.frames), sum(1 for f in self.frames if f.of(c)))
                for c in CLASSES}

    def reasons(self, category: str) -> list[tuple[str, int, int]]:
        """Return the reason kinds (``reason_kind``) of one class's lines with their line and
        frame counts, most lines first."""
        lines: Counter = Counter()
        frames: Counter = Counter()
        for f in self.frames:
            kinds = [reason_kind(w.reason) for w in f.of(category)]
            lines.update(kinds)
            frames.update(set(kinds))
        return [(k, n, frames[k]) for k, n in sorted(lines.items(), key=lambda kv: (-kv[1], kv[0]))]

    def frames_of(self, category: str) -> tuple[str, ...]:
        """Return the names of the frames with at least one line of this class."""
        return tuple(f.name for f in self.frames if f.of(category))

    def to_dict(self) -> dict:
        """Return the counts, the reasons by kind and the frames of each class as JSON-able values."""
        return {"benchmark": self.benchmark, "source": self.source, "frames": len(self.frames),
                "classes": {c: {"lines": n, "frames": fr, "frame_names": list(self.frames_of(c)),
                                "reasons": [{"kind": k, "lines": m, "frames": f} for k, m, f in self.reasons(c)]}
                            for c, (n, fr) in self.counts().items()}}

    def table(self) -> str:
        """Return the class counts and, under each class but "found", its reasons by kind."""
        labels = sum(len(f.labels) for f in self.frames)
        predicted = sum(len(f.predictions) for f in self.frames)
        rows = []
        for c, (n, frames) in self.counts().items():
            rows.append((c, n, frames))
            if c != FOUND:
                rows += [(f"  {k}", m, fr) for k, m, fr in self.reasons(c)]
        w = max(len(r[0]) for r in rows)
        out = [f"{self.benchmark} ({self.source}): {len(self.frames)} frames, {labels} label lines, "
               f"{predicted} predicted lines",
               f"{'class / reason':<{w}s} {'lines':>5s} {'frames':>6s}"]
        out += [f"{name:<{w}s} {n:5d} {frames:6d}" for name, n, frames in rows]
        return "\n".join(out)


def set_frames(benchmark: str, root: str | os.PathLike,
               list_file: str | os.PathLike | None = None) -> list[tuple[str, Path, object]]:
    """Return (name, image, labels) of every labelled frame of a dataset, in list order.

    CULane: the images of ``list_file`` (default: ``culane.default_list``: ``list/test.txt``, else
    the dev set's ``list.txt``) and their ``.lines.txt``. TuSimple: the records of ``list_file``
    (default: ``data.TUSIMPLE_DEV_FULLRES`` when ``root`` holds it, else the root's label files,
    ``tusimple.label_files``). A missing image raises ``InputError`` naming it.
    """
    r = Path(root)
    if benchmark == "culane":
        listed = Path(list_file) if list_file else culane.default_list(r)
        labels = culane.read_labels(r, listed)
        named = list(zip(labels.entries, labels.lanes))
    elif benchmark == "tusimple":
        source = Path(list_file) if list_file else (
            r / data.TUSIMPLE_DEV_FULLRES if (r / data.TUSIMPLE_DEV_FULLRES).is_file() else r)
        named = [(rec.raw_file, rec) for rec in tusimple.read_labels(source)]
    else:
        raise InputError(f"{benchmark!r}: not a benchmark; choose one of {', '.join(BENCHMARKS)}")
    out = []
    for name, labels in named:
        image = r.joinpath(*PurePosixPath(name.lstrip("/")).parts)
        if not image.is_file():
            raise InputError(f"{image}: the labelled frame {name} is missing; pass the dataset root "
                             "the labels are relative to")
        out.append((name, image, labels))
    return out


def read_frame(benchmark: str, image) -> np.ndarray:
    """Return a labelled frame (a path, or an RGB array) as ``predict`` sees it: RGB, a TuSimple
    frame at the official 1280x720 (``tusimple.full_size``, as the scoreboard upscales it)."""
    rgb = image if isinstance(image, np.ndarray) else io.read_image(image)
    return tusimple.full_size(rgb) if benchmark == "tusimple" else rgb


def refined_configs(benchmark: str, images: Iterable[tuple[str, Path]], config: PipelineConfig,
                    on_points: Callable[[PointsRefinement], None] | None = None) -> dict[str, PipelineConfig]:
    """Return the config of each sequence (``batch.frame_sequence``) of ``images`` ((name, path)
    pairs) whose bird's-eye points ``predict`` moves: ``config`` with its points moved to where
    the sequence's lines meet (``lines.refine_points_px``, ``batch.refine.sequence_refinement``
    on the frames as ``read_frame`` reads them). Each sequence's ``PointsRefinement`` goes to
    ``on_points``. Empty when the refinement is off."""
    if config.lines.refine_points_px <= 0:
        return {}
    by_sequence: dict[str, list[Path]] = {}
    for name, image in images:
        by_sequence.setdefault(batch.frame_sequence(benchmark, name), []).append(Path(image))
    out = {}
    for sequence, paths in by_sequence.items():
        found = sequence_refinement(paths, config, None, sequence, functools.partial(read_frame, benchmark))
        if on_points is not None:
            on_points(found)
        if found.moved:
            out[sequence] = shifted_points(config, found.shift_px)
    return out


def explain_set(benchmark: str, root: str | os.PathLike | None = None, config: PipelineConfig | None = None,
                list_file: str | os.PathLike | None = None,
                on_frame: Callable[[FrameWhy], None] | None = None,
                on_points: Callable[[PointsRefinement], None] | None = None) -> SetWhy:
    """Return every labelled frame of a dataset explained (``explain_frame``), in list order,
    each sequence through the points ``predict`` gives it (``refined_configs``).

    Parameters
    ----------
    benchmark : "culane" or "tusimple".
    root : the dataset root (default: the dev set, ``data.culane_dev`` or ``data.tusimple_dev``;
        ``InputError`` saying how to point at it when absent).
    config : the pipeline's config (default: ``batch.benchmark_config(benchmark)``).
    list_file : the frames (``set_frames``).
    on_frame : called with each frame's record as it is done (a progress line).
    on_points : called with each sequence's ``PointsRefinement`` before its frames are explained.
    """
    if root is None:
        root = data.require(data.CULANE_DEV if benchmark == "culane" else data.TUSIMPLE_DEV)
    config = batch.benchmark_config(benchmark) if config is None else config
    named = set_frames(benchmark, root, list_file)
    configs = refined_configs(benchmark, ((name, image) for name, image, _ in named), config, on_points)
    pipelines: dict = {}
    frames = []
    for name, image, labels in named:
        rgb = read_frame(benchmark, image)
        sequence = batch.frame_sequence(benchmark, name)
        own = configs.get(sequence, config)
        key = (rgb.shape[1], rgb.shape[0], sequence if sequence in configs else None)
        if key not in pipelines:
            pipelines[key] = LanePipeline(own, None, size=key[:2])
        frame = explain_frame(benchmark, rgb, labels, own, name=name, pipeline=pipelines[key],
                              keep_mask=False)
        if on_frame is not None:
            on_frame(frame)
        frames.append(frame)
    return SetWhy(benchmark, str(root), tuple(frames))
