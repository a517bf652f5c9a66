"""The official metrics of the public lane benchmarks: TuSimple accuracy, FP and FN; CULane F1.

Written for lanelib from the benchmarks' own definitions; no third-party code is copied.

TuSimple (``evaluate/lane.py`` of github.com/TuSimple/tusimple-benchmark, ``LaneEval``):

- a lane is one x (px) per row of ``h_samples``; a negative x (the label files use -2) means the
  lane has no point on that row;
- a truth lane's hit distance is ``20 px / cos(angle)``, the angle fitted by least squares as
  x against y through the lane's points (x >= 0); 20 px with fewer than two points (``get_angle``);
- a predicted lane's accuracy on a truth lane is the share of ALL ``h_samples`` rows where
  ``|x_pred - x_truth| < threshold``, a missing point standing at x = -100 on both sides (so a row
  where neither has a point counts as hit) (``line_accuracy``);
- each truth lane takes its best accuracy over the predicted lanes (0 with none); it is matched
  at 0.85 or more, else a false negative; FP = predicted lanes - matched truth lanes (``bench``);
- an image whose ``run_time`` is over 200 ms, or with more than (truth lanes + 2) predicted
  lanes, scores accuracy 0, FP 0, FN 1;
- with more than 4 truth lanes the worst accuracy is dropped and one FN forgiven; accuracy and FN
  are divided by min(truth lanes, 4) (at least 1), FP by the predicted lanes (0 with none);
- the set's Accuracy, FP and FN are the sums over the predictions divided by the number of
  labelled images (``bench_one_submit``), which requires one prediction per labelled image.

The point matching is ``score_lines``, which ``lanelib.evaluate`` uses too for its own
synthetic truth (there only the rows with a truth point count: ``every_row=False``).

CULane (the ``evaluate`` tool of the SCNN / CULane authors, ``tools/lane_evaluation``:
``src/lane_compare.cpp``, ``src/spline.cpp``, ``src/counter.cpp``, ``src/evaluate.cpp``, as
shipped e.g. in cfzd/Ultra-Fast-Lane-Detection ``evaluation/culane``; run with ``-w 30 -t 0.5
-c 1640 -r 590``):

- a lane with more than 2 points is resampled by a natural cubic spline in x(t), y(t), ``t`` the
  chord length along the points, at 50 steps per segment plus the last point; a 2-point lane is
  drawn as it is (``splineInterpTimes``, ``get_lane_similarity``);
- each lane is drawn as a polyline 30 px thick (OpenCV ``line``, 8-connected, points rounded to
  whole pixels) on a 1640 x 590 canvas; the similarity of two lanes is the IoU of their pixels;
  a lane with fewer than 2 points has similarity 0;
- per image, truth and predicted lanes are paired by the Hungarian assignment of the largest
  total IoU (here ``scipy.optimize.linear_sum_assignment`` on 1 - IoU); a pair is a true
  positive when its IoU is strictly above 0.5; FP = predicted - TP, FN = truth - TP
  (``Counter::count_im_pair``);
- TP, FP and FN are summed over the list; precision = TP / (TP + FP), recall = TP / (TP + FN),
  F1 = 2PR / (P + R). The C++ tool prints -1 for a precision or recall with a zero denominator;
  here it is 0, as in the common Python ports (lanedet / CLRNet ``culane_metric.py``).

Where lanelib differs on purpose: consecutive repeated points of a CULane lane are dropped
before the spline (the C++ spline divides by their zero distance).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Sequence

import cv2
import numpy as np

# --------------------------------------------------------------------------- TuSimple constants

POINT_THRESHOLD_PX = 20.0    # TuSimple ``pixel_thresh``
MATCH_ACCURACY = 0.85        # TuSimple ``pt_thresh``: a truth line is matched at this accuracy
MAX_RUN_TIME_MS = 200.0      # an image predicted slower than this scores accuracy 0, FN 1
EXTRA_LANES_ALLOWED = 2      # more predicted lanes than truth lanes + this: accuracy 0, FN 1
SCORED_LANES = 4             # accuracy and FN are divided by at most this many truth lanes
MISSING_X = -100.0           # where TuSimple's line_accuracy puts a missing point

# --------------------------------------------------------------------------- CULane constants

CULANE_IMAGE_SIZE = (1640, 590)  # (width, height) px of the canvas the lanes are drawn on
CULANE_LANE_WIDTH_PX = 30        # thickness of the drawn lanes
CULANE_IOU = 0.5                 # a pair is a true positive when its IoU is above this
SPLINE_STEPS = 50                # spline samples per segment between two label points


# --------------------------------------------------------------------------- point accuracy

def line_threshold_px(gt_x: np.ndarray, rows: np.ndarray,
                      threshold_px: float = POINT_THRESHOLD_PX) -> float:
    """Return the horizontal hit distance (px) for a truth line: ``threshold_px / cos(slant)``.

    The slant is that of the least-squares straight line x = k*y + c through the line's points
    (TuSimple ``get_angle``); with fewer than two points the distance is ``threshold_px``.

    Parameters
    ----------
    gt_x : truth x (px) at ``rows``; NaN where the line has no point.
    rows : image rows (px).
    threshold_px : the hit distance across a vertical line (TuSimple: 20 px).
    """
    ok = np.isfinite(gt_x)
    if ok.sum() < 2:
        return float(threshold_px)
    slope = np.polyfit(np.asarray(rows, float)[ok], np.asarray(gt_x, float)[ok], 1)[0]
    return float(threshold_px / math.cos(math.atan(slope)))


def line_accuracy(pred_x: np.ndarray, gt_x: np.ndarray, threshold_px: float,
                  every_row: bool = False) -> float:
    """Return the share of a truth line's points hit by a predicted line (NaN if none is scored).

    Parameters
    ----------
    pred_x : predicted x (px) at the truth rows; NaN where the prediction has no point.
    gt_x : truth x (px) at the same rows; NaN where the line has no point.
    threshold_px : horizontal distance (px) below which a point is hit.
    every_row : False (lanelib's synthetic truth): only the rows with a truth point count, and a
        missing prediction never hits. True (TuSimple's ``line_accuracy``): every row counts, a
        missing point on either side standing at x = ``MISSING_X``, so a row where neither line
        has a point is a hit.
    """
    gt = np.asarray(gt_x, float)
    pred = np.asarray(pred_x, float)
    if every_row:
        gt = np.where(np.isfinite(gt), gt, MISSING_X)
        pred = np.where(np.isfinite(pred), pred, MISSING_X)
    scored = np.isfinite(gt)
    if not scored.any():
        return float("nan")
    with np.errstate(invalid="ignore"):
        hit = np.abs(pred[scored] - gt[scored]) < threshold_px
    return float(hit.sum() / scored.sum())


@dataclass(frozen=True)
class LineScores:
    """How one frame's predicted lines match its truth lines (TuSimple rules).

    ``accuracy`` holds one value per truth line (NaN where that line has no scored point);
    ``pred_lines`` and ``gt_lines`` count the predicted lines and the scored truth lines;
    ``fp_lines`` (predicted lines - matched truth lines) and ``fn_lines`` the unmatched ones.
    """

    accuracy: tuple[float, ...]
    pred_lines: int
    gt_lines: int
    fp_lines: int
    fn_lines: int


def score_lines(pred_xs: Sequence[np.ndarray], gt_xs: Sequence[np.ndarray], rows: np.ndarray,
                threshold_px: float = POINT_THRESHOLD_PX,
                match_accuracy: float = MATCH_ACCURACY, every_row: bool = False) -> LineScores:
    """Return the TuSimple accuracy of each truth line and the frame's FP and FN line counts.

    Parameters
    ----------
    pred_xs : one array per predicted line, its x (px) at ``rows`` (NaN where it has no point).
    gt_xs : one array per truth line, its x (px) at ``rows`` (NaN where it has no point).
    rows : the truth rows (px).
    threshold_px : hit distance across the line (px).
    match_accuracy : accuracy at which a predicted line matches a truth line.
    every_row : see ``line_accuracy``; with True every truth line is scored, even one without a
        point (TuSimple), with False such a line is left out (NaN accuracy, not counted).
    """
    accs = []
    matched = 0
    gt_lines = 0
    for gt in gt_xs:
        gt = np.asarray(gt, float)
        if not every_row and not np.isfinite(gt).any():
            accs.append(float("nan"))
            continue
        gt_lines += 1
        thr = line_threshold_px(gt, rows, threshold_px)
        best = max((line_accuracy(p, gt, thr, every_row) for p in pred_xs), default=0.0)
        accs.append(best)
        matched += best >= match_accuracy
    return LineScores(tuple(accs), len(pred_xs), gt_lines, len(pred_xs) - matched, gt_lines - matched)


# --------------------------------------------------------------------------- TuSimple

def tusimple_x(lane: Iterable[float]) -> np.ndarray:
    """Return a TuSimple lane's x values (px) with the no-point marker (any negative x) as NaN."""
    x = np.asarray(list(lane), np.float64)
    return np.where(x >= 0, x, np.nan)


@dataclass(frozen=True)
class TuSimpleImage:
    """One image's TuSimple figures: ``accuracy``, ``fp`` and ``fn`` (fractions, ``bench``)."""

    accuracy: float
    fp: float
    fn: float


def tusimple_image(pred_lanes: Sequence[Sequence[float]], gt_lanes: Sequence[Sequence[float]],
                   h_samples: Sequence[float], run_time_ms: float = 0.0) -> TuSimpleImage:
    """Return one image's official TuSimple accuracy, FP and FN (see the module docstring).

    Parameters
    ----------
    pred_lanes : predicted lanes, each one x (px) per ``h_samples`` row, negative = no point.
    gt_lanes : the labelled lanes, in the same layout.
    h_samples : the label's rows (px).
    run_time_ms : the prediction's time for this image (ms); over ``MAX_RUN_TIME_MS`` scores 0.

    Raises ValueError when a predicted lane has another length than ``h_samples`` (TuSimple's
    "Format of lanes error"); the readers in ``tusimple.py`` say which file and line.
    """
    for i, lane in enumerate(pred_lanes):
        if len(lane) != len(h_samples):
            raise ValueError(f"predicted lane {i + 1} has {len(lane)} x values for "
                             f"{len(h_samples)} h_samples")
    if run_time_ms > MAX_RUN_TIME_MS or len(pred_lanes) > len(gt_lanes) + EXTRA_LANES_ALLOWED:
        return TuSimpleImage(0.0, 0.0, 1.0)
    s = score_lines([tusimple_x(p) for p in pred_lanes], [tusimple_x(g) for g in gt_lanes],
                    np.asarray(h_samples, np.float64), every_row=True)
    total, fn = sum(s.accuracy), s.fn_lines
    if len(gt_lanes) > SCORED_LANES:
        total -= min(s.accuracy)
        fn = max(fn - 1, 0)
    per = max(min(len(gt_lanes), SCORED_LANES), 1)
    fp = s.fp_lines / len(pred_lanes) if pred_lanes else 0.0
    return TuSimpleImage(total / per, fp, fn / per)


@dataclass(frozen=True)
class TuSimpleScore:
    """The official TuSimple figures of a prediction set: ``Accuracy``, ``FP``, ``FN``, and the F1
    of the last two (``f1``).

    ``images`` is the number of labelled images the sums are divided by; ``per_image`` keeps each
    prediction's ``TuSimpleImage`` under its ``raw_file``.
    """

    images: int
    accuracy: float
    fp: float
    fn: float
    per_image: tuple[tuple[str, TuSimpleImage], ...] = ()

    @property
    def f1(self) -> float:
        """Return ``tusimple_f1`` of the FP and FN rates."""
        return tusimple_f1(self.fp, self.fn)

    def to_dict(self) -> dict:
        """Return the figures as JSON-able values, named as TuSimple's own output names them (and
        "F1")."""
        return {"benchmark": "tusimple", "images": self.images, "Accuracy": self.accuracy,
                "FP": self.fp, "FN": self.fn, "F1": self.f1}

    def table(self) -> str:
        """Return the figures as printable lines (accuracy and F1 in %, FP and FN as fractions)."""
        return (f"TuSimple, {self.images} images\n"
                f"Accuracy  {100.0 * self.accuracy:.2f} %\n"
                f"FP        {self.fp:.4f}\n"
                f"FN        {self.fn:.4f}\n"
                f"F1        {100.0 * self.f1:.2f} %")


def tusimple_f1(fp: float, fn: float) -> float:
    """Return the F1 of TuSimple's FP and FN rates: precision ``1 - fp`` and recall ``1 - fn``, as
    lane detection papers report it beside the official figures (0 when both are 0: every line
    false and every label missed). The official accuracy credits a label the points of any line
    near it, false or not; the F1 counts every false line and every missed one.

    Examples
    --------
    >>> round(tusimple_f1(0.1, 1 / 3), 4), tusimple_f1(1.0, 1.0)
    (0.766, 0.0)
    """
    precision, recall = 1.0 - float(fp), 1.0 - float(fn)
    return 0.0 if precision + recall <= 0 else 2.0 * precision * recall / (precision + recall)


def tusimple_score(images: Iterable[tuple[str, TuSimpleImage]], labelled: int) -> TuSimpleScore:
    """Return the set's TuSimple figures: each image's sums over ``labelled`` images.

    Parameters
    ----------
    images : ``(raw_file, TuSimpleImage)`` of each prediction.
    labelled : the number of labelled images (TuSimple divides by it, not by the predictions).
    """
    rows = tuple(images)
    n = max(labelled, 1)
    return TuSimpleScore(labelled, sum(r.accuracy for _, r in rows) / n,
                         sum(r.fp for _, r in rows) / n, sum(r.fn for _, r in rows) / n, rows)


# --------------------------------------------------------------------------- CULane

def interpolate_lane(points: np.ndarray, steps: int = SPLINE_STEPS) -> np.ndarray:
    """Return a CULane lane resampled as the official tool draws it, (n, 2) x, y (px).

    Two points are returned as they are; more points by a natural cubic spline in x(t) and y(t),
    ``t`` the chord length from the first point, ``steps`` samples per segment (the segment's
    start and ``steps - 1`` points inside it) and then the last point (``splineInterpTimes``).
    Consecutive repeated points are dropped first.

    Parameters
    ----------
    points : (n, 2) lane points x, y (px), in label order.
    steps : samples per segment (CULane: 50).
    """
    p = np.asarray(points, np.float64).reshape(-1, 2)
    if len(p) > 1:
        p = p[np.r_[True, np.any(np.diff(p, axis=0) != 0, axis=1)]]
    if len(p) <= 2:
        return p
    t = np.r_[0.0, np.cumsum(np.hypot(*np.diff(p, axis=0).T))]
    k = np.arange(steps) / steps
    return np.vstack([natural_cubic_spline(t, p, k), p[-1:]])


def natural_cubic_spline(t: np.ndarray, values: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Return the natural cubic spline through (t, values) sampled in every segment, (segments *
    len(fractions), dims): segment i at t[i] + fraction * (t[i+1] - t[i]), segment by segment.

    The spline is the C2 piecewise cubic with zero second derivative at both ends (the CULane
    tool's ``spline.cpp``); its second derivatives M solve the tridiagonal system
    h[i-1] M[i-1] + 2 (h[i-1] + h[i]) M[i] + h[i] M[i+1] = 6 (d[i] - d[i-1]), d the slopes
    (values[i+1] - values[i]) / h[i], M[0] = M[n-1] = 0.

    Parameters
    ----------
    t : (n,) strictly increasing knots, n >= 2.
    values : (n, dims) values at the knots.
    fractions : where each segment is sampled, in [0, 1).
    """
    y = np.asarray(values, np.float64).reshape(len(t), -1)
    h = np.diff(t)
    d = np.diff(y, axis=0) / h[:, None]
    n = len(t)
    m = np.zeros_like(y)
    if n > 2:
        a = np.diag(2.0 * (h[:-1] + h[1:])) + np.diag(h[1:-1], 1) + np.diag(h[1:-1], -1)
        m[1:-1] = np.linalg.solve(a, 6.0 * np.diff(d, axis=0))
    u = np.asarray(fractions, np.float64)[None, :, None]
    hh = h[:, None, None]
    y0, y1, m0, m1 = y[:-1, None], y[1:, None], m[:-1, None], m[1:, None]
    # the cubic of each segment in the fraction u of its length (Hermite form of the spline)
    out = ((1 - u) * y0 + u * y1
           + hh ** 2 / 6.0 * (((1 - u) ** 3 - (1 - u)) * m0 + (u ** 3 - u) * m1))
    return out.reshape(-1, y.shape[1])


def lane_mask(points: np.ndarray, image_size: tuple[int, int] = CULANE_IMAGE_SIZE,
              width_px: int = CULANE_LANE_WIDTH_PX) -> np.ndarray:
    """Return a lane drawn as CULane scores it: a (height, width) uint8 mask of 0 and 1.

    The lane (``interpolate_lane``) is drawn segment by segment with OpenCV's 8-connected
    ``line`` of thickness ``width_px``, its points rounded to whole pixels; a lane with fewer
    than 2 points draws nothing.

    Parameters
    ----------
    points : (n, 2) lane points x, y (px).
    image_size : (width, height) px of the canvas (CULane: 1640 x 590).
    width_px : thickness of the drawn lane (CULane: 30 px).
    """
    w, h = image_size
    mask = np.zeros((h, w), np.uint8)
    p = np.asarray(points, np.float64).reshape(-1, 2)
    if len(p) < 2:
        return mask
    q = np.rint(interpolate_lane(p)).astype(np.int64)
    for a, b in zip(q[:-1], q[1:]):
        cv2.line(mask, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), 1, int(width_px), cv2.LINE_8)
    return mask


def iou_matrix(gt_lanes: Sequence[np.ndarray], pred_lanes: Sequence[np.ndarray],
               image_size: tuple[int, int] = CULANE_IMAGE_SIZE,
               width_px: int = CULANE_LANE_WIDTH_PX) -> np.ndarray:
    """Return the (truth, predicted) IoU of every pair of drawn lanes (``lane_mask``).

    A lane with fewer than 2 points has IoU 0 with every lane (CULane ``get_lane_similarity``).
    """
    gts = [lane_mask(g, image_size, width_px) for g in gt_lanes]
    preds = [lane_mask(p, image_size, width_px) for p in pred_lanes]
    gt_sum = [int(m.sum()) for m in gts]
    pred_sum = [int(m.sum()) for m in preds]
    out = np.zeros((len(gts), len(preds)))
    for i, g in enumerate(gts):
        for j, p in enumerate(preds):
            if gt_sum[i] == 0 or pred_sum[j] == 0:
                continue
            inter = int(np.count_nonzero(g & p))
            out[i, j] = inter / (gt_sum[i] + pred_sum[j] - inter)
    return out


def matched_pair_indices(ious: np.ndarray, iou_threshold: float = CULANE_IOU) -> list[tuple[int, int]]:
    """Return the (truth, predicted) index pairs of one image that are true positives: the
    Hungarian pairs of the largest total IoU whose IoU is above the threshold.

    Parameters
    ----------
    ious : (truth lanes, predicted lanes) IoU (``iou_matrix``).
    iou_threshold : a pair counts when its IoU is strictly above this (CULane: 0.5).

    Examples
    --------
    >>> matched_pair_indices(np.array([[0.2, 0.8], [0.7, 0.6], [0.0, 0.1]]))
    [(0, 1), (1, 0)]
    """
    if ious.size == 0:
        return []
    # imported here, not at the top: scipy.optimize takes about 1 s to import and only the CULane
    # score needs it; every other command starts without it (tests/test_imports.py)
    from scipy.optimize import linear_sum_assignment
    rows, cols = linear_sum_assignment(1.0 - ious)
    return [(int(i), int(j)) for i, j in zip(rows, cols) if ious[i, j] > iou_threshold]


def matched_pairs(ious: np.ndarray, iou_threshold: float = CULANE_IOU) -> int:
    """Return the true positives of one image: how many ``matched_pair_indices`` there are.

    Parameters
    ----------
    ious : (truth lanes, predicted lanes) IoU (``iou_matrix``).
    iou_threshold : a pair counts when its IoU is strictly above this (CULane: 0.5).
    """
    return len(matched_pair_indices(ious, iou_threshold))


@dataclass(frozen=True)
class CULaneCounts:
    """CULane true positives, false positives and false negatives, and their precision, recall, F1."""

    tp: int = 0
    fp: int = 0
    fn: int = 0
    images: int = 0

    def __add__(self, other: "CULaneCounts") -> "CULaneCounts":
        return CULaneCounts(self.tp + other.tp, self.fp + other.fp, self.fn + other.fn,
                            self.images + other.images)

    @property
    def precision(self) -> float:
        """Return TP / (TP + FP) (0 with no prediction)."""
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else 0.0

    @property
    def recall(self) -> float:
        """Return TP / (TP + FN) (0 with no truth lane)."""
        return self.tp / (self.tp + self.fn) if self.tp + self.fn else 0.0

    @property
    def f1(self) -> float:
        """Return 2 P R / (P + R) (0 when both are 0)."""
        p, r = self.precision, self.recall
        return 2 * p * r / (p + r) if p + r else 0.0

    def to_dict(self) -> dict:
        """Return the counts and figures as JSON-able values."""
        return {"benchmark": "culane", "images": self.images, "TP": self.tp, "FP": self.fp,
                "FN": self.fn, "precision": self.precision, "recall": self.recall, "F1": self.f1}

    def table(self) -> str:
        """Return the counts and figures as printable lines (precision, recall, F1 in %)."""
        return (f"CULane, {self.images} images\n"
                f"TP {self.tp}  FP {self.fp}  FN {self.fn}\n"
                f"precision  {100.0 * self.precision:.2f} %\n"
                f"recall     {100.0 * self.recall:.2f} %\n"
                f"F1         {100.0 * self.f1:.2f} %")


def culane_image(gt_lanes: Sequence[np.ndarray], pred_lanes: Sequence[np.ndarray],
                 image_size: tuple[int, int] = CULANE_IMAGE_SIZE,
                 width_px: int = CULANE_LANE_WIDTH_PX,
                 iou_threshold: float = CULANE_IOU) -> CULaneCounts:
    """Return one image's CULane TP, FP and FN (``Counter::count_im_pair``).

    Parameters
    ----------
    gt_lanes : the labelled lanes, each (n, 2) x, y (px).
    pred_lanes : the predicted lanes, in the same layout.
    image_size : (width, height) px of the canvas (CULane: 1640 x 590).
    width_px : thickness of the drawn lanes (CULane: 30 px).
    iou_threshold : a matched pair counts when its IoU is above this (CULane: 0.5).
    """
    if not gt_lanes or not pred_lanes:
        tp = 0
    else:
        tp = matched_pairs(iou_matrix(gt_lanes, pred_lanes, image_size, width_px), iou_threshold)
    return CULaneCounts(tp, len(pred_lanes) - tp, len(gt_lanes) - tp, 1)
