"""Scoring a lane pipeline against ground truth: measurement errors, TuSimple point accuracy, FP/FN.

The ground truth comes from lanelib's synthetic data (``lanelib.synth.truth``): per image or video
frame the signed curvature (1/m) and radius at the car, the lateral offset (m), the lane width, and
each ego line's x in the RAW (distorted) image at fixed rows (TuSimple-style ``h_samples``).

Measurements (offset, curvature, radius) are scored on the frames where the lane was found.
The radius error is scored only on curves, frames whose true radius is at most
``RADIUS_SCORED_MAX_M`` (the generator's curves are 150 m to 3 km): on a straighter road a 23 m
view cannot tell 5 km from 50 km, the relative error of the radius means nothing there, and the
curvature error covers those frames.

Point accuracy and the false-positive and false-negative line rates follow the TuSimple lane
benchmark (``evaluate/lane.py`` of TuSimple/tusimple-benchmark): each fitted bird's-eye line is
mapped to the raw image (``pipeline.birdseye_to_raw``: the perspective's inverse, then the
camera's lens) and its x is compared
with the truth's x at each truth row. A truth point is hit when the horizontal distance is below
``POINT_THRESHOLD_PX / cos(angle)``, where ``angle`` is the truth line's slant from vertical
(fitted straight through its points), i.e. within about 20 px measured across the line. A truth
line's accuracy is its share of hit points, taken against the best-matching predicted line; a
frame's accuracy is the mean over its truth lines and the report's the mean over frames. A truth
line whose best accuracy is below ``MATCH_ACCURACY`` (0.85) is a false negative; a predicted line
that matches no truth line is a false positive; the rates are FP / predicted lines and
FN / truth lines per frame, averaged over the frames.

One difference from TuSimple, made because the pipeline only ever looks at its bird's-eye view:
only the truth points that fall inside that view are scored (TuSimple scores every annotated
point, up to the horizon). A truth line with no point inside the view is not a truth line for
that frame; a line found there is a false positive. For the same reason a truth line's accuracy
is the share of ITS points hit, where TuSimple's counts every row, a row where neither line has a
point as a hit. The matching itself is the one ``lanelib.benchmarks.metrics.score_lines`` that
the official TuSimple score uses (``every_row=False`` here, True there); the names
``line_threshold_px``, ``line_accuracy``, ``score_lines`` and ``LineScores`` are imported from it.

What the errors include: the truth gives the offset and the curvature AT THE CAR, while the
pipeline (``fit.measure``) takes the offset on the bird's-eye view's bottom row, about 4.8 m
ahead of the camera, and the curvature of a parabola fitted over the whole view (4.8 m to 28 m
ahead). A heading of 0.01 rad therefore adds about 4.8 cm to the offset error, and in a clothoid
transition the fit reports the mean curvature of the road ahead rather than that at the car.
These are errors of the pipeline's reading of the lane and are scored as such.
"""
from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from tqdm import tqdm

from . import cluster

from .benchmarks.metrics import (  # noqa: F401  (the point matching is shared; see above)
    MATCH_ACCURACY, POINT_THRESHOLD_PX, LineScores, line_accuracy, line_threshold_px, score_lines)
from .camera import Calibration
from .errors import DecodeStoppedError, InputError, LaneLibError, naming_the_file
from .io import VideoReader, list_images, read_image
from .synth.truth import load_image_truth, load_video_truth
from .tracking import LaneTracker

RADIUS_SCORED_MAX_M = 3000.0  # radius error is scored on frames with a true radius up to this
SUMMARY_KEYS = ("frames", "found_rate", "offset_err_cm_median", "offset_err_cm_p95",
                "curvature_err_median", "radius_err_pct_median", "point_accuracy", "fp_rate",
                "fn_rate", "files_failed")


# --------------------------------------------------------------------------- raw-image mapping

