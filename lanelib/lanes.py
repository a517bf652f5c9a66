"""Lane-pixel search, polynomial fits, curvature, offset, lane width and the plausibility checks.

A lane is found only when both lines pass ``LaneChecks`` (``check_lane``: ``line_problem`` of each
line, ``pair_problem`` of the two), in a single image (``LanePipeline.detect``) as in a video
(``LaneTracker``); a ``result.FrameResult`` that failed them says why in ``reason`` and keeps the
fits and what they measured apart in ``rejected``, with NaN measurements: no lane rather than a
confident wrong one.

Coordinates are bird's-eye pixels, x to the right and y down; each line is fitted as
``x = a*y**2 + b*y + c``. Metric fits come from the pixel fits by exact scaling of the
coefficients (no refit): with ``x_m = xm*x`` and ``y_m = ym*y``,
``x_m = (xm/ym**2)*a*y_m**2 + (xm/ym)*b*y_m + xm*c``.

Sign conventions (the synthetic ground truth uses the same):
- curvature (1/m) is positive when the road bends to the RIGHT as the car drives ahead;
  the radius is ``1/|curvature|``, capped at ``RADIUS_MAX_M`` (a straight road);
- the vehicle offset (m) is positive when the car is RIGHT of the lane centre.
  The car is where the bottom-centre pixel of the undistorted frame lands in the bird's-eye view.
Curvature, offset and width are read on the bird's-eye view's bottom row, the nearest road the
camera sees (4.8 m ahead with the default points), as the Udacity convention has it; the fits are
not extrapolated to the car itself. Where the car is not parallel to the lane, the offset there
differs from the offset below the camera by heading x 4.8 m (about 5 cm per 0.01 rad); the
synthetic ground truth is given at the car, so ``evaluate`` counts that term as error.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from .params.roads import EdgeConfig, LinesConfig
from .params.stages import LaneChecks, SearchConfig

RADIUS_MAX_M = 100_000.0
NEAR_SHARE = 0.02  # share of a line's pixels nearest the car left out of where it reaches (LineFit.gap_px)


@dataclass(frozen=True)
class LineFit:
    """One fitted line: pixel coefficients (a, b, c) of x = f(y), or not found with a reason.

    ``scatter_px`` is the RMS horizontal distance (px) of the line's pixels from the fit (0 for a
    line not fitted to pixels, e.g. a tracked one). ``stripe_scatter_px`` is their RMS distance
    from the nearer of two parallel stripes fitted to them (``two_stripes``), measured by the
    search (``sliding_windows``, ``search_around``) where the pixels scatter like a double line
    (``scatter_px`` above a quarter of ``SearchConfig.double_line_px``) but are not narrowed to
    its inner stripe, and split into two stripes of at least a fifth of them each; None where
    not measured (one stripe: the texture rule reads ``scatter_px``). ``gap_px`` is how far
    (rows) the line's pixels stop short of the view's bottom row, the car's end: from the bottom
    row to the row that all but ``NEAR_SHARE`` of its pixels lie above (0 for a line that
    reaches the car, or was not fitted to pixels). A few stray pixels near the car do not count
    as reaching it.
    """

    coeffs_px: tuple[float, float, float] | None
    n_pixels: int = 0
    span_px: float = 0.0
    reason: str = ""
    scatter_px: float = 0.0
    gap_px: float = 0.0
    stripe_scatter_px: float | None = None

    @property
    def found(self) -> bool:
        return self.coeffs_px is not None

    def x_at(self, y) -> np.ndarray:
        """Return x (px) of the line at rows ``y`` (px); raises if the line was not found."""
        if self.coeffs_px is None:
            raise ValueError(f"line not found: {self.reason}")
        if isinstance(y, np.ndarray) and y.ndim and (y.dtype.kind in "iu" or y.dtype == np.float64):
            return _poly(self.coeffs_px, y)  # np.polyval's values, without its array of zeros
        return np.polyval(self.coeffs_px, y)


@dataclass(frozen=True)
class Window:
    """One sliding window: which line, its x range and y range (px)."""

    side: str
    x_low: int
    x_high: int
    y_low: int
    y_high: int


@dataclass(frozen=True)
class LaneSearch:
    """The pixels found for each line, how they were found, and the fits."""

    left: LineFit
    right: LineFit
    method: str  # "windows" or "prior"
    left_pixels: tuple[np.ndarray, np.ndarray] = field(repr=False)  # (ys, xs)
    right_pixels: tuple[np.ndarray, np.ndarray] = field(repr=False)
    windows: tuple[Window, ...] = ()
    bases_px: tuple[float | None, float | None] = (None, None)
    # (peak - mean) / mean of the histogram at each base (``base_peak_confidence``); None where
    # the bases were given or not found
    base_confidence: tuple[float | None, float | None] = (None, None)
    # the look-ahead: the first row (px) of the view the search read (0: the whole view)
    top_px: int = 0
    # (left, right): the line is the unpainted asphalt edge (``road_edge``), not paint
    edge: tuple[bool, bool] = (False, False)
    # (left, right): the line is placed a remembered shoulder inside the asphalt edge (its paint
    # faded out, ``LaneTracker`` step 8), not seen
    shoulder: tuple[bool, bool] = (False, False)


def line_source(search: LaneSearch, side: int) -> str:
    """Return where the found line ``side`` (0 left, 1 right) of a search comes from: "edge" (the
    asphalt edge), "shoulder" (placed a remembered shoulder inside it) or "seen" (paint)."""
    return "edge" if search.edge[side] else "shoulder" if search.shoulder[side] else "seen"


@dataclass(frozen=True)
class LaneMeasurement:
    """Lane geometry at the car in metres (NaN where a line needed for it was not found)."""

    curvature_per_m: float
    radius_m: float
    offset_m: float
    lane_width_m: float
    left_curvature_per_m: float
    right_curvature_per_m: float


# --------------------------------------------------------------------------- pixels

def lane_pixels(binary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (ys, xs) of the nonzero pixels of a mask, sorted by y (int32 arrays)."""
    pts = cv2.findNonZero(binary)
    if pts is None:
        return np.empty(0, np.int32), np.empty(0, np.int32)
    pts = pts.reshape(-1, 2)
    return pts[:, 1].copy(), pts[:, 0].copy()  # findNonZero scans row by row: already sorted by y