def fit_x_in_raw(coeffs_px, pipeline, rows: np.ndarray) -> np.ndarray:
    """Return the x (px) in the RAW image of a bird's-eye fit at raw ``rows`` (NaN where it ends).

    The fit ``x = a*y**2 + b*y + c`` is sampled over the bird's-eye rows, mapped to the raw
    image by the pipeline's bird's-eye -> raw transform (``pipeline.birdseye_to_raw``: the
    perspective's inverse, then the lens; no distortion without a calibration), then read at
    ``rows``. Points where the lens model folds back (``camera.Lens.valid``) are left out.

    Parameters
    ----------
    coeffs_px : (a, b, c) of the fit in bird's-eye pixels.
    pipeline : the ``LanePipeline`` that made the fit.
    rows : raw-image rows (px).
    """
    h = pipeline.size[1]
    # a little beyond the view: distortion moves rows near the view's edge by a pixel or two
    yb = np.linspace(-0.05 * h, 1.05 * h, 2 * h)
    xb = np.polyval(coeffs_px, yb)
    raw, keep = pipeline.birdseye_to_raw.checked(np.column_stack([xb, yb]))
    if keep.sum() < 2:
        return np.full(len(rows), np.nan)
    raw = raw[keep]
    order = np.argsort(raw[:, 1])
    return np.interp(np.asarray(rows, float), raw[order, 1], raw[order, 0], left=np.nan, right=np.nan)


def in_view(pipeline, xs: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Return which raw-image points (x, row in px; NaN x = none) fall inside the bird's-eye view."""
    xs = np.asarray(xs, float)
    rows = np.asarray(rows, float)
    out = np.zeros(len(xs), bool)
    ok = np.isfinite(xs)
    if not ok.any():
        return out
    bird = pipeline.raw_to_birdseye(np.column_stack([xs[ok], rows[ok]]))
    w, h = pipeline.size
    out[ok] = (bird[:, 0] >= 0) & (bird[:, 0] <= w - 1) & (bird[:, 1] >= 0) & (bird[:, 1] <= h - 1)
    return out


def truth_calibration(camera) -> Calibration:
    """Return the ``Calibration`` of the true camera recorded in a ground truth (``CameraTruth``).

    The same as ``camera.calibration()``, which new code calls.
    """
    return camera.calibration()


def truth_x(xs) -> np.ndarray:
    """Return truth x positions (px) with the not-visible marker (negative, -2) as NaN."""
    x = np.asarray(xs, np.float64)
    return np.where(x >= 0, x, np.nan)


def score_frame(pipeline, result, lane) -> LineScores:
    """Return the TuSimple line scores of one pipeline result against one frame's ``LaneTruth``.

    Only the truth points inside the pipeline's bird's-eye view are scored (see the module
    docstring); the found lines of ``result`` are mapped to the raw image by ``fit_x_in_raw``.
    """
    rows = np.asarray(lane.h_samples_px, np.float64)
    gts = []
    for xs in (lane.left_x_px, lane.right_x_px):
        gt = truth_x(xs)
        gt[~in_view(pipeline, gt, rows)] = np.nan
        gts.append(gt)
    preds = [fit_x_in_raw(fit.coeffs_px, pipeline, rows) for fit in (result.left, result.right) if fit.found]
    return score_lines(preds, gts, rows)


# --------------------------------------------------------------------------- the report

def _nan_stat(values: np.ndarray, fn) -> float:
    """Return ``fn`` of the finite values (NaN when there are none)."""
    v = np.asarray(values, np.float64)
    v = v[np.isfinite(v)]
    return float(fn(v)) if v.size else float("nan")


@dataclass(frozen=True)
class EvalReport:
    """Per-frame errors of a pipeline against ground truth, and their summary.

    Arrays have one entry per frame (image or video frame, in order); measurement arrays are NaN
    where the pipeline found no lane. ``line_accuracy`` is (frames, 2): the left and right truth
    lines' TuSimple accuracy, NaN where that line had no point in view. ``truth`` keeps each
    frame's ``LaneTruth`` (heading, lane width, line positions) for plots against the scene.

    Parameters
    ----------
    source : what was evaluated (folder or video path).
    detector : ``"frame"`` (each frame on its own) or ``"tracker"`` (``LaneTracker``).
    names : the image file names, or the frame numbers as text.
    failed : ``(file name, error)`` of each image that could not be scored (unreadable image,
        missing or corrupt truth, another size than the truth's camera); left out of every figure.
    joints : a video scored with the tracker on Dask: how its segments were joined (re-runs of
        joints that did not settle in the warm-up, ``cluster.settle_joints``); None otherwise.
    """

    source: str
    detector: str
    names: tuple[str, ...]
    found: np.ndarray
    offset_true_m: np.ndarray
    offset_pred_m: np.ndarray
    curvature_true_per_m: np.ndarray
    curvature_pred_per_m: np.ndarray
    radius_true_m: np.ndarray
    radius_pred_m: np.ndarray
    lane_width_true_m: np.ndarray
    lane_width_pred_m: np.ndarray
    line_accuracy: np.ndarray
    pred_lines: np.ndarray
    gt_lines: np.ndarray
    fp_lines: np.ndarray
    fn_lines: np.ndarray
    truth: tuple = field(default=(), repr=False)
    failed: tuple[tuple[str, str], ...] = ()
    joints: cluster.Joints | None = None  # on Dask with the tracker: how the segments were joined

    @property
    def frames(self) -> int:
        """Return the number of frames scored."""
        return len(self.names)

    @property
    def offset_err_cm(self) -> np.ndarray:
        """Return |offset error| per frame (cm; NaN where no lane was found)."""
        return np.abs(self.offset_pred_m - self.offset_true_m) * 100.0

    @property
    def curvature_err_per_m(self) -> np.ndarray:
        """Return |curvature error| per frame (1/m; NaN where no lane was found)."""
        return np.abs(self.curvature_pred_per_m - self.curvature_true_per_m)

    @property
    def radius_err_pct(self) -> np.ndarray:
        """Return |radius error| / true radius per frame (%; NaN off curves and where not found).

        Scored where the true radius is at most ``RADIUS_SCORED_MAX_M`` (see the module docstring).
        """
        curve = self.radius_true_m <= RADIUS_SCORED_MAX_M
        with np.errstate(invalid="ignore", divide="ignore"):
            err = np.abs(self.radius_pred_m - self.radius_true_m) / self.radius_true_m * 100.0
        return np.where(curve, err, np.nan)

    @property
    def frame_point_accuracy(self) -> np.ndarray:
        """Return each frame's point accuracy: mean over its truth lines (NaN with none in view)."""
        acc = self.line_accuracy
        n = np.isfinite(acc).sum(axis=1)
        total = np.where(np.isfinite(acc), acc, 0.0).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 0, total / np.maximum(n, 1), np.nan)

    def summary(self) -> dict:
        """Return the summary figures under ``SUMMARY_KEYS`` (NaN where nothing was scored)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            fp = np.where(self.pred_lines > 0, self.fp_lines / np.maximum(self.pred_lines, 1), 0.0)
            fn = np.where(self.gt_lines > 0, self.fn_lines / np.maximum(self.gt_lines, 1), 0.0)
        n = self.frames
        return {
            "frames": n,
            "found_rate": float(np.mean(self.found)) if n else float("nan"),
            "offset_err_cm_median": _nan_stat(self.offset_err_cm, np.median),
            "offset_err_cm_p95": _nan_stat(self.offset_err_cm, lambda v: np.percentile(v, 95)),
            "curvature_err_median": _nan_stat(self.curvature_err_per_m, np.median),
            "radius_err_pct_median": _nan_stat(self.radius_err_pct, np.median),
            "point_accuracy": _nan_stat(self.frame_point_accuracy, np.mean),
            "fp_rate": float(np.mean(fp)) if n else float("nan"),
            "fn_rate": float(np.mean(fn)) if n else float("nan"),
            "files_failed": len(self.failed),
        }

    def to_dict(self) -> dict:
        """Return the summary as JSON-able values (NaN as None) under ``SUMMARY_KEYS``."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in self.summary().items()}

    def table(self) -> str:
        """Return the summary as a printable table (one column: this report)."""
        return format_table([self])

    @property
    def radius_frames(self) -> int:
        """Return the number of frames on which the radius error is scored."""
        return int(np.isfinite(self.radius_err_pct).sum())