def histogram(binary: np.ndarray, fraction: float = 0.5) -> np.ndarray:
    """Return the count of mask pixels per column over the lower ``fraction`` of the image."""
    h = binary.shape[0]
    start = int(h * (1 - fraction))
    return cv2.reduce(binary[start:], 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel() // 255


def find_bases(hist: np.ndarray, car_x: float | None = None) -> tuple[float | None, float | None]:
    """Return the x of the strongest column left and right of ``car_x`` (None where empty)."""
    mid = int(car_x if car_x is not None else len(hist) / 2)
    left = int(np.argmax(hist[:mid])) if hist[:mid].any() else None
    right = mid + int(np.argmax(hist[mid:])) if hist[mid:].any() else None
    return (None if left is None else float(left), None if right is None else float(right))


def candidate_bases(hist: np.ndarray, car_x: float | None, count: int,
                    min_gap_px: float) -> tuple[list[float], list[float]]:
    """Return up to ``count`` histogram peaks (x, strongest first) left and right of ``car_x``.

    A peak is a column that holds the most pixels within ``min_gap_px`` either side (one per
    line, however wide); columns with no pixels are never peaks.
    """
    mid = int(car_x if car_x is not None else len(hist) / 2)
    r = max(1, int(min_gap_px))
    kernel = np.ones((1, 2 * r + 1), np.uint8)
    local_max = cv2.dilate(hist.astype(np.float32).reshape(1, -1), kernel).ravel()
    peaks = np.flatnonzero((hist > 0) & (hist >= local_max))
    out = []
    for side in (peaks[peaks < mid], peaks[peaks >= mid]):
        chosen: list[float] = []
        for x in side[np.argsort(-hist[side], kind="stable")]:
            if all(abs(x - c) >= min_gap_px for c in chosen):
                chosen.append(float(x))
            if len(chosen) == count:
                break
        out.append(chosen)
    return out[0], out[1]


def base_peak_confidence(hist: np.ndarray, x: float | None) -> float | None:
    """Return how much the histogram's peak at column ``x`` stands out: (peak - mean) / mean.

    0 for a flat histogram, large for one strong line on an empty view; None for no base, 0.0
    for an empty histogram.
    """
    if x is None:
        return None
    mean = float(np.mean(hist)) if len(hist) else 0.0
    if mean <= 0:
        return 0.0
    return (float(hist[int(x)]) - mean) / mean


def _window_clusters(xs: np.ndarray) -> list[np.ndarray]:
    """Return the indices into ``xs`` of each run of occupied columns (split at empty columns)."""
    order = np.argsort(xs, kind="stable")
    sx = xs[order]
    cuts = np.nonzero(np.diff(sx) > 1)[0] + 1
    return np.split(order, cuts)


def sliding_windows(binary: np.ndarray, config: SearchConfig = SearchConfig(),
                    bases: tuple[float | None, float | None] | None = None,
                    car_x: float | None = None, top_px: int = 0) -> LaneSearch:
    """Return the lane pixels found by sliding windows from the histogram bases, and their fits.

    With ``top_px`` > 0 the search reads only the rows from ``top_px`` down (a shorter
    look-ahead, ``lookahead_top_px``): the histogram covers the lower ``histogram_fraction`` of
    those rows and the windows, as tall as in the whole view, stop there. The fits stay in the
    view's coordinates and their span rules in its rows (``fit_line``).
    """
    h = binary.shape[0]
    top_px = int(min(max(top_px, 0), h - 1))
    ys, xs = lane_pixels(binary)
    if top_px:
        first = int(np.searchsorted(ys, top_px))
        ys, xs = ys[first:], xs[first:]
    seen = binary[top_px:] if top_px else binary
    confidence: tuple[float | None, float | None] = (None, None)
    if bases is None:
        hist = histogram(seen, config.histogram_fraction)
        bases = find_bases(hist, car_x)
        confidence = tuple(base_peak_confidence(hist, b) for b in bases)
        if None in bases:  # a dashed line may have no dash in the lower part: look at all rows
            whole_hist = histogram(seen, 1.0)
            whole = find_bases(whole_hist, car_x)
            confidence = tuple(c if b is not None else base_peak_confidence(whole_hist, w)
                               for b, c, w in zip(bases, confidence, whole))
            bases = tuple(b if b is not None else w for b, w in zip(bases, whole))
    win_h = h / config.n_windows
    windows: list[Window] = []
    picked = {}
    for side, base in zip(("left", "right"), bases):
        chosen = []
        x = base
        margin = config.margin_px
        toward_centre = 1 if side == "left" else -1  # the lane centre lies right of the left line
        for i in range(config.n_windows):
            if x is None:
                break
            y_high = int(round(h - i * win_h))
            y_low = max(top_px, int(round(h - (i + 1) * win_h)))
            if y_high <= top_px:
                break
            lo, hi = np.searchsorted(ys, [y_low, y_high])
            row_xs = xs[lo:hi]
            inside = np.nonzero((row_xs >= x - margin) & (row_xs < x + margin))[0]
            windows.append(Window(side, int(x - margin), int(x + margin), y_low, y_high))
            if config.centre_first and len(inside) >= config.minpix:
                full = [c for c in _window_clusters(row_xs[inside]) if len(c) >= config.minpix]
                if full:
                    near = max(full, key=lambda c: toward_centre * float(row_xs[inside[c[0]]]))
                    inside = np.sort(inside[near])
            chosen.append(inside + lo)
            if len(inside) >= config.minpix:
                if config.window_histogram:
                    wx = row_xs[inside]
                    x0 = int(wx.min())
                    x = float(x0 + int(np.argmax(np.bincount(wx - x0))))
                else:
                    x = float(row_xs[inside].mean())
                margin = config.margin_px
            elif config.grow_margin_px:
                margin += config.grow_margin_px
        idx = np.concatenate(chosen) if chosen else np.empty(0, np.int64)
        picked[side] = (ys[idx], xs[idx])
    left, picked["left"] = fit_side(picked["left"], "left", h, config, "no lane pixels left of the car", top_px)
    right, picked["right"] = fit_side(picked["right"], "right", h, config, "no lane pixels right of the car",
                                      top_px)
    left, right = parallel_fits(left, right, picked["left"], picked["right"], h, config)
    return LaneSearch(left, right, "windows", picked["left"], picked["right"], tuple(windows), bases,
                      confidence, top_px)


def search_around(binary: np.ndarray, left: LineFit, right: LineFit,
                  config: SearchConfig = SearchConfig(), top_px: int = 0) -> LaneSearch:
    """Return the lane pixels within ``prior_margin_px`` of previous fits, and their new fits.

    With ``top_px`` > 0 only the rows from ``top_px`` down are read (as in ``sliding_windows``).
    """
    h, w = binary.shape[:2]
    top_px = int(min(max(top_px, 0), h - 1))
    # only the columns that the bands around the found fits reach hold pixels the search reads
    found = [p.x_at(np.arange(top_px, h, dtype=np.float64)) for p in (left, right) if p.found]
    lo = min(float(x.min()) for x in found) - config.prior_margin_px if found else 0.0
    hi = max(float(x.max()) for x in found) + config.prior_margin_px if found else 0.0
    if math.isfinite(lo) and math.isfinite(hi):
        c0 = min(w, max(0, math.floor(lo) - 1))
        c1 = max(c0, min(w, math.ceil(hi) + 2))
    else:
        c0, c1 = 0, w
    if c1 > c0:
        ys, xs = lane_pixels(binary[top_px:, c0:c1])
        ys += top_px
        xs += c0
    else:
        ys, xs = np.empty(0, np.int32), np.empty(0, np.int32)
    picked = {}
    for side, prior in (("left", left), ("right", right)):
        if not prior.found:
            picked[side] = (ys[:0], xs[:0])
            continue
        near = np.abs(xs - prior.x_at(ys)) < config.prior_margin_px
        picked[side] = (ys[near], xs[near])
    new_left, picked["left"] = fit_side(
        picked["left"], "left", h, config, "no previous left fit to search around" if not left.found
        else "no lane pixels near the previous left fit", top_px)
    new_right, picked["right"] = fit_side(
        picked["right"], "right", h, config, "no previous right fit to search around" if not right.found
        else "no lane pixels near the previous right fit", top_px)
    new_left, new_right = parallel_fits(new_left, new_right, picked["left"], picked["right"], h, config)
    return LaneSearch(new_left, new_right, "prior", picked["left"], picked["right"], top_px=top_px)


def lookahead_top_px(lines, size_px: tuple[int, int], config: SearchConfig = SearchConfig()) -> int:
    """Return the first row (px) of the look-ahead that keeps the tracked lines in the view.

    On a tight bend the lane leaves the bird's-eye view sideways long before its top row (the
    view is about 7.4 m wide: a line 1.9 m from its side leaves it after sqrt(2 * R * 1.9 m) of
    road, 15 m on a 60 m bend); above that row the other line sweeps across into its search
    windows and every check compares a line with the extrapolation of one that is gone. The
    look-ahead ends on the lowest row where a line comes within ``margin_px / 2`` of the view's
    side (about to leave it), but keeps at least ``min_view_fraction`` of the view's height. It
    is a band of rows of the same view, not a second warp: the metric scale (``ym_per_px``) and
    the fits' coordinates stay those of the view, so radius, offset and width read the same,
    and the overlay and the evaluation map the fits as before.

    Parameters
    ----------
    lines : pixel coefficients (a, b, c) of each tracked line (e.g. the tracked lane's two).
    size_px : (width, height) of the bird's-eye view.
    config : ``margin_px`` and ``min_view_fraction``.
    """
    w, h = size_px
    rows = np.arange(h - 1, -1, -8, dtype=np.float64)  # bottom to top, every 8 rows
    edge = config.margin_px / 2
    out = np.zeros(len(rows), bool)
    for coeffs in lines:
        x = np.polyval(coeffs, rows)
        out |= (x < edge) | (x > w - 1 - edge)
    if not out.any():
        return 0
    top = int(rows[int(np.argmax(out))]) + 1
    return int(min(top, round(h * (1.0 - config.min_view_fraction))))


def parallel_fits(left: LineFit, right: LineFit, left_pixels, right_pixels, height_px: int,
                  config: SearchConfig = SearchConfig()) -> tuple[LineFit, LineFit]:
    """Return the two fits with a short line's curvature taken from the other, longer line.

    A line whose pixels span less than ``min_span_fraction`` of the view (one dash, the stub
    of a line leaving the view on a bend) is fitted straight by ``fit_line`` unless its bend is
    resolved (``SearchConfig.short_bend_resolution``): its curvature is not measured, or measured
    over a short span, and a straight line beside a curved one fails the pair's curvature check
    and runs off the lane ahead. The lines of a lane are parallel, so it takes the second-order
    coefficient of the other line when that one spans enough for a second-order fit, and only
    its slope and position are fitted to its own pixels. Two short lines of which one kept its
    bend share one second-order coefficient fitted to both lines' pixels (``shared_curvature``):
    the two stubs of a hairpin's lines each read the bend from 5-6 m of line, with their own
    pixel noise, and two curvatures read apart make lines that part ahead. Two long lines, or
    two short straight ones, are left as they are.
    """
    if not (left.found and right.found):
        return left, right
    short = config.min_span_fraction * height_px
    if (left.span_px < short and right.span_px < short
            and (left.coeffs_px[0] != 0.0 or right.coeffs_px[0] != 0.0)):
        return shared_curvature(left, right, left_pixels, right_pixels, height_px)
    if (left.span_px < short) == (right.span_px < short):
        return left, right
    (line, pixels, other) = ((left, left_pixels, right) if left.span_px < short
                             else (right, right_pixels, left))
    ys, xs = pixels
    a = float(other.coeffs_px[0])
    y = ys.astype(np.float64)
    _, b, c, rss = _least_squares(ys, xs - a * y * y, 1, float(height_px))
    shared = replace(line, coeffs_px=(a, b, c), scatter_px=math.sqrt(rss / max(len(ys), 1)))
    return (shared, right) if line is left else (left, shared)


def shared_curvature(left: LineFit, right: LineFit, left_pixels, right_pixels,
                     height_px: int) -> tuple[LineFit, LineFit]:
    """Return the two lines refitted with one second-order coefficient: x = a*y**2 + b_i*y + c_i,
    by least squares over both lines' pixels (the lines of a lane are parallel; ``parallel_fits``).

    The normal equations of the five unknowns from sums over each line's pixels, with y centred
    on the mean row of both and divided by ``height_px`` (as ``_least_squares``); each fit's
    ``scatter_px`` is its own pixels' RMS distance from it. The fits are returned unchanged when
    the equations are singular.
    """
    scale = float(height_px)
    m = (float(left_pixels[0].astype(np.float64).sum() + right_pixels[0].astype(np.float64).sum())
         / (len(left_pixels[0]) + len(right_pixels[0])))
    parts = []
    for ys, xs in (left_pixels, right_pixels):
        t = (ys.astype(np.float64) - m) / scale
        x0 = float(xs.mean())
        x = xs.astype(np.float64) - x0
        t2 = t * t
        st = [float(len(t)), float(t.sum()), float(t2.sum()), float((t2 * t).sum()), float((t2 * t2).sum())]
        sx = [float(x.sum()), float((x * t).sum()), float((x * t2).sum())]
        parts.append((st, sx, x0, t, x))
    (sl, xl, _, _, _), (sr, xr, _, _, _) = parts
    gram = np.array([[sl[4] + sr[4], sl[3], sl[2], sr[3], sr[2]],
                     [sl[3], sl[2], sl[1], 0.0, 0.0],
                     [sl[2], sl[1], sl[0], 0.0, 0.0],
                     [sr[3], 0.0, 0.0, sr[2], sr[1]],
                     [sr[2], 0.0, 0.0, sr[1], sr[0]]])
    rhs = np.array([xl[2] + xr[2], xl[1], xl[0], xr[1], xr[0]])
    try:
        p = np.linalg.solve(gram, rhs)  # (A, b_left, c_left, b_right, c_right) in t
    except np.linalg.LinAlgError:
        return left, right
    fits = []
    for fit, (b, c), (_, _, x0, t, x) in zip((left, right), ((p[1], p[2]), (p[3], p[4])), parts):
        r = x - (p[0] * t * t + b * t + c)
        coeffs = (float(p[0] / scale ** 2), float(b / scale - 2 * p[0] * m / scale ** 2),
                  float(x0 + c - b * m / scale + p[0] * m * m / scale ** 2))
        fits.append(replace(fit, coeffs_px=coeffs, scatter_px=math.sqrt(float((r * r).mean()))))
    return fits[0], fits[1]


def inner_stripe(ys: np.ndarray, xs: np.ndarray, side: str, spacing_px: float,
                 height_px: int, stripes: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Return the pixels (ys, xs) of a line's inner stripe where they form a double line, else all.

    A double line (two stripes ``spacing_px`` apart, centre to centre) is one lane boundary,
    marked at its inner stripe, the one nearer the lane: right of the fit for the ``"left"``
    line, left of it for the ``"right"`` one. A fit through both runs between the stripes, and
    their pixels fill and scatter over the search band like a bright patch. The pixels are
    fitted as two parallel stripes (``two_stripes``: one curve, the stripes either side of it,
    each pixel on the nearer); they are a double line when the stripes are resolved
    (``_stripes_resolved``: each holds at least a fifth of the pixels, they lie 0.6-1.5 x
    ``spacing_px`` apart, each is narrow and the gap between them is clear) and lie side by
    side (each of eight bands of rows that holds pixels of one holds pixels of the other, but
    for a quarter of them). A single line, a dashed one or texture is returned unchanged. The
    stripes are fitted with a shared curve rather than split at the residuals of one fit: on a
    tight bend a short line's one fit misses the curve, the residuals of the two stripes run into
    each other and the gap looks filled.

    Far ahead the two stripes blur into one blob (a few raw pixels hold both, stretched by the
    bird's-eye view) that fills the gap, and a line whose blurred rows hold many of its pixels
    is not resolved as a whole; fitted through them it runs between the stripes, 0.11 m off
    the inner one at the car. Its near rows may still be resolved: the eight bands are then
    judged one by one from the car's end (each narrow stripe and a clear gap, as above, about
    the curve; a band where one stripe is worn away counts, as which stripe its pixels lie on is
    clear; so does a band whose own pixels form two resolved stripes, ``_band_resolved_alone``,
    as the curve fitted through the blurred rows may miss the near ones), and the
    run of resolved bands nearest the car (two at least, bands of under 20 pixels skipped),
    refitted on its own pixels until it settles, is a double line when it passes the rule as a
    whole. Only its inner stripe is returned: the rows beyond the run are left out, neither
    split (which pixels of a blur belong to which stripe is a guess) nor kept whole (the outer
    stripe in them would pull the fit off the inner one at the car as well).

    Parameters
    ----------
    ys, xs : the line's pixels (bird's-eye px).
    side : "left" or "right": which way the lane lies.
    spacing_px : centre-to-centre distance of the stripes (``SearchConfig.double_line_px``;
        0: off).
    height_px : height of the view (scales the first fit).
    stripes : ``two_stripes(ys, xs, 2, height_px)`` when already fitted (None: fitted here).
    """
    keep, _ = _inner_stripe_mask(ys, xs, side, spacing_px, height_px, stripes)
    return (ys, xs) if keep is None else (ys[keep], xs[keep])


def _inner_stripe_mask(ys: np.ndarray, xs: np.ndarray, side: str, spacing_px: float, height_px: int,
                       stripes: tuple | None, first: tuple | None = None) -> tuple[np.ndarray | None, bool]:
    """Return which pixels ``inner_stripe`` keeps (None: all, not a double line) and whether the
    line was resolved as a double line as a whole (False: on its near rows only). ``first``:
    ``fit_line``'s first fit of the same pixels (``_fit_line``) when already made (``fit_side``)."""
    n = len(ys)
    if spacing_px <= 0 or n < 20:
        return None, False
    y_min = ys.min()
    span = float(ys.max() - y_min)
    if span <= 0:
        return None, False
    degree = 2 if span >= 0.3 * height_px else 1
    rss = first[3] if first is not None and degree == 2 else _least_squares(ys, xs, degree, float(height_px))[3]
    if rss < n * (spacing_px / 4) ** 2:
        return None, False  # close to one fit (a single stripe): no second stripe to look for
    model = two_stripes(ys, xs, 2, height_px, first=first) if stripes is None else stripes
    bands, counts, distinct = _row_bands(ys, y_min, span)
    y = ys.astype(np.float64)
    r = xs - _poly(model[0], y)  # from the centre curve
    inner = _inner_side(bands, None, model, side, spacing_px, r)
    if inner is not None:
        return inner, True
    # the near rows: the run of bands from the car's end where the stripes are resolved
    held = counts >= 20
    near = None  # all the pixels
    for _ in range(3):
        coeffs, spacing, upper, _ = model
        if r is None:
            r = xs - _poly(coeffs, y)
        run = []
        for band in range(7, -1, -1):
            if not held[band]:
                continue
            g = bands == band
            if not (_stripes_resolved(r[g], spacing[g], upper[g], spacing_px, pair=False)
                    or _band_resolved_alone(ys[g], xs[g], spacing_px, height_px, (span + 1) / 8,
                                            None if distinct is None else distinct[band])):
                break
            run.append(band)
        if len(run) < 2:
            return None, False
        settled = np.isin(bands, run)
        if settled.all() if near is None else (settled == near).all():
            break
        near = settled
        part = two_stripes(ys[near], xs[near], 2, height_px)
        # the near rows' model on every pixel: its curve, its spacing (linear in y, so the line
        # through its values on the run's first and last rows) and each pixel's side
        lo, hi = int(np.argmin(y[near])), int(np.argmax(y[near]))
        y0, y1 = float(y[near][lo]), float(y[near][hi])
        slope = (float(part[1][hi]) - float(part[1][lo])) / (y1 - y0) if y1 > y0 else 0.0
        model = (part[0], float(part[1][lo]) + slope * (y - y0), xs > np.polyval(part[0], y), part[3])
        r = None
    if r is None:
        r = xs - _poly(model[0], y)
    return _inner_side(bands, near, model, side, spacing_px, r), False


def _row_bands(ys: np.ndarray, y_min, span: float) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Return each pixel's band of rows (eight of ``span`` + 1 rows from ``y_min`` down), the
    pixels in each band and the distinct rows each holds (None for pixels off the integer rows).

    The band of row ``y`` is ``(y - y_min) * 8 // (span + 1)``; for integer rows it is read from a
    table of that expression over the span's rows, so the pixels cost one look-up each."""
    if ys.dtype.kind not in "iu":
        bands = ((ys - y_min) * 8 // (span + 1)).astype(np.int64)
        return bands, np.bincount(bands, minlength=8), None
    table = ((np.arange(int(span) + 1) * 8) // (span + 1)).astype(np.intp)
    offset = (ys - y_min).astype(np.intp)
    per_row = np.bincount(offset, minlength=len(table))
    counts = np.bincount(table, weights=per_row, minlength=8)
    distinct = np.bincount(table, weights=per_row > 0, minlength=8)
    return table[offset], counts, distinct


def _poly(coeffs, y: np.ndarray) -> np.ndarray:
    """Return ``np.polyval`` of a second-order ``coeffs`` (a, b, c) on ``y`` (the same values:
    Horner's rule, without polyval's array of zeros)."""
    a, b, c = coeffs
    return (a * y + b) * y + c


def _inner_side(bands: np.ndarray, rows: np.ndarray | None, model: tuple, side: str, spacing_px: float,
                r: np.ndarray) -> np.ndarray | None:
    """Return which pixels of ``rows`` (a mask; None: all) lie on the inner stripe of the
    two-stripe ``model`` (``two_stripes``' curve, spacing per pixel and side per pixel; ``r``:
    each pixel's residual from its curve), or None when those pixels are not a double line there
    (``inner_stripe``: resolved, side by side)."""
    _, spacing, upper, _ = model
    on_rows, r, spacing, up = (bands, r, spacing, upper) if rows is None else (
        bands[rows], r[rows], spacing[rows], upper[rows])
    if not _stripes_resolved(r, spacing, up, spacing_px):
        return None
    # side by side, not one after the other: both stripes on most of the rows either is on
    # (a curve the first fit misses leaves residuals of one sign on some rows, the other on others)
    on = [np.bincount(on_rows[g], minlength=8) > 0 for g in (~up, up)]
    if (on[0] & on[1]).sum() < 0.75 * (on[0] | on[1]).sum():
        return None
    keep = upper if side == "left" else ~upper
    return keep.copy() if rows is None else rows & keep


BAND_ONE_STRIPE_RMS = 0.22  # under the 0.24 x spacing two resolved stripes need (``_band_resolved_alone``)


def _band_resolved_alone(ys: np.ndarray, xs: np.ndarray, spacing_px: float, height_px: int,
                         rows: float, distinct: float | None = None) -> bool:
    """Return whether one band of a line's rows (``rows`` high) shows two resolved stripes on
    its own: its pixels, on at least half of its rows, fitted as two straight parallel stripes
    (``two_stripes`` of degree 1) pass ``_stripes_resolved`` with both stripes present. The
    line's curve, fitted through rows where the stripes blur, can miss the band's stripes at the
    car by more than a stripe's width; the band's own pixels are not misled by those rows (but
    pixels on a few rows only would fit any two straight stripes). ``distinct``: the band's
    distinct rows when already counted."""
    if (len(np.unique(ys)) if distinct is None else distinct) < rows / 2:
        return False
    # two stripes side by side, each a fifth of the pixels, 0.6 x spacing_px apart or more, lie
    # at least 0.4 x 0.6 = 0.24 x spacing_px (RMS) from any one straight line through them: a
    # band closer than that to its own straight fit is one stripe (most bands of a single line)
    if _least_squares(ys, xs, 1, float(height_px))[3] < len(ys) * (BAND_ONE_STRIPE_RMS * spacing_px) ** 2:
        return False
    coeffs, spacing, upper, _ = two_stripes(ys, xs, 1, height_px)
    return _stripes_resolved(xs - _poly(coeffs, ys.astype(np.float64)), spacing, upper, spacing_px)


def _stripes_resolved(r: np.ndarray, spacing: np.ndarray, upper: np.ndarray, spacing_px: float,
                      pair: bool = True) -> bool:
    """Return whether pixels at residuals ``r`` (px) from a two-stripe curve, with the stripes'
    ``spacing`` (px) on their rows and ``upper`` their side, lie on two resolved stripes: each
    stripe is narrow (its pixels' RMS distance from it under a quarter of their median spacing:
    the view's scale and the stripes' width scale alike) and the gap between them is clear
    (under 5 % of the pixels within an eighth of the spacing of its middle). With ``pair`` the
    pixels must also show both: each stripe holds at least a fifth of them and their median
    spacing is 0.6-1.5 x ``spacing_px``; without it a band of rows where one stripe is worn
    away still counts (which stripe its pixels lie on is clear)."""
    n = len(r)
    if n == 0:
        return False
    right = int(np.count_nonzero(upper))
    if pair and min(n - right, right) < 0.2 * n:
        return False
    # the median lies between the least and the greatest spacing: those decide most lines at once
    if pair and (float(spacing.max()) < 0.6 * spacing_px or float(spacing.min()) > 1.5 * spacing_px):
        return False
    apart = float(np.median(spacing))
    if pair and not 0.6 * spacing_px <= apart <= 1.5 * spacing_px:
        return False
    off = r - np.where(upper, 0.5, -0.5) * spacing  # from the pixel's stripe
    if max(float(np.sqrt(np.mean(off[g] ** 2))) for g, held in ((~upper, right < n), (upper, right > 0))
           if held) > abs(apart) / 4:
        return False
    # no clear gap between them: one line the first fit misses (or a blur of both), not two
    return np.count_nonzero(np.abs(r) < np.abs(spacing) / 8) <= 0.05 * n


def stripe_spacing_px(binary: np.ndarray, coeffs_px, spacing_px: float, top_px: int = 0,
                      bands: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows (px) and the measured centre-to-centre spacing (px) of a double line's two
    stripes along the fit ``coeffs_px`` (of either stripe or between them), one per band of rows
    from ``top_px`` down where both stripes show.

    In each of ``bands`` bands of rows the mask's pixels within 2.5 x ``spacing_px`` of the fit
    are split into two groups by their x residual (two-means); the band counts when each group
    holds at least a fifth of them, their centres lie 0.5-2.5 x ``spacing_px`` apart and the gap
    between them is clear (as in ``inner_stripe``; the split starts from the residuals' extremes, as
    the spacing ahead is not known). The flat view spreads or narrows the road
    ahead where it pitches, the stripes' spacing with it: its change along the rows is the
    change of the view's scale across the road.
    """
    h = binary.shape[0]
    ys, xs = np.nonzero(binary[top_px:])
    ys = ys + top_px
    r = xs - np.polyval(coeffs_px, ys.astype(np.float64))
    near = np.abs(r) < 2.5 * spacing_px
    ys, r = ys[near], r[near]
    edges = np.linspace(float(top_px), float(h), bands + 1)
    out_y, out_s = [], []
    for lo_y, hi_y in zip(edges[:-1], edges[1:]):
        sel = (ys >= lo_y) & (ys < hi_y)
        rb = r[sel]
        if len(rb) < 20:
            continue
        lo, hi = float(rb.min()), float(rb.max())
        for _ in range(8):  # two-means on the residuals, from their extremes
            upper = rb > (lo + hi) / 2
            if upper.all() or not upper.any():
                break  # one group: no two stripes in this band
            lo, hi = float(rb[~upper].mean()), float(rb[upper].mean())
        else:
            n = len(rb)
            gap = hi - lo
            if (min(int(upper.sum()), int((~upper).sum())) >= 0.2 * n
                    and 0.5 * spacing_px <= gap <= 2.5 * spacing_px
                    and np.count_nonzero(np.abs(rb - (lo + hi) / 2) < gap / 8) <= 0.05 * n):
                out_y.append(0.5 * (lo_y + hi_y))
                out_s.append(gap)
    return np.array(out_y), np.array(out_s)


def fit_side(pixels: tuple[np.ndarray, np.ndarray], side: str, height_px: int, config: SearchConfig,
              missing: str, top_px: int = 0) -> tuple[LineFit, tuple[np.ndarray, np.ndarray]]:
    """Return ``fit_line`` of one line's pixels and the pixels it rests on: those of its inner
    stripe (``inner_stripe``) when they scatter from the fit like a double line (RMS above a
    quarter of ``double_line_px``), so a single line costs no second fit. Every search fits its
    lines here (``side``: "left" or "right", the side of the lane they bound). A line resolved
    as a double line as a whole is its inner stripe's fit, found or not: a fit through both
    stripes runs between them, never on the line (a patch of double line too short to fit, with
    a stray pixel further on lending the whole its span, is not found rather than fitted through
    both stripes and bent by that pixel). An inner stripe resolved only on the rows nearest the
    car is taken when its fit is found and as well founded as the fit of the whole line (second
    order where that one is: spanning ``min_span_fraction`` of the view); a short stub of it is
    not worth the line, which was not shown to be two stripes beyond it. A line that
    scatters so but is not narrowed to a stripe keeps its pixels' spread about two stripes
    (``two_stripes``, fitted once for both: ``LineFit.stripe_scatter_px``) when each stripe holds
    at least a fifth of them. ``top_px``: the search's look-ahead (``fit_line``)."""
    fit, first = _fit_line(*pixels, height_px, config, missing, top_px)
    if config.double_line_px and fit.found and fit.scatter_px > config.double_line_px / 4:
        stripes = two_stripes(*pixels, 2, height_px, first=first)
        keep, whole = _inner_stripe_mask(*pixels, side, config.double_line_px, height_px, stripes, first)
        if keep is not None:
            inner = (pixels[0][keep], pixels[1][keep])
            narrowed = fit_line(*inner, height_px, config, missing=missing, top_px=top_px)
            curved = config.min_span_fraction * height_px
            if whole or narrowed.found and (narrowed.span_px >= curved or fit.span_px < curved):
                return narrowed, inner
        n = len(pixels[0])
        right = int(np.count_nonzero(stripes[2]))
        if min(right, n - right) >= 0.2 * n:
            fit = replace(fit, stripe_scatter_px=math.sqrt(stripes[3] / n))
    return fit, pixels


def offset_line(coeffs_px, offset_m, xm_per_px: float, ym_per_px: float, height_px: int,
                top_px: int = 0) -> tuple[float, float, float]:
    """Return the pixel fit (a, b, c) of the curve parallel to a line at ``offset_m`` along its normal.

    The lines of a lane are parallel curves: the other line lies a lane width away along the
    normal, not at the same x shift on every row (on a 35 m bend, 23 m ahead, the two differ by
    over half a metre). The line is sampled on the rows from ``top_px`` to the bottom, each
    point moved ``offset_m`` along the normal in metres (positive: to the right of the line as
    the car drives, larger x) and the second-order fit x = f(y) refitted to the moved points.

    Parameters
    ----------
    coeffs_px : (a, b, c) of the line in bird's-eye pixels.
    offset_m : signed normal distance (m); + to the right. One value, or one per sampled row
        (``offset_rows_px``): a distance that changes along the view, as a tracked lane's width
        does where a grade widens or narrows the flat view's lane ahead.
    xm_per_px, ym_per_px : metres per bird's-eye pixel across and along the road.
    height_px : height of the view; top_px : first row sampled.
    """
    y = offset_rows_px(height_px, top_px)
    x = np.polyval(coeffs_px, y)
    slope_m = np.polyval(np.polyder(np.asarray(coeffs_px, float)), y) * xm_per_px / ym_per_px
    norm = np.sqrt(1.0 + slope_m * slope_m)
    x_new = x + offset_m / norm / xm_per_px
    y_new = y - offset_m * slope_m / norm / ym_per_px
    return tuple(float(v) for v in np.polyfit(y_new, x_new, 2))


def offset_rows_px(height_px: int, top_px: int = 0) -> np.ndarray:
    """Return the rows (px) ``offset_line`` samples: 24, evenly from ``top_px`` to the bottom."""
    return np.linspace(float(top_px), height_px - 1.0, 24)


def normal_width_m(left_px, right_px, y_px, xm_per_px: float, ym_per_px: float):
    """Return the distance (m) between two lines along their normal on row ``y_px`` (a float),
    or on each of several rows (an array).

    The horizontal width on a row times the cosine of the lane's heading there (the mean slope
    of the two lines); equal to the lane width on a bend where the horizontal width is wider.
    """
    xl, xr = np.polyval(left_px, y_px), np.polyval(right_px, y_px)
    dl = np.polyval(np.polyder(np.asarray(left_px, float)), y_px)
    dr = np.polyval(np.polyder(np.asarray(right_px, float)), y_px)
    slope_m = 0.5 * (dl + dr) * xm_per_px / ym_per_px
    out = (xr - xl) * xm_per_px / np.sqrt(1.0 + slope_m * slope_m)
    return float(out) if np.ndim(out) == 0 else out


# --------------------------------------------------------------------------- fits

def fit_line(ys: np.ndarray, xs: np.ndarray, height_px: int, config: SearchConfig = SearchConfig(),
             missing: str = "no lane pixels", top_px: int = 0) -> LineFit:
    """Return the 2nd-order fit x = f(y) of a line's pixels, or a not-found LineFit saying why.

    Pixels spanning less than ``min_span_fraction`` of the height are fitted straight, unless
    the search read a look-ahead (``top_px`` > 0, its first row) and the 2nd-order fit bows over
    the span by ``short_bend_resolution`` times the pixels' RMS scatter about it or more (a
    resolved bend: a tight bend's line that leaves the view sideways).
    """
    return _fit_line(ys, xs, height_px, config, missing, top_px)[0]


def _fit_line(ys: np.ndarray, xs: np.ndarray, height_px: int, config: SearchConfig, missing: str,
              top_px: int) -> tuple[LineFit, tuple | None]:
    """Return ``fit_line``'s fit and its first fit: ``_least_squares`` of degree 2 of all the
    pixels and the sums it read (a, b, c, rss, ``_normal_sums``; None when the line was turned
    down before it), which ``fit_side`` hands on to the stripe test rather than fit the same
    pixels again."""
    n = len(ys)
    if n == 0:
        return LineFit(None, 0, 0.0, missing), None
    span = float(ys.max() - ys.min())
    if n < config.min_line_pixels:
        return LineFit(None, n, span, f"only {n} lane pixels (need {config.min_line_pixels})"), None
    if span < config.min_found_span_fraction * height_px:
        return LineFit(None, n, span, f"pixels span only {span:.0f} px of the height"), None
    degree = 2
    sums = _normal_sums(ys, xs, float(height_px))
    a, b, c, rss = _least_squares(ys, xs, degree, float(height_px), sums)
    first = (a, b, c, rss, sums)
    if span < config.min_span_fraction * height_px and not (
            top_px > 0 and config.short_bend_resolution > 0
            and abs(a) * span * span / 4 >= config.short_bend_resolution * math.sqrt(rss / n)):
        degree = 1
        a, b, c, rss = _least_squares(ys, xs, degree, float(height_px))
    if 0 < config.trim_outliers_pct < 100:
        keep = max(degree + 1, int(round(n * config.trim_outliers_pct / 100)))
        if keep < n:
            residual = np.abs(xs - np.polyval((a, b, c), ys))
            idx = np.sort(np.argpartition(residual, keep - 1)[:keep])
            ys, xs, n = ys[idx], xs[idx], keep
            span = float(ys.max() - ys.min())
            a, b, c, rss = _least_squares(ys, xs, degree, float(height_px))
    gap = max(0.0, height_px - 1.0 - float(np.quantile(ys, 1.0 - NEAR_SHARE)))
    return LineFit((a, b, c), n, span, scatter_px=math.sqrt(rss / n), gap_px=gap), first


def two_stripes(ys: np.ndarray, xs: np.ndarray, degree: int, height_px: int, iterations: int = 8,
                first: tuple | None = None) -> tuple[tuple[float, float, float], np.ndarray, np.ndarray, float]:
    """Return a line's pixels fitted as two parallel stripes: the centre curve's (a, b, c), the
    stripes' spacing (px) on each pixel's row, which pixels lie on the right-hand stripe (larger
    x), and the residual sum of squares (px**2) of the pixels about their stripe.

    One curve x = f(y) (of ``degree``) with the two stripes at +-d(y)/2 across it, d linear in y
    (the flat view spreads or narrows the road ahead where it pitches, the spacing with it:
    ``stripe_spacing_px``), fitted by least squares alternating with the pixels' assignment to
    the nearer stripe (two-means sharing one curve), from the split at the one-curve fit. Its
    residual is the pixels' spread within their stripes: a double line's two narrow stripes
    leave little of it (their width / sqrt(12)), where one curve through both runs in the gap;
    pixels spread evenly over a band keep half their RMS spread (each half of the band).
    ``first``: ``fit_line``'s first fit (a, b, c, rss and its ``_normal_sums``) of the same
    pixels when already made (``fit_side``; used for degree 2 only).
    """
    scale = float(height_px)
    k = degree + 1  # terms of the centre curve: 1, t (, t**2)
    n = len(ys)
    if first is not None and degree == 2 and (xs.dtype.kind in "iu" or xs.dtype == np.float64):
        # fit_line's first fit read the same arrays and sums (x's mean the same: integer or
        # float64 pixels' sums do not depend on the order they are added in)
        a, b, c, rss, sums = first
    else:
        sums = _normal_sums(ys, xs, scale)
        a, b, c, rss = _least_squares(ys, xs, degree, scale, sums)
    # the normal equations from sums of t**j and x * t**j over all pixels and over the right-hand
    # stripe's (s = +-1/2 per stripe: sums of s * t**j are the right stripe's less half the
    # whole), by numpy reductions as in ``_least_squares`` (no BLAS threads)
    y, m, t, t2, t3, st, x0, x, xt, sx = sums
    q, xsum = np.array(st), np.array(sx)
    # the per-pixel terms in one array: rows 1, t, .., t**k, then x, x * t (x about its mean)
    per_pixel = np.empty((k + 3, n))
    per_pixel[0] = 1.0
    for j, term in enumerate((t, t2, t3)[:k] + (x, xt), start=1):
        per_pixel[j] = term
    # the blocks of the normal equations that do not depend on the split
    fixed = np.zeros((k + 2, k + 2))
    for r in range(k):
        fixed[r, :k] = q[r:r + k]
    fixed[k:, k:] = 0.25 * np.array([[q[0], q[1]], [q[1], q[2]]])
    upper = xs > _poly((a, b, c), y)
    right = np.empty(k + 3)
    for i in range(iterations):
        right[0] = np.count_nonzero(upper)  # the right-hand stripe's pixels (the sum of its 1s)
        if right[0] == 0 or right[0] == n:
            return (a, b, c), np.zeros_like(t), np.zeros(n, bool), rss  # one stripe
        right[1:] = np.einsum("ij,j->i", per_pixel[1:], upper.astype(np.float64))
        st = right[:k + 1] - 0.5 * q[:k + 1]  # sums of s * t**j
        gram = fixed.copy()
        for r in range(k):
            gram[r, k:] = gram[k:, r] = st[r:r + 2]
        rhs = np.concatenate([xsum[:k], right[k + 1:] - 0.5 * xsum[:2]])
        try:
            p = np.linalg.solve(gram, rhs)
        except np.linalg.LinAlgError:
            return (a, b, c), np.zeros_like(t), np.zeros(n, bool), rss  # one stripe
        # the centre curve p0 + p1 t (+ p2 t**2), summed in that order (as einsum did)
        centre = np.multiply(t, p[1])
        centre += p[0]
        if k == 3:
            centre += np.multiply(t2, p[2])
        now = x > centre
        if i == iterations - 1 or not (now != upper).any():
            break
        upper = now
    spacing = p[k] + p[k + 1] * t
    residual = x - centre - np.where(upper, 0.5, -0.5) * spacing
    p2 = p[2] if degree == 2 else 0.0
    coeffs = (float(p2 / scale ** 2), float(p[1] / scale - 2 * p2 * m / scale ** 2),
              float(x0 + p[0] - p[1] * m / scale + p2 * m * m / scale ** 2))
    return coeffs, spacing, upper, float((residual * residual).sum())


def row_medians(keys: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return each distinct key of ``keys`` (a row, or a shrunk grid's row; ascending) and the
    median of the ``xs`` that share it (``np.median``'s, for all rows at once)."""
    keys, xs = np.asarray(keys), np.asarray(xs, float)
    order = np.lexsort((xs, keys))
    k, v = keys[order], xs[order]
    rows, first, counts = np.unique(k, return_index=True, return_counts=True)
    lo, hi = first + (counts - 1) // 2, first + counts // 2
    return rows, (v[lo] + v[hi]) / 2


def least_squares_poly(ys: np.ndarray, xs: np.ndarray, degree: int, scale: float) -> tuple[float, float, float]:
    """Return (a, b, c) of the least-squares x = a*y**2 + b*y + c (a = 0 for degree 1).

    The same fit as ``np.polyfit`` (to rounding), from the normal equations in y centred on its
    mean and divided by ``scale`` (e.g. the image height), which keeps them well conditioned; it
    costs a few sums instead of an SVD of an n x 3 matrix (the video hot path).
    """
    return _least_squares(ys, xs, degree, scale)[:3]


def _least_squares(ys: np.ndarray, xs: np.ndarray, degree: int, scale: float,
                   sums: tuple | None = None) -> tuple[float, float, float, float]:
    """Return (a, b, c) of ``least_squares_poly`` and the residual sum of squares (px**2).

    The residual comes from the same sums: for the least-squares solution p of G p = s it is
    sum(x**2) - p . s, with x taken about its mean so that the difference keeps its digits.
    ``sums``: ``_normal_sums(ys, xs, scale)`` when already made.
    """
    _, m, _, _, _, st, x0, x, _, sx = _normal_sums(ys, xs, scale) if sums is None else sums
    k = degree + 1
    gram = np.array([[st[i + j] for j in range(k)] for i in range(k)])
    p = np.linalg.solve(gram, np.array(sx[:k]))  # x - x0 = p0 + p1*t (+ p2*t**2)
    rss = max(0.0, float((x * x).sum()) - sum(float(p[i]) * sx[i] for i in range(k)))
    p2 = p[2] if degree == 2 else 0.0
    a = p2 / scale ** 2
    b = p[1] / scale - 2 * p2 * m / scale ** 2
    c = x0 + p[0] - p[1] * m / scale + p2 * m * m / scale ** 2
    return float(a), float(b), float(c), rss


def _normal_sums(ys: np.ndarray, xs: np.ndarray, scale: float) -> tuple:
    """Return what ``_least_squares`` fits from: y (float), its mean m, t = (y - m) / ``scale``,
    t**2, t**3, the sums of t**0..4, x's mean x0, x - x0, (x - x0) * t and the sums of (x - x0) *
    t**0..2; ``two_stripes`` starts from the same arrays and sums."""
    y = ys.astype(np.float64)
    x = xs.astype(np.float64)
    m = float(y.mean())
    t = (y - m) / scale
    # sums of products by numpy reductions, not BLAS dot products: BLAS threads spin on a busy machine
    t2 = t * t
    t3 = t2 * t
    st = [float(len(t)), float(t.sum()), float(t2.sum()), float(t3.sum()), float((t2 * t2).sum())]
    x0 = float(x.mean())
    x -= x0
    xt = x * t
    sx = [float(x.sum()), float(xt.sum()), float((x * t2).sum())]
    return y, m, t, t2, t3, st, x0, x, xt, sx


def fit_to_metres(coeffs_px, xm_per_px: float, ym_per_px: float) -> tuple[float, float, float]:
    """Return the metric coefficients of a pixel fit by exact scaling (x, y both in metres)."""
    a, b, c = coeffs_px
    return (a * xm_per_px / ym_per_px ** 2, b * xm_per_px / ym_per_px, c * xm_per_px)


def curvature(coeffs, y) -> float:
    """Return the signed curvature of x = a*y**2 + b*y + c at ``y`` (units of 1/y; right turn > 0)."""
    a, b, _ = coeffs
    return float(2 * a / (1 + (2 * a * y + b) ** 2) ** 1.5)


def radius(curv: float) -> float:
    """Return the radius 1/|curvature|, capped at RADIUS_MAX_M (NaN stays NaN)."""
    if np.isnan(curv):
        return float("nan")
    return float(min(RADIUS_MAX_M, 1.0 / abs(curv))) if curv != 0 else RADIUS_MAX_M


def support(fit: LineFit) -> float:
    """Return how much evidence a fit rests on: its pixel count times the rows it spans."""
    return float(fit.n_pixels) * max(fit.span_px, 1.0) if fit.found else 0.0


def measure(left: LineFit, right: LineFit, height_px: int, car_x_px: float,
            xm_per_px: float, ym_per_px: float) -> LaneMeasurement:
    """Return curvature, radius, offset and lane width in metres on the view's bottom row.

    The lane's centre line has the mean position of the two lines and their shape (a, b)
    weighted by each line's ``support``, so a line resting on one dash does not bend the lane.
    Anything needing a line that was not found is NaN.
    """
    y_px = height_px - 1
    y_m = y_px * ym_per_px
    nan = float("nan")
    kl = curvature(fit_to_metres(left.coeffs_px, xm_per_px, ym_per_px), y_m) if left.found else nan
    kr = curvature(fit_to_metres(right.coeffs_px, xm_per_px, ym_per_px), y_m) if right.found else nan
    if not (left.found and right.found):
        return LaneMeasurement(nan, nan, nan, nan, kl, kr)
    wl, wr = support(left), support(right)
    if wl + wr == 0:  # lines carried by a tracker with no pixels of their own: equal weight
        wl = wr = 1.0
    cl, cr = np.array(left.coeffs_px), np.array(right.coeffs_px)
    centre = (cl * wl + cr * wr) / (wl + wr)
    centre[2] = (cl[2] + cr[2]) / 2
    k = curvature(fit_to_metres(centre, xm_per_px, ym_per_px), y_m)
    xl, xr = float(left.x_at(y_px)), float(right.x_at(y_px))
    offset = (car_x_px - (xl + xr) / 2) * xm_per_px
    width = (xr - xl) * xm_per_px
    return LaneMeasurement(k, radius(k), offset, width, kl, kr)


# --------------------------------------------------------------------------- plausibility checks

def line_problem(fit: LineFit, band_px: float, checks: LaneChecks = LaneChecks(),
                 xm_per_px: float | None = None, side: str = "left") -> str:
    """Return why one fitted line is not a plausible lane line ("" when it is, or is not found).

    Parameters
    ----------
    fit : the line's fit, with the pixel count, rows spanned and scatter of its pixels.
    band_px : width (px) of the band its pixels were searched in, inside the view
        (``search_bands_px``; 0: the band checks are skipped).
    checks : the limits.
    xm_per_px : metres per bird's-eye pixel across, to state the scatter in metres (optional).
    side : "left" or "right", for the message.

    A line filling its band is a bright patch (``max_band_fill``); a line whose pixels spread
    evenly across the band is texture (``max_band_scatter``): both rules compare the pixels with
    the band they were searched in, so they hold for any view scale and search margin. A line
    that scatters over the limit from its one fit is still a line when its pixels form two
    narrow stripes (a double line the search did not narrow to its inner stripe): their spread
    about the two stripes (``LineFit.stripe_scatter_px``) within the limit of an even spread
    over half the band.
    """
    if not fit.found or band_px <= 0:
        return ""
    fill = fit.n_pixels / ((fit.span_px + 1) * band_px)
    if fill > checks.max_band_fill:
        return (f"{side} line is a bright patch, not a line (fills {fill:.0%} of its search band, "
                f"limit {checks.max_band_fill:.0%})")
    even = band_px / math.sqrt(12.0)
    scatter = fit.scatter_px / even
    if scatter <= checks.max_band_scatter:
        return ""
    # two stripes (a double line) each in its half of the band: spread like texture even so?
    stripes = (fit.scatter_px if fit.stripe_scatter_px is None else fit.stripe_scatter_px) / (even / 2)
    if stripes <= checks.max_band_scatter:
        return ""
    metres = f"{fit.scatter_px * xm_per_px:.2f} m, " if xm_per_px else ""
    two = ("" if fit.stripe_scatter_px is None else
           f"; as two stripes {stripes:.0%} of an even spread over half the band")
    return (f"{side} line is texture, not a line (its pixels scatter {metres}{scatter:.0%} of "
            f"an even spread over its search band, limit {checks.max_band_scatter:.0%}{two})")


def turn_back_m(fit: LineFit, height_px: int, xm_per_px: float, top_px: int = 0,
                width_px: int | None = None) -> float:
    """Return how far (m, across) a line's fit comes back, above its pixels, from the row where
    its x turns around within the look-ahead (rows ``top_px`` to the bottom); 0 when it does not
    turn there, or turns only where its pixels are (``LineFit.gap_px`` and ``span_px`` give their
    rows; a fit without pixels, span 0, rests on none). With ``width_px`` (the view's width) only
    the part inside the view's columns counts: a tight bend's line leaves the view sideways, and
    its fit's turn out there is not drawn.

    Examples
    --------
    A parabola turning on row 300, fitted to pixels on rows 400-719 only, comes back 300**2 * a
    px between row 300 and the view's top:

    >>> a = 0.5 / 0.00578 / 300**2
    >>> fit = LineFit((a, -2 * a * 300, 600.0), 2000, 319.0)
    >>> round(turn_back_m(fit, 720, 0.00578), 2)
    0.5
    >>> round(turn_back_m(replace(fit, span_px=719.0), 720, 0.00578), 2)  # seen on every row
    0.0
    """
    a, b, _ = fit.coeffs_px
    if a == 0:
        return 0.0
    turn = -b / (2 * a)
    if not top_px < turn < height_px - 1.0:
        return 0.0
    end = min(turn, height_px - 1.0 - fit.gap_px - fit.span_px)  # above the turn and the pixels
    if end <= top_px:
        return 0.0
    xs = np.polyval(fit.coeffs_px, np.linspace(float(top_px), end, 16))
    if width_px is not None:
        xs = xs[(xs >= 0) & (xs < width_px)]
    return float(np.ptp(xs)) * xm_per_px if len(xs) > 1 else 0.0


def turn_back_problem(fit: LineFit, height_px: int, xm_per_px: float, checks: LaneChecks = LaneChecks(),
                      top_px: int = 0, side: str = "left", width_px: int | None = None) -> str:
    """Return why a found line's fit hooks sideways within the look-ahead ("" when it does not,
    or is not found): it comes back more than ``max_turn_back_m`` beyond its pixels from where
    its x turns around (``turn_back_m``; with ``width_px``, inside the view's columns)."""
    if not fit.found:
        return ""
    back = turn_back_m(fit, height_px, xm_per_px, top_px, width_px)
    if back <= checks.max_turn_back_m:
        return ""
    return (f"{side} line hooks back {back:.2f} m beyond its pixels within the view (its x turns "
            f"around; limit {checks.max_turn_back_m} m)")


def holds_from_px(left: LineFit, right: LineFit, height_px: int, width_px: int, xm_per_px: float,
                  checks: LaneChecks = LaneChecks(), top_px: int = 0) -> int:
    """Return the first row (from the view's top) from which a lane's found lines hold down to
    the car: above it a line leaves the view's columns (where the road is not imaged), hooks
    back beyond its pixels (``turn_back_m`` over ``max_turn_back_m``: from its turning row), or
    the two lines touch or cross. A lane is drawn, and an inferred line reported, only below it:
    a second-order fit extrapolated beyond its paint may otherwise swing across the road.

    Examples
    --------
    A straight pair holds over the whole view; a line that leaves a 1280 px view on row 200 is
    drawn from row 201; a fit on rows 400-719 that turns on row 300 is drawn from its turn:

    >>> left, right = LineFit((0.0, 0.0, 400.0)), LineFit((0.0, 0.0, 880.0))
    >>> holds_from_px(left, right, 720, 1280, 0.00578)
    0
    >>> holds_from_px(left, LineFit((0.0, -1.0, 1480.0)), 720, 1280, 0.00578)
    201
    >>> a = 0.5 / 0.00578 / 300**2
    >>> holds_from_px(LineFit((a, -2 * a * 300, 400.0), 2000, 319.0), right, 720, 1280, 0.00578)
    300
    """
    rows = np.arange(float(top_px), float(height_px))
    top = top_px
    xs = {}
    for i, fit in enumerate((left, right)):
        if not fit.found:
            continue
        x = np.polyval(fit.coeffs_px, rows)
        xs[i] = x
        out = np.flatnonzero((x < 0) | (x >= width_px))
        if len(out):
            top = max(top, int(rows[out[-1]]) + 1)
        if turn_back_m(fit, height_px, xm_per_px, top_px, width_px) > checks.max_turn_back_m:
            a, b, _ = fit.coeffs_px
            top = max(top, int(math.ceil(-b / (2 * a))))
    if left.found and right.found:
        touch = np.flatnonzero(xs[1] - xs[0] <= 0)
        if len(touch):
            top = max(top, int(rows[touch[-1]]) + 1)
    return min(top, height_px - 1)


def gap_problem(fit: LineFit, ym_per_px: float, max_gap_m: float, side: str = "left") -> str:
    """Return why a line is not seen at the car: its pixels stop more than ``max_gap_m`` (m of
    road) short of the view's bottom row (``LineFit.gap_px``), so its position there is an
    extrapolation ("" when they reach nearer, or the line is not found). ``ym_per_px``: metres
    per bird's-eye pixel along the road."""
    gap_m = fit.gap_px * ym_per_px
    if not fit.found or gap_m <= max_gap_m:
        return ""
    return (f"{side} line seen only from {gap_m:.1f} m ahead of the view's bottom row "
            f"(limit {max_gap_m} m): at the car it is an extrapolation")


def pair_problem(left: LineFit, right: LineFit, height_px: int, xm_per_px: float, ym_per_px: float,
                 checks: LaneChecks = LaneChecks(), top_px: int = 0,
                 width_reference_px: np.ndarray | None = None) -> str:
    """Return why two found lines are not a plausible lane ("" when they are).

    The lane width on the bottom row must lie within ``min_width_m``-``max_width_m``; the lines
    may not cross (or touch) on any of ``4 * check_rows`` rows of the look-ahead; over
    ``check_rows`` rows from the look-ahead's top row (``top_px``, 0: the view's) to the bottom
    it may vary by at most ``max_width_spread_m`` times the share of the view's height those rows
    cover (parallel lines: the same divergence per metre); the two curvatures on the
    bottom row may differ by at most ``max_curvature_diff_per_m`` divided by that share. Only a
    few rows are evaluated (cheap enough for every frame).

    Why the curvature allowance grows as the look-ahead shortens: a curvature read from a fit
    over fewer metres of line is measured less well (for the same pixel noise its error grows as
    1 / span**2, and a parabola fitted to a circle's arc reads a curvature that depends on how
    much of the arc it spans: on a drawn 40 m bend the outer line, seen longer, read 0.0253 and
    the inner one 0.0224 1/m). Divided by the share, the two lines may still part by a
    curvature difference's dk * L**2 / 2 over the look-ahead's L that shrinks with L, as the
    width spread's limit does: a fixed limit refuses the true lane of a tight bend seen only
    in a short look-ahead.

    With ``width_reference_px`` (the tracked lane's width, px, on those rows) the spread is
    that of the width's difference from the reference: a grade makes the flat bird's-eye view
    widen or narrow the lane ahead, and the track already follows that change, so only a
    change of it from one frame to the next is refused.
    """
    rows = np.linspace(float(top_px), height_px - 1.0, checks.check_rows)
    width = (np.polyval(right.coeffs_px, rows) - np.polyval(left.coeffs_px, rows)) * xm_per_px
    spread_of = width if width_reference_px is None else width - np.asarray(width_reference_px) * xm_per_px
    if not checks.min_width_m <= width[-1] <= checks.max_width_m:
        return (f"lane width {width[-1]:.2f} m at the car outside {checks.min_width_m}-"
                f"{checks.max_width_m} m")
    dense = np.linspace(float(top_px), height_px - 1.0, 4 * checks.check_rows)
    apart = np.polyval(right.coeffs_px, dense) - np.polyval(left.coeffs_px, dense)
    if (apart <= 0).any():
        j = int(np.flatnonzero(apart <= 0)[-1])  # the crossing nearest the car: between j and j + 1
        row = dense[j] + (dense[j + 1] - dense[j]) * -apart[j] / (apart[j + 1] - apart[j])
        return f"lines cross {(height_px - 1.0 - row) * ym_per_px:.1f} m ahead of the view's bottom row"
    spread = float(spread_of.max() - spread_of.min())
    share = (height_px - 1.0 - top_px) / (height_px - 1.0)  # the look-ahead's share of the view
    limit = checks.max_width_spread_m * share
    if spread > limit:
        return (f"lines not parallel (width varies by {spread:.2f} m, "
                f"limit {round(limit, 2)} m)")
    y_m = (height_px - 1) * ym_per_px
    kl = curvature(fit_to_metres(left.coeffs_px, xm_per_px, ym_per_px), y_m)
    kr = curvature(fit_to_metres(right.coeffs_px, xm_per_px, ym_per_px), y_m)
    k_limit = checks.max_curvature_diff_per_m / share
    if abs(kl - kr) > k_limit:
        return (f"curvatures differ by {abs(kl - kr):.4f} 1/m "
                f"(limit {round(k_limit, 4)} 1/m)")
    return ""


def pitched_pair_problem(left: LineFit, right: LineFit, height_px: int, xm_per_px: float,
                         ym_per_px: float, checks: LaneChecks = LaneChecks(), top_px: int = 0,
                         max_change: float = 0.5) -> str:
    """Return why two found lines are not a lane even in a pitched flat view ("" when they are).

    The bird's-eye view is flat at the pitch its points were chosen for. Where the camera looks
    at the road ahead at another pitch (a grade, the car's load, another mount), the flat view
    scales the road across by a factor that changes linearly with the distance ahead: the
    lines of a lane then converge or diverge at a constant rate, which ``pair_problem`` refuses
    as not parallel. Here the width's straight-line trend over the check rows (a least-squares
    line in the row) is taken as the view's pitch when it changes the width by at most
    ``max_change`` of its width at the car over the whole view (its share of that over a
    shorter look-ahead, ``top_px``); the pair then passes ``pair_problem`` with that trend as
    its width reference: width at the car, parallel about the trend, equal curvatures.

    Examples
    --------
    Straight lines 3.5 m apart at the car and 2.25 m at the view's top:

    >>> left, right = LineFit((0.0, -0.3, 650.0)), LineFit((0.0, 0.0, 1040.0))
    >>> pair_problem(left, right, 720, 0.00578, 0.0326)
    'lines not parallel (width varies by 1.25 m, limit 0.7 m)'
    >>> pitched_pair_problem(left, right, 720, 0.00578, 0.0326)
    ''
    >>> pitched_pair_problem(left, right, 720, 0.00578, 0.0326, max_change=0.3)
    'lines not parallel even in a pitched view (their width changes by 36% of its width at the car, limit 30%)'
    """
    rows = np.linspace(float(top_px), height_px - 1.0, checks.check_rows)
    width = np.polyval(right.coeffs_px, rows) - np.polyval(left.coeffs_px, rows)
    trend = np.polyval(np.polyfit(rows, width, 1), rows)
    share = (height_px - 1.0 - top_px) / (height_px - 1.0)
    if trend[-1] <= 0:
        return pair_problem(left, right, height_px, xm_per_px, ym_per_px, checks, top_px)
    change, limit = abs(trend[0] - trend[-1]) / trend[-1], max_change * share
    if change > limit:
        return (f"lines not parallel even in a pitched view (their width changes by {change:.0%} of "
                f"its width at the car, limit {limit:.0%})")
    return pair_problem(left, right, height_px, xm_per_px, ym_per_px, checks, top_px, width_reference_px=trend)


@dataclass(frozen=True)
class LaneCheck:
    """Why the fits of one search are not a plausible lane: per line and for the pair ("" = passes).

    A line that was not found is not checked (its own ``reason`` says why it is missing); the pair
    is checked only when both lines were found and passed their own checks.
    """

    left: str = ""
    right: str = ""
    pair: str = ""

    @property
    def ok(self) -> bool:
        """Return True when nothing failed."""
        return not (self.left or self.right or self.pair)

    @property
    def reason(self) -> str:
        """Return every failure, joined by "; " ("" when nothing failed)."""
        return "; ".join(r for r in (self.left, self.right, self.pair) if r)


def check_lane(left: LineFit, right: LineFit, bands_px: tuple[float, float], height_px: int,
               xm_per_px: float, ym_per_px: float, checks: LaneChecks = LaneChecks(),
               top_px: int = 0, width_px: int | None = None) -> LaneCheck:
    """Return the plausibility checks of two fits: ``line_problem`` (and, given ``width_px``,
    ``turn_back_problem``) of each, then ``pair_problem``.

    Parameters
    ----------
    left, right : the fits of one search (bird's-eye pixels).
    bands_px : width (px) of the band each line's pixels were searched in (``search_bands_px``).
    height_px : height of the bird's-eye view.
    xm_per_px, ym_per_px : metres per bird's-eye pixel across and along the road.
    checks : the limits.
    top_px : the first row of the look-ahead the fits were made in (``LaneSearch.top_px``).
    width_px : width of the bird's-eye view, to check each line's turn back inside it (None:
        not checked; the tracker's searches leave it to their checks against the track).
    """
    lp = line_problem(left, bands_px[0], checks, xm_per_px, "left")
    rp = line_problem(right, bands_px[1], checks, xm_per_px, "right")
    if width_px is not None:
        lp = lp or turn_back_problem(left, height_px, xm_per_px, checks, top_px, "left", width_px)
        rp = rp or turn_back_problem(right, height_px, xm_per_px, checks, top_px, "right", width_px)
    pp = ""
    if left.found and right.found and not (lp or rp):
        pp = pair_problem(left, right, height_px, xm_per_px, ym_per_px, checks, top_px)
    return LaneCheck(lp, rp, pp)


def search_bands_px(search: LaneSearch, size_px: tuple[int, int],
                    config: SearchConfig = SearchConfig()) -> tuple[float, float]:
    """Return the mean width (px) inside the view of the band each line was searched in.

    Sliding windows: the mean of the line's windows cut to the view. A search around prior
    fits: ``2 * prior_margin_px`` around the new fit on eight rows, cut to the view. Cut to the
    view, so that texture along the view's edge, in half a window, is compared with the half it
    could fill.

    Parameters
    ----------
    search : the search (its windows, or its method "prior" and fits).
    size_px : (width, height) of the bird's-eye view.
    config : the search parameters (``margin_px``, ``prior_margin_px``).
    """
    w, h = size_px
    out = []
    for side in ("left", "right"):
        wins = [win for win in search.windows if win.side == side]
        if wins:
            widths = [max(0, min(w, win.x_high) - max(0, win.x_low)) for win in wins]
            out.append(float(sum(widths)) / len(widths))
            continue
        half = config.prior_margin_px if search.method == "prior" else config.margin_px
        fit = getattr(search, side)
        if not fit.found:
            out.append(2.0 * half)
            continue
        xs = fit.x_at(np.linspace(float(search.top_px), h - 1.0, 8))
        out.append(float(np.mean(np.clip(xs + half, 0, w) - np.clip(xs - half, 0, w))))
    return out[0], out[1]


# --------------------------------------------------------------------------- the asphalt edge


TRACE_START = 4  # edge points the trace starts from and extends by a straight line (``road_edge``)
DARK_V = 80.0  # saturation below this value (V, 0-255) is measured against it: a shadow's tint is not colour


def saturation(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the saturation ((max - min) / max of R, G, B, 0-1, the max taken as at least
    ``DARK_V``: the tint of a shadow or the noise of a dark pixel is not colour) and the value
    (max of R, G, B, 0-255) of each pixel of an RGB image, float32."""
    r, g, b = cv2.split(np.ascontiguousarray(rgb))
    hi = cv2.max(cv2.max(r, g), b).astype(np.float32)
    return (hi - cv2.min(cv2.min(r, g), b)) / np.maximum(hi, DARK_V), hi


def verge_features(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the per-pixel features that tell a verge from the road surface in a (shrunk)
    bird's-eye image: saturation (``saturation``: the bluish tint of a shadow or the noise of a
    dark pixel is not colour), grain (local std / mean of V over 3 x 3 px) and where the camera
    sees (not black). Both are free of the light's brightness, so a shadow on
    the road, a repaved strip, a tar seam and a concrete barrier (grey and smooth like the road)
    look like road; grass and dirt differ in saturation, gravel in grain."""
    sat, hi = saturation(rgb)
    mean = cv2.blur(hi, (3, 3))
    var = np.maximum(cv2.blur(hi * hi, (3, 3)) - mean * mean, 0.0)
    return sat, np.sqrt(var) / np.maximum(mean, 8.0), hi > 0


ROAD_VIEW_INSET = 0.25      # share of the lane's width left out inside each line (``road_view_top_px``)
ROAD_VIEW_REFERENCE_M = 1.5  # road (m) above the view's bottom row whose surface is the reference
ROAD_VIEW_OFF_SHARE = 0.5   # share of a row's interior pixels unlike the road for the row to be off it


def road_view_interior(rows_px: np.ndarray, lines, width_px: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the first and last-plus-one column (px, int) of the lane interior that
    ``road_view_top_px`` reads on each row of ``rows_px``: ``ROAD_VIEW_INSET`` of the lane's width
    inside each of the ``lines`` (pixel coefficients), clipped to a view ``width_px`` wide."""
    xl, xr = np.polyval(lines[0], rows_px), np.polyval(lines[1], rows_px)
    inset = ROAD_VIEW_INSET * (xr - xl)
    return (np.clip(np.round(xl + inset), 0, width_px).astype(int),
            np.clip(np.round(xr - inset), 0, width_px).astype(int))


def road_view_top_px(rows_rgb: np.ndarray, rows_px: np.ndarray, lines, ym_per_px: float,
                     min_saturation_step: float, run_m: float, width_px: int | None = None,
                     col0_px: int = 0) -> int:
    """Return the first row (px) of the look-ahead over the road seen continuously from the car:
    the row just below the lowest run of ``run_m`` of road whose lane interior does not look like
    the road near the car; 0 when the whole view does.

    Beyond a crest, or a car or anything else standing on the road ahead, the bird's-eye view's
    far rows hold what the camera sees there (grass, a barrier, other stretches of the road
    farther round a bend), and the lines' fits follow it. Each sampled row's lane interior (between
    the ``lines``, ``ROAD_VIEW_INSET`` of the lane's width inside each: no paint, a few pixels of
    a track's error) is compared with the road's surface just ahead of the car (the interior of
    the rows within ``ROAD_VIEW_REFERENCE_M`` of the bottom row): a pixel is unlike the road when
    its saturation (``saturation``: a shadow's dark tint is not colour) exceeds the
    reference's median by ``min_saturation_step`` (``EdgeConfig``'s: grass, dirt, a painted car),
    and a row is off the road when ``ROAD_VIEW_OFF_SHARE`` of its seen interior pixels are. A
    shadow, a repaved strip or a tar seam keeps the road's low saturation and never ends the
    view, however dark. A row whose interior is not in the view (the lines crossing or leaving
    it) ends the scan (``lookahead_top_px`` handles lines leaving the view).

    Parameters
    ----------
    rows_rgb : (n, W, 3) uint8 RGB rows of the bird's-eye view, in the order of ``rows_px``, or
        of its columns from ``col0_px`` on (at least those of ``road_view_interior``).
    rows_px : the view's rows sampled, from the bottom up (decreasing y).
    lines : pixel coefficients (a, b, c) of the tracked left and right lines.
    ym_per_px : metres of road per view row.
    min_saturation_step : saturation (0-1) above the road's that is unlike it.
    run_m : least run (m of road) of rows off the road that ends the view (a shadow's tinted
        edge, a patch of dirt on one row does not).
    width_px : the view's width (default: that of ``rows_rgb``); col0_px : the view's column of
        ``rows_rgb``'s first one.
    """
    rows_px = np.asarray(rows_px, np.float64)
    lo, hi = road_view_interior(rows_px, lines, rows_rgb.shape[1] if width_px is None else width_px)
    sat, top_v = saturation(rows_rgb)
    cols = np.arange(col0_px, col0_px + rows_rgb.shape[1])
    inside = (cols >= lo[:, None]) & (cols < hi[:, None])
    seen = inside & (top_v > 0)
    n_seen = seen.sum(axis=1)
    # the interior must be in the view: wide enough and mostly seen, from the bottom row on
    valid = (hi - lo >= 4) & (n_seen * 2 >= np.maximum(hi - lo, 1))
    stop = int(np.argmin(valid)) if not valid.all() else len(rows_px)
    ref = seen[:stop] & ((rows_px[0] - rows_px[:stop]) <= ROAD_VIEW_REFERENCE_M / ym_per_px)[:, None]
    if not ref.any():
        return 0
    limit = float(np.median(sat[:stop][ref])) + min_saturation_step
    off = ((sat[:stop] > limit) & seen[:stop]).sum(axis=1) >= ROAD_VIEW_OFF_SHARE * np.maximum(n_seen[:stop], 1)
    step_m = ym_per_px * abs(rows_px[0] - rows_px[-1]) / max(len(rows_px) - 1, 1)
    need = max(1, int(np.ceil(run_m / max(step_m, 1e-9))))
    run, prev = 0, -2
    for i in np.flatnonzero(off):  # the first run of ``need`` rows off the road, from the bottom
        run = run + 1 if run and i == prev + 1 else 1
        prev = i
        if run >= need:
            first = i - need + 1
            return 0 if first == 0 else int(rows_px[first - 1])
    return 0


@dataclass(frozen=True)
class VergeGrid:
    """The verge features (``verge_features``) of a bird's-eye view shrunk by ``scale`` each way,
    of its rows from ``row0`` (shrunk rows) down to the bottom: what ``road_edge`` reads, made
    once for several edges of one frame (``verge_grid``). ``height_px`` is the whole view's."""

    sat: np.ndarray
    grain: np.ndarray
    seen: np.ndarray
    row0: int
    height_px: int
    scale: int


def verge_grid(bird: np.ndarray, scale: int, row0_px: int = 0, height_px: int | None = None,
               sampled: bool = False) -> VergeGrid:
    """Return the ``VergeGrid`` of a bird's-eye image, or of its rows from ``row0_px`` (a multiple
    of ``scale``) down when ``bird`` holds only those (``height_px``: the whole view's height).
    ``sampled``: ``bird`` holds one row of each ``scale`` rows (``grid_rows_px``), shrunk only
    across (a quarter of the remap and of the features for a grid read on every frame)."""
    h, w = bird.shape[:2]
    rows = h if sampled else h // scale
    small = cv2.resize(bird, (w // scale, rows), interpolation=cv2.INTER_AREA) if scale > 1 else bird
    sat, grain, seen = verge_features(small)
    return VergeGrid(sat, grain, seen, row0_px // scale, h if height_px is None else height_px, scale)


def grid_rows_px(row0_px: int, height_px: int, scale: int) -> np.ndarray:
    """Return the one row of each ``scale`` rows from ``row0_px`` (a multiple of ``scale``) to
    ``height_px`` that a sampled ``verge_grid`` reads: the middle one of each."""
    return np.arange(row0_px + scale // 2, height_px - scale + 1 + scale // 2, scale)


def _edge_step(sat_row, grain_row, a: int, b: int, pad: tuple[int, int], win: int, sign: float,
               road_sat: float, road_grain: float, config: EdgeConfig) -> int | None:
    """Return the column (shrunk grid) of the road-to-verge step between columns ``a`` and ``b``
    of one row (``road_edge``'s test: the mean verge score of the ``2 * step_m`` window beyond it
    less that of the ``step_m`` window inside, largest, with the inside road and the outside
    verge), or None where there is none."""
    lo, hi = a - pad[0], b + pad[1]
    score = np.clip((sat_row[lo:hi] - road_sat) / config.min_saturation_step, 0, 1)
    if config.min_texture_ratio > 0:
        score = np.maximum(score, np.clip((grain_row[lo:hi] / road_grain - 1.0)
                                          / config.min_texture_ratio, 0, 1))
    if sign < 0:
        score = score[::-1]
    c = np.concatenate([[0.0], np.cumsum(score)])
    idx = np.arange(win, len(score) - 2 * win + 1)
    if not len(idx):
        return None
    inner = (c[idx] - c[idx - win]) / win
    outer = (c[idx + 2 * win] - c[idx]) / (2 * win)
    step = outer - inner
    j = int(np.argmax(step))
    if step[j] < config.min_step or inner[j] > config.max_inner or outer[j] < config.min_outer:
        return None
    # the boundary between the last inner and the first outer column
    return (lo + int(idx[j])) if sign > 0 else (hi - int(idx[j]))


def _edge_steps(sat, grain, seen, rows, a, b, pad: tuple[int, int], win: int, sign: float,
                road_sat: np.ndarray, road_grain: np.ndarray, config: EdgeConfig) -> tuple[np.ndarray, np.ndarray]:
    """Return which of ``rows`` (indices into them) have a road-to-verge step between their
    columns ``a`` and ``b`` and its column (shrunk grid, float): ``_edge_step`` on every row at
    once (the same sums in the same order, so the same columns)."""
    lo, hi = a - pad[0], b + pad[1]
    length = hi - lo
    keep = b > a
    if keep.any():
        offs = np.arange(int(length[keep].max()))
        inside = offs[None, :] < length[:, None]
        cols = (lo[:, None] + offs[None, :]) if sign > 0 else (hi[:, None] - 1 - offs[None, :])
        cols = np.clip(cols, 0, sat.shape[1] - 1)
        rr = rows[:, None]
        keep &= np.all(seen[rr, cols] | ~inside, axis=1)
    if not keep.any():
        return np.zeros(0, int), np.zeros(0)
    idx_rows = np.flatnonzero(keep)
    rr, cols, inside, length = rows[keep][:, None], cols[keep], inside[keep], length[keep]
    score = np.clip((sat[rr, cols] - road_sat[keep][:, None]) / config.min_saturation_step, 0, 1)
    if config.min_texture_ratio > 0:
        score = np.maximum(score, np.clip((grain[rr, cols] / road_grain[keep][:, None] - 1.0)
                                          / config.min_texture_ratio, 0, 1))
    score = np.where(inside, score, 0.0)
    c = np.concatenate([np.zeros((len(score), 1)), np.cumsum(score, axis=1)], axis=1)
    n = c.shape[1]
    j = np.arange(win, max(win + 1, n - 2 * win))
    valid = (j[None, :] <= (length - 2 * win)[:, None])
    jj = np.clip(j, 0, n - 1 - 2 * win) if n - 1 - 2 * win >= 0 else np.zeros_like(j)
    inner = (c[:, jj] - c[:, np.maximum(jj - win, 0)]) / win
    outer = (c[:, np.minimum(jj + 2 * win, n - 1)] - c[:, jj]) / (2 * win)
    step = np.where(valid, outer - inner, -np.inf)
    best = np.argmax(step, axis=1)
    pick = np.arange(len(step))
    ok = valid.any(axis=1) & (step[pick, best] >= config.min_step) & (inner[pick, best] <= config.max_inner) \
        & (outer[pick, best] >= config.min_outer)
    x = np.where(sign > 0, lo[keep] + j[best], hi[keep] - j[best]).astype(float)
    return idx_rows[ok], x[ok]


def road_edge(bird: np.ndarray, other: LineFit, side: str, xm_per_px: float, ym_per_px: float,
              checks: LaneChecks = LaneChecks(), config: EdgeConfig = EdgeConfig(),
              top_px: int = 0, guide_px=None, range_m: tuple[float, float] | None = None,
              bottom_px: int | None = None, grid: VergeGrid | None = None) -> tuple[LineFit, np.ndarray]:
    """Return the fit of the asphalt edge on ``side`` ("left"/"right") of the lane whose other
    line is ``other``, and its edge points ((N, 2) x, y px); a not-found fit says why.

    In the bird's-eye view shrunk by ``config.scale``, each pixel of a row gets a 0-1 verge
    score: its saturation above the road surface's (``verge_features``; the road is that row's
    median between ``other`` and the nearest the edge can be) over ``min_saturation_step``, or
    its grain's ratio to the road's, less 1, over ``min_texture_ratio``, whichever is larger
    (per row: the view blurs with distance, the grain with it). On each row, from the bottom up,
    between ``range_m`` (along the normal, default ``checks.min_width_m`` - 0.2 to
    ``max_width_m`` + 0.2 m) from ``guide_px`` (pixel coefficients; default ``other``'s fit),
    the edge is the column where the mean score of the ``2 * step_m`` window beyond it minus
    that of the ``step_m`` window inside is largest, kept when the inside is road (``max_inner``),
    the outside verge (``min_outer``) and the rise at least ``min_step``. With
    ``config.trace_margin_m``, once ``TRACE_START`` rows have an edge point the edge is followed
    instead: each row is searched within ``trace_margin_m`` (along the row, one shrunk pixel
    more per row without a point) of the straight line through the last ``TRACE_START`` points,
    so the edge is followed over the view where it is seen, however the flat view's width from
    ``other`` changes with distance (a pitched road, an S-bend beyond the other line's pixels);
    the road surface of a row whose reference lies out of the view is the last row's, and the
    trace ends after ``trace_gap_m`` of road without a point. The points are fitted
    by ``fit_line`` with ``trim_outliers_pct``, then refitted up to three times without the
    points beyond 3 robust standard deviations (1.4826 x the median distance) of the fit (a
    robust fit: a patch of darker grass or a shadow does not bend it). A seam, a repaved strip's
    edge, a shadow's edge or a concrete barrier's has grey road-like surface beyond it and gives
    no edge. ``bottom_px``: the rows below it are not read (default: the view's bottom row).
    ``grid``: the view's ``verge_grid`` made already (``bird`` is then not read).
    """
    if grid is None:
        grid = verge_grid(bird, config.scale)
    k, h, row0 = grid.scale, grid.height_px, grid.row0
    sat, grain, seen = grid.sat, grid.grain, grid.seen
    sh, sw = row0 + sat.shape[0], sat.shape[1]
    sign = 1.0 if side == "right" else -1.0
    last_row = sh if bottom_px is None else min(sh, int(np.ceil((bottom_px + 1) / k)))
    rows = np.arange(max(row0, top_px // k), last_row)[::-1]  # from the bottom up
    yf = rows * k + (k - 1) / 2.0  # the full view's rows at the shrunk rows' centres
    x_line = np.polyval(other.coeffs_px, yf)
    guide = np.asarray(other.coeffs_px if guide_px is None else guide_px, float)
    x_guide = np.polyval(guide, yf)

    def stretch_of(coeffs) -> np.ndarray:  # px across per metre along the normal
        slope = np.polyval(np.polyder(coeffs), yf) * xm_per_px / ym_per_px
        return np.sqrt(1.0 + slope * slope) / xm_per_px

    stretch, stretch_g = stretch_of(np.asarray(other.coeffs_px, float)), stretch_of(guide)
    near_m, far_m = (checks.min_width_m - 0.2, checks.max_width_m + 0.2) if range_m is None else range_m
    win = max(2, int(round(config.step_m / xm_per_px / k)))
    pad = (win, 2 * win) if sign > 0 else (2 * win, win)  # the outer window is 2 x step_m
    trace_half = config.trace_margin_m / xm_per_px / k
    gap_rows = max(1, int(round(config.trace_gap_m / ym_per_px / k)))
    # the road surface of each row: between the line and the nearest the edge may be (medians
    # of the windows on all rows at once, NaN where a row's window is short or not all seen)
    near = np.round((x_line + sign * 0.3 * checks.min_width_m * stretch) / k).astype(int)
    far = np.round((x_line + sign * (checks.min_width_m - 0.3) * stretch) / k).astype(int)
    p0, p1 = np.maximum(0, np.minimum(near, far)), np.minimum(sw, np.maximum(near, far) + 1)
    span = p1 - p0
    refs = np.full((len(rows), 2), np.nan)
    if len(rows) and span.max() > 0:
        offs = np.arange(int(span.max()))
        inside = offs[None, :] < span[:, None]
        cols = np.clip(p0[:, None] + offs[None, :], 0, sw - 1)
        rr = (rows - row0)[:, None]
        ok = (span >= win) & np.all(seen[rr, cols] | ~inside, axis=1)
        if ok.any():
            lo_i, hi_i = (span[ok] - 1) // 2, span[ok] // 2
            pick = np.arange(int(ok.sum()))
            for j, feature in enumerate((sat, grain)):
                vals = np.sort(np.where(inside, feature[rr, cols], np.nan)[ok], axis=1)  # NaN last
                refs[ok, j] = (vals[pick, lo_i] + vals[pick, hi_i]) / 2  # np.median's, in float32
    ys, xs = [], []
    road_sat, road_grain, missed = None, 1e-3, 0
    if trace_half <= 0:  # every row at once: its own road surface, its range from the guide
        use = ~np.isnan(refs[:, 0]) & (np.nan_to_num(refs[:, 0], nan=1.0) <= config.max_road_saturation)
        x0 = x_guide + sign * near_m * stretch_g
        x1 = x_guide + sign * far_m * stretch_g
        a, b = (x0 // k).astype(int), np.ceil(x1 / k).astype(int)
        a, b = np.maximum(np.minimum(a, b), pad[0]), np.minimum(np.maximum(a, b), sw - pad[1])
        ys_a, xs_a = _edge_steps(sat, grain, seen, rows[use] - row0, a[use], b[use], pad, win, sign,
                                 refs[use, 0].astype(sat.dtype),
                                 np.maximum(refs[use, 1], 1e-3).astype(grain.dtype), config)
        ys_a = yf[use][ys_a] if len(ys_a) else np.zeros(0)
        xs_a = xs_a * float(k)
        rows = rows[:0]  # the loop below is the trace's
    for i, r in enumerate(rows):
        tracing = trace_half > 0 and len(xs) >= TRACE_START
        if not np.isnan(refs[i, 0]):
            if refs[i, 0] > config.max_road_saturation:
                missed += 1
                continue
            road_sat, road_grain = float(refs[i, 0]), max(float(refs[i, 1]), 1e-3)
        elif not tracing or road_sat is None:
            continue
        if tracing:
            if missed > gap_rows:
                break  # the edge is no longer seen: the trace ends
            last_y, last_x = np.asarray(ys[-TRACE_START:]) / k, np.asarray(xs[-TRACE_START:]) / k
            slope, at = np.polyfit(last_y, last_x, 1)
            centre = slope * r + at
            half = trace_half + missed
            a, b = int(np.floor(centre - half)), int(np.ceil(centre + half))
        else:
            x0 = x_guide[i] + sign * near_m * stretch_g[i]
            x1 = x_guide[i] + sign * far_m * stretch_g[i]
            a, b = sorted((int(x0 // k), int(np.ceil(x1 / k))))
        a, b = max(a, pad[0]), min(b, sw - pad[1])
        if b <= a or not seen[r - row0, a - pad[0]:b + pad[1]].all():
            missed += 1
            continue
        x = _edge_step(sat[r - row0], grain[r - row0], a, b, pad, win, sign, road_sat, road_grain, config)
        if x is None:
            missed += 1
            continue
        missed = 0
        ys.append(yf[i])
        xs.append(float(x * k))
    if trace_half > 0:
        ys_a, xs_a = np.asarray(ys, float), np.asarray(xs, float)
    order = np.argsort(ys_a, kind="stable")  # the points from the view's top down
    ys_a, xs_a = ys_a[order], xs_a[order]
    depth = (h if bottom_px is None else bottom_px + 1) - top_px
    fit_cfg = SearchConfig(min_line_pixels=config.min_points, min_span_fraction=0.3,
                           min_found_span_fraction=config.min_span_fraction * depth / h,
                           trim_outliers_pct=config.trim_outliers_pct)
    fit = fit_line(ys_a, xs_a, h, fit_cfg, missing=f"no {side} asphalt edge (no road-to-verge step)")
    for _ in range(3):  # refit without the points far from the fit (robust: a patch, a shadow)
        if not fit.found:
            break
        res = np.abs(xs_a - fit.x_at(ys_a))
        keep = res <= max(2.0 * k, 3.0 * 1.4826 * float(np.median(res)))
        if keep.all():
            break
        ys_a, xs_a = ys_a[keep], xs_a[keep]
        fit = fit_line(ys_a, xs_a, h, replace(fit_cfg, trim_outliers_pct=0.0),
                       missing=f"no {side} asphalt edge (no road-to-verge step)")
    if not fit.found:
        fit = replace(fit, reason=f"{side} asphalt edge: {fit.reason}")
    return fit, np.column_stack([xs_a, ys_a])


# --------------------------------------------------------------------------- every line in view


@dataclass(frozen=True)
class ViewLine:
    """One line found by ``find_lines``: its fit x = a*y**2 + b*y + c in view px and its span.

    ``y_top_px``/``y_bottom_px`` are the first and last rows where it has pixels: where it is seen
    (``LinesConfig.extend_m`` beyond). ``scatter_px``: 1.4826 times the median |x residual|.
    """

    coeffs_px: tuple[float, float, float]
    y_top_px: float
    y_bottom_px: float
    n_pixels: int
    scatter_px: float

    def x_at(self, y) -> np.ndarray:
        """Return x (px) of the line at rows ``y`` (px)."""
        return np.polyval(self.coeffs_px, y)


def _peaks(hist: np.ndarray, min_gap_px: float, least: float) -> np.ndarray:
    """Return the columns of the histogram's peaks (at least ``least``), strongest first, each
    the highest within ``min_gap_px`` either side."""
    r = max(1, int(min_gap_px))
    hist = hist.astype(np.float32)  # compared with its dilation, in the same precision
    local_max = cv2.dilate(hist.reshape(1, -1), np.ones((1, 2 * r + 1), np.uint8)).ravel()
    peaks = np.flatnonzero((hist >= least) & (hist >= local_max))
    chosen: list[int] = []
    for x in peaks[np.argsort(-hist[peaks], kind="stable")]:
        if all(abs(int(x) - c) >= min_gap_px for c in chosen):
            chosen.append(int(x))
    return np.asarray(chosen, int)


def trace_line(ys: np.ndarray, xs: np.ndarray, x0: float, y0: float, height: int, win: int,
               margin: float, grow: float, max_empty: int, minpix: int, max_slope: float,
               slope: float = 0.0) -> np.ndarray:
    """Return the indices of the pixels of the line through (x0, y0), traced up and down by
    windows that follow the line's slope: a straight fit of the last window centres, once they
    span a window's height, its slope at most ``max_slope`` (px across per px along).

    ``ys``/``xs`` are the pixels (ascending ``ys``), ``win`` the windows' height, ``margin``
    their half width, grown by ``grow`` after each empty window; a trace stops after
    ``max_empty`` empty windows in a row, and a window recentres on ``minpix`` pixels or more.
    ``slope`` (dx/dy) is followed until the trace's own windows span enough rows for a slope.

    Examples
    --------
    >>> ys = np.arange(100.0); xs = 50 + 0.2 * ys                   # a slanted line
    >>> ys = np.append(ys, [10.0, 60.0]); xs = np.append(xs, [90.0, 10.0])  # two specks
    >>> order = np.argsort(ys, kind="stable")
    >>> len(trace_line(ys[order], xs[order], 60.0, 50.0, 100, 10, 5.0, 1.0, 2, 3, 1.0))
    100
    """
    picked = []
    for step in (-1, 1):  # up, then down
        centres: list[tuple[float, float]] = []
        x, m, empty = x0, margin, 0
        y_lo = y0 + win / 2  # upward the first window is the one around (x0, y0)
        while empty <= max_empty:
            lo_y, hi_y = (y_lo - win, y_lo) if step < 0 else (y_lo, y_lo + win)
            if hi_y <= 0 or lo_y >= height:
                break
            yc = (lo_y + hi_y) / 2
            cy, cx = np.asarray(centres[-4:]).T if centres else (np.array([y0]), np.array([x0]))
            if len(centres) >= 2 and np.ptp(cy) >= win:
                fitted, _ = np.polyfit(cy, cx, 1)
                x = cx[-1] + float(np.clip(fitted, -max_slope, max_slope)) * (yc - cy[-1])
            else:  # too few windows for a slope of its own yet: the one given
                x = cx[-1] + slope * (yc - cy[-1])
            lo, hi = np.searchsorted(ys, [lo_y, hi_y])
            inside = np.flatnonzero(np.abs(xs[lo:hi] - x) < m) + lo
            if len(inside) >= minpix:
                picked.append(inside)
                centres.append((float(ys[inside].mean()), float(xs[inside].mean())))
                x = centres[-1][1]
                m, empty = margin, 0
            else:
                m, empty = m + grow, empty + 1
            y_lo = lo_y if step < 0 else hi_y
    if not picked:
        return np.empty(0, np.int64)
    return np.unique(np.concatenate(picked))


def _fit_view_line(ys: np.ndarray, xs: np.ndarray, idx: np.ndarray, height: int, curved_px: float,
                   margin: float) -> tuple[ViewLine, np.ndarray] | None:
    """Return the fit of the pixels ``idx`` refined once on all pixels within ``margin / 2`` of it
    over its span, with the pixels it used; None without pixels."""
    for _ in range(2):
        if len(idx) < 3:
            return None
        y, x = ys[idx], xs[idx]
        span = float(y.max() - y.min())
        degree = 2 if span >= curved_px else 1
        a, b, c, rss = _least_squares(y, x, degree, float(height))
        lo, hi = np.searchsorted(ys, [y.min(), y.max() + 1])
        near = np.flatnonzero(np.abs(xs[lo:hi] - np.polyval((a, b, c), ys[lo:hi])) < margin / 2) + lo
        if len(near) < 3:
            break
        idx = near
    y = ys[idx]
    residual = np.abs(xs[idx] - np.polyval((a, b, c), y))
    return ViewLine((a, b, c), float(y.min()), float(y.max()), int(len(idx)),
                    1.4826 * float(np.median(residual))), idx


def _compare_x(p: ViewLine, q: ViewLine) -> float:
    """Return x of ``p`` minus x of ``q`` where both are seen (or midway between their spans)."""
    top, bottom = max(p.y_top_px, q.y_top_px), min(p.y_bottom_px, q.y_bottom_px)
    y = (top + bottom) / 2
    return float(p.x_at(y) - q.x_at(y))


def _mean_gap(p: ViewLine, q: ViewLine) -> float:
    """Return the mean |x difference| (px) of two lines over the rows both are seen on, or at
    the row midway between their spans when they share none."""
    top, bottom = max(p.y_top_px, q.y_top_px), min(p.y_bottom_px, q.y_bottom_px)
    rows = np.linspace(top, bottom, 8) if bottom > top else np.array([(top + bottom) / 2])
    return float(np.mean(np.abs(p.x_at(rows) - q.x_at(rows))))


def find_lines(binary: np.ndarray, config: LinesConfig = LinesConfig(), xm_per_px: float = 0.016,
               ym_per_px: float = 0.2) -> list[ViewLine]:
    """Return every line of a (wide, long) bird's-eye lane mask, left to right, with its span.

    Lines start at the peaks of column histograms of ``config.bands`` horizontal bands from the
    bottom up (a line needs pixels within the lowest ``bands * band_m``), strongest first; a peak within ``min_gap_fraction`` of a lane width of a line
    already traced there is skipped. Each line is traced up and down by windows that follow its
    slope, fitted with x = a*y**2 + b*y + c (straight when short), refitted once on the pixels
    near the fit, and kept with the rows where it has pixels. Traces nearer than that gap over
    their common rows are merged (refitted on both pixel sets). Left to right is compared where
    two lines are both seen.

    Parameters
    ----------
    binary : the 0/255 lane mask of the view (``perspective.LinesView``).
    config : the search in metres.
    xm_per_px, ym_per_px : metres per view pixel across and along the road.
    """
    h, w = binary.shape[:2]
    ys, xs = lane_pixels(binary)
    if not len(ys):
        return []
    gap = config.min_gap_fraction * config.lane_width_m / xm_per_px
    margin = config.margin_m / xm_per_px
    grow = config.grow_margin_m / xm_per_px
    win = max(2, int(round(config.window_m / ym_per_px)))
    band = max(2, int(round(config.band_m / ym_per_px)))
    curved = config.curved_span_m / ym_per_px
    least_peak = config.min_peak_m / ym_per_px
    found: list[tuple[ViewLine, np.ndarray]] = []
    smooth = np.ones(max(1, int(round(0.1 / xm_per_px))), np.float32)
    for k in range(config.bands):
        y1, y0 = h - k * band, max(0, h - (k + 1) * band)
        if y1 <= 0:
            break
        hist = cv2.reduce(binary[y0:y1], 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel() / 255.0
        hist = np.convolve(hist, smooth / len(smooth), mode="same")
        yc = (y0 + y1) / 2
        for x0 in _peaks(hist, gap, least_peak):
            if any(line.y_top_px - band <= yc <= line.y_bottom_px + band and abs(line.x_at(yc) - x0) < gap
                   for line, _ in found):
                continue
            idx = trace_line(ys, xs, float(x0), yc, h, win, margin, grow, config.max_empty_windows,
                         config.min_window_pixels, config.max_slope * ym_per_px / xm_per_px)
            fitted = _fit_view_line(ys, xs, idx, h, curved, margin)
            if fitted is not None:
                found.append(fitted)
    merged = True
    while merged:  # merge traces of one line
        merged = False
        for i in range(len(found)):
            for j in range(i + 1, len(found)):
                if _mean_gap(found[i][0], found[j][0]) < gap:
                    idx = np.union1d(found[i][1], found[j][1])
                    fitted = _fit_view_line(ys, xs, idx, h, curved, margin)
                    found = [f for n, f in enumerate(found) if n not in (i, j)]
                    if fitted is not None:
                        found.append(fitted)
                    merged = True
                    break
            if merged:
                break
    lines = [line for line, _ in found
             if line.n_pixels >= config.min_line_pixels
             and (line.y_bottom_px - line.y_top_px) * ym_per_px >= config.min_span_m
             and line.scatter_px * xm_per_px <= config.max_scatter_m]
    if config.extend_m > 0:
        more = config.extend_m / ym_per_px
        lines = [replace(line, y_top_px=max(0.0, line.y_top_px - more),
                         y_bottom_px=min(h - 1.0, line.y_bottom_px + more)) for line in lines]
    return sorted(lines, key=functools.cmp_to_key(lambda p, q: _compare_x(p, q)))