_ROWS = (  # (label, summary key, format of a value)
    ("frames", "frames", "{:d}"),
    ("lane found (%)", "found_rate", "pct"),
    ("|offset error| median (cm)", "offset_err_cm_median", "{:.1f}"),
    ("|offset error| p95 (cm)", "offset_err_cm_p95", "{:.1f}"),
    ("|curvature error| median (1/m)", "curvature_err_median", "{:.1e}"),
    ("radius error median (%)", "radius_err_pct_median", "{:.1f}"),
    ("point accuracy (%)", "point_accuracy", "pct"),
    ("false-positive lines (%)", "fp_rate", "pct"),
    ("false-negative lines (%)", "fn_rate", "pct"),
)


def format_cell(value, fmt: str) -> str:
    """Return one printed cell of a table: the value formatted, or "-" where it is missing or NaN."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if fmt == "pct":
        return f"{100.0 * value:.1f}"
    return fmt.format(value)


def format_table(reports: Sequence[EvalReport], titles: Sequence[str] | None = None) -> str:
    """Return the summaries of ``reports`` side by side as a plain-text table.

    Parameters
    ----------
    reports : one column each.
    titles : column titles; default the source's name and the detector.
    """
    titles = list(titles) if titles is not None else [
        f"{Path(r.source).name} ({r.detector})" for r in reports]
    sums = [r.summary() for r in reports]
    cols = [[format_cell(s[key], fmt) for _, key, fmt in _ROWS] for s in sums]
    label_w = max(len(label) for label, _, _ in _ROWS)
    widths = [max(len(t), *(len(c) for c in col)) for t, col in zip(titles, cols)]
    lines = [" " * label_w + "".join(f"  {t:>{w}}" for t, w in zip(titles, widths))]
    for i, (label, _, _) in enumerate(_ROWS):
        lines.append(f"{label:<{label_w}}" + "".join(f"  {col[i]:>{w}}" for col, w in zip(cols, widths)))
    notes = [f"radius error on {r.radius_frames} frame(s) with a true radius <= "
             f"{RADIUS_SCORED_MAX_M:.0f} m" for r in reports]
    if len(set(notes)) == 1:
        lines.append(notes[0])
    else:
        lines += [f"{t}: {n}" for t, n in zip(titles, notes)]
    for t, r in zip(titles, reports):
        if r.failed:
            lines.append((f"{t}: " if len(reports) > 1 else "")
                         + f"{len(r.failed)} of {r.frames + len(r.failed)} files failed and are left "
                           "out of the scores")
    return "\n".join(lines)


# --------------------------------------------------------------------------- runs

class _Collector:
    """Gathers per-frame values into an EvalReport."""

    def __init__(self, pipeline, source: str, detector: str):
        self.pipeline = pipeline
        self.source = source
        self.detector = detector
        self.rows: list[tuple] = []

    def add(self, name: str, result, lane) -> None:
        self.rows.append(_score_row(self.pipeline, name, result, lane))

    def report(self, failed: Sequence[tuple[str, str]] = ()) -> EvalReport:
        cols = list(zip(*self.rows)) if self.rows else [()] * 16
        f = lambda i: np.asarray(cols[i], np.float64)  # noqa: E731
        i_ = lambda i: np.asarray(cols[i], np.int64)  # noqa: E731
        acc = np.asarray(cols[10], np.float64).reshape(-1, 2)
        return EvalReport(self.source, self.detector, tuple(cols[0]), np.asarray(cols[1], bool),
                          f(2), f(3), f(4), f(5), f(6), f(7), f(8), f(9), acc,
                          i_(11), i_(12), i_(13), i_(14), tuple(cols[15]), tuple(failed))


def _score_row(pipeline, name: str, result, lane) -> tuple:
    """Return one frame's row of an ``EvalReport`` (what ``_Collector`` gathers)."""
    s = score_frame(pipeline, result, lane)
    m = result.measurement
    return (name, bool(result.found), lane.offset_m, m.offset_m, lane.curvature_per_m,
            m.curvature_per_m, lane.radius_m, m.radius_m, lane.lane_width_m, m.lane_width_m,
            s.accuracy, s.pred_lines, s.gt_lines, s.fp_lines, s.fn_lines, lane)


def score_images(chunk: Sequence[Path], pipeline) -> list[tuple[tuple | None, tuple[str, str] | None]]:
    """Return ``(row, None)`` for each image of ``chunk`` scored, ``(None, (name, error))`` for
    each that could not be (a task of ``evaluate_images`` on Dask, and its loop in one process)."""
    out = []
    w, h = pipeline.size
    for f in chunk:
        try:
            lane = load_image_truth(f).lane
            rgb = read_image(f)
            if rgb.shape[:2] != (h, w):
                raise InputError(f"{f}: is {rgb.shape[1]}x{rgb.shape[0]} but the ground truth's camera "
                                 f"is {w}x{h}; score images rendered by that camera (regenerate them "
                                 "with `python -m lanelib synth images`)")
            result = pipeline.detect(rgb)
        except LaneLibError as e:
            out.append((None, (f.name, naming_the_file(str(e), f, f.with_suffix(".json")))))
            continue
        out.append((_score_row(pipeline, f.name, result, lane), None))
    return out


def evaluate_images(folder: str | os.PathLike, pipeline, max_frames: int | None = None,
                    workers: int = 1, scheduler: str | None = None, progress: bool = True) -> EvalReport:
    """Return the per-image evaluation of ``pipeline`` on a folder of images with truth beside them.

    Each image is detected on its own (``LanePipeline.detect``) and scored against the JSON truth
    beside it (``lanelib.synth.truth.load_image_truth``). An image that cannot be scored (not
    readable, its truth missing or corrupt, another size than ``pipeline.size``) goes to the
    report's ``failed`` with a one-line error naming the file, is left out of every figure, and
    the run goes on.

    Parameters
    ----------
    folder : folder of images, each ``NAME.jpg`` with ``NAME.json`` beside it.
    pipeline : the ``LanePipeline`` to score (its calibration is used to map lines to the raw image).
    max_frames : score only the first this many images (by name).
    workers, scheduler : score the images in chunks on Dask workers (``cluster.dask_client``,
        ``cluster.map_items``; the pipeline is sent as its config, calibration and size), with a
        progress bar unless ``progress`` is false; the report is that of one process.

    Raises
    ------
    InputError
        If the folder does not exist or holds no images, or no Dask scheduler answers.

    Examples
    --------
    >>> from lanelib import data
    >>> from lanelib.pipeline import LanePipeline
    >>> folder = data.bundled("test_images")
    >>> camera = calibration_from_truth(folder)
    >>> report = evaluate_images(folder, LanePipeline(calibration=camera, size=camera.image_size))
    >>> summary = report.summary()
    >>> summary["frames"], summary["found_rate"], summary["point_accuracy"]
    (8, 1.0, 1.0)
    """
    files = list_images(folder)[:max_frames]
    on_dask = workers != 1 or scheduler is not None  # a bar only there, as before
    scored = cluster.run_items(score_images, files, workers, scheduler, "evaluate", "image",
                               progress and on_dask, pipeline=pipeline)
    col = _Collector(pipeline, str(folder), "frame")
    col.rows = [row for row, _ in scored if row is not None]
    return col.report([fail for _, fail in scored if fail is not None])


def evaluate_video(path: str | os.PathLike, pipeline, use_tracker: bool = True,
                   max_frames: int | None = None, workers: int = 1, scheduler: str | None = None,
                   progress: bool = True) -> EvalReport:
    """Return the per-frame evaluation of ``pipeline`` on a video with its per-frame truth.

    Parameters
    ----------
    path : the video; its truth ``NAME.csv`` and ``NAME.json`` lie beside it.
    pipeline : the ``LanePipeline`` to score.
    use_tracker : track the lane through the frames (``LaneTracker``); False detects every frame
        on its own (``LanePipeline.detect``).
    max_frames : score only the first this many frames.
    workers, scheduler : score the clip in segments on Dask workers (``cluster.dask_client``,
        ``cluster.segments``; with the tracker each segment starts ``cluster.WARMUP_FRAMES`` early
        and drops those frames, and a segment whose tracker did not come to the previous one's
        state in that warm-up is scored again from that state: ``cluster.settle_joints``), so the
        rows are those of one run, with a progress bar unless ``progress`` is false.

    Raises
    ------
    InputError
        If the video or its truth is missing or unreadable, the video stops decoding before the
        frames to score (a truncated file), or it holds more frames than its truth.
    """
    with cluster.dask_client(workers, scheduler) as client:
        if client is None:
            return evaluate_video_many(path, [pipeline], use_tracker, max_frames)[0]
        truth = load_video_truth(path)
        frames = range(len(truth.frames[:max_frames]))
        warmup = cluster.WARMUP_FRAMES if use_tracker else 0
        spans = cluster.segments(frames, cluster.segment_count(len(frames), cluster.total_threads(client),
                                                               max(1, warmup)), warmup)
        # the last segment reads on to the clip's end (unless --max-frames): a clip longer than
        # its truth is refused, as in one process
        segs = [(first, start, stop, max_frames is None and stop == frames.stop)
                for first, start, stop in spans]
        with tqdm(total=len(frames), desc="evaluate", unit="frame", disable=not progress,
                  dynamic_ncols=True) as bar:
            # the tracker's state checked at each joint (cluster.settle_joints): the rows of one process
            done, joints = cluster.map_segments(client, score_video_segment, segs, bar, lambda o: o[1],
                                                lambda o: isinstance(o[0], str), path=Path(path),
                                                pipeline=pipeline, use_tracker=use_tracker,
                                                max_frames=max_frames)
    col = _Collector(pipeline, str(path), "tracker" if use_tracker else "frame")
    for rows, _ in done:
        if isinstance(rows, str):  # the first segment that failed says why, as one process would
            raise InputError(rows)
        col.rows += rows
    if len(col.rows) < len(frames):
        raise InputError(f"{path}: the video has {len(col.rows)} frames but its truth "
                         f"{Path(path).with_suffix('.csv')} has {len(truth.frames)}; "
                         "regenerate both with `python -m lanelib synth --all`")
    return replace(col.report(), joints=joints if use_tracker else None)


def score_video_segment(chunk: Sequence[tuple[int, int, int, bool]], path: Path, pipeline,
                        use_tracker: bool, max_frames: int | None, state: LaneTracker | None = None
                        ) -> list[tuple[list[tuple] | str, cluster.Carry]]:
    """Return the score rows of each segment ``(first, start, stop, to_end)`` of a video (a Dask
    task of ``evaluate_video``) and its tracker's state at its ends (``cluster.Carry``): run from
    ``first`` (a fresh tracker, or a copy of the tracker ``state``: a re-run from the previous
    segment's state), rows kept from ``start``; a segment that cannot be scored (the clip breaks
    off, more frames than truth) gives the error's message instead of rows (the client raises
    the first one in the clip's order)."""
    truth = load_video_truth(path).frames
    out: list[tuple[list[tuple] | str, cluster.Carry]] = []
    for first, start, stop, to_end in chunk:
        tracked = None
        if use_tracker:
            tracked = copy.deepcopy(state) if state is not None else LaneTracker(pipeline)
        rows: list[tuple] = []
        try:
            entry = _score_segment(path, pipeline, tracked, truth, first, start,
                                   None if to_end else stop, rows)
        except DecodeStoppedError as e:
            out.append((f"{e}; only {e.frames + first} of the {len(truth[:max_frames])} frames to "
                        "score could be read: pass a complete video, or --max-frames up to that",
                        cluster.Carry()))
        except InputError as e:
            out.append((str(e), cluster.Carry()))
        else:
            end = tracked.state_key() if tracked is not None else None
            out.append((rows, cluster.Carry(entry, end, tracked)))
    return out


def _score_segment(path: Path, pipeline, tracker, truth, first: int, start: int, stop: int | None,
                   rows: list) -> bytes | None:
    """Append the score rows of frames ``start ..`` to ``rows``, run from frame ``first``; return
    the tracker's ``state_key`` before frame ``start`` (None without a tracker)."""
    entry = None
    with VideoReader(path, first, stop) as reader:
        for n, raw in enumerate(reader):
            i = first + n
            if i >= len(truth):
                raise InputError(f"{path}: the video has more frames than its truth "
                                 f"{Path(path).with_suffix('.csv')} ({len(truth)}); "
                                 "regenerate the truth with `python -m lanelib synth --all`")
            if i == start and tracker is not None:
                entry = tracker.state_key()
            result = tracker.update(raw, index=i) if tracker is not None else pipeline.detect(raw)
            if i >= start:
                rows.append(_score_row(pipeline, str(i), result, truth[i]))
    return entry


def evaluate_video_many(path: str | os.PathLike, pipelines: Sequence, use_tracker: bool = True,
                        max_frames: int | None = None, on_frame: Callable | None = None) -> list[EvalReport]:
    """Return ``evaluate_video`` of each pipeline on one video, decoding it once for all.

    Each pipeline runs on its own (its own ``LaneTracker``) over the same frames, in step; the
    reports are those ``evaluate_video`` gives one by one (``compare.compare_methods`` uses this).
    ``on_frame(index, raw, results)``, when given, sees each frame and the pipelines' results in
    their order (e.g. to draw chosen frames while they are scored, without a second run).
    """
    truth = load_video_truth(path)
    frames = truth.frames[:max_frames]
    runners = [(p, LaneTracker(p) if use_tracker else None,
                _Collector(p, str(path), "tracker" if use_tracker else "frame")) for p in pipelines]
    n = 0
    with VideoReader(path) as reader:
        try:
            for i, raw in enumerate(reader):
                if i >= len(frames):
                    if max_frames is None or i < max_frames:
                        raise InputError(f"{path}: the video has more frames than its truth "
                                         f"{Path(path).with_suffix('.csv')} ({len(truth.frames)}); "
                                         "regenerate the truth with `python -m lanelib synth --all`")
                    break
                results = []
                for pipeline, tracker, col in runners:
                    result = tracker.update(raw, index=i) if tracker is not None else pipeline.detect(raw)
                    col.add(str(i), result, frames[i])
                    results.append(result)
                if on_frame is not None:
                    on_frame(i, raw, results)
                n += 1
                if max_frames is not None and i + 1 >= max_frames:
                    break  # not one frame more: the video may end (or break off) right here
        except DecodeStoppedError as e:
            raise InputError(f"{e}; only {e.frames} of the {len(frames)} frames to score could be "
                             "read: pass a complete video, or --max-frames up to that") from None
    if n < len(frames):
        raise InputError(f"{path}: the video has {n} frames but its truth "
                         f"{Path(path).with_suffix('.csv')} has {len(truth.frames)}; "
                         "regenerate both with `python -m lanelib synth --all`")
    return [col.report() for _, _, col in runners]


def calibration_from_truth(path: str | os.PathLike) -> Calibration:
    """Return the true camera recorded in the ground truth of a folder of images or of a video.

    For a folder, the first truth (by image name) that can be read; for a video, its JSON.

    Raises
    ------
    InputError
        If the path does not exist, or no truth beside it can be read (the message is the first
        image's error).
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file or folder; check the path")
    if not p.is_dir():
        return load_video_truth(p).camera.calibration()
    first_error = None
    for image in list_images(p):
        try:
            return load_image_truth(image).camera.calibration()
        except InputError as e:
            first_error = first_error or e
    raise first_error
