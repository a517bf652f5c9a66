"""Every line in the (wide, long) lines view, traced by windows (``LinesConfig.method = "trace"``).

``find_lines`` starts a line at each strong peak of the column histograms of bands of rows from the
bottom up, follows it up and down with ``trace_line``, fits it (``ViewLine``) and merges traces of
one line; ``lines.vote`` finds them by a vote over straight lines instead.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import cv2
import numpy as np

from ..fit import least_squares_rss
from ..params import LinesConfig
from ..search import lane_pixels


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

    def shifted(self, rows: float) -> "ViewLine":
        """Return the same line in a view whose rows are numbered ``rows`` further on (a crop of
        the view that starts ``rows`` rows down holds it at its rows minus ``rows``).

        Examples
        --------
        >>> line = ViewLine((0.01, 0.5, 20.0), 0.0, 50.0, 10, 1.0)
        >>> moved = line.shifted(30)
        >>> float(moved.x_at(40.0)) == float(line.x_at(10.0)), moved.y_top_px, moved.y_bottom_px
        (True, 30.0, 80.0)
        """
        a, b, c = self.coeffs_px
        return replace(self, coeffs_px=(a, b - 2 * a * rows, a * rows * rows - b * rows + c),
                       y_top_px=self.y_top_px + rows, y_bottom_px=self.y_bottom_px + rows)


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
        a, b, c, rss = least_squares_rss(y, x, degree, float(height))
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
    bottom up (a line needs pixels within the lowest ``bands * band_m``), strongest first; a peak
    within ``min_gap_fraction`` of a lane width of a line already traced there is skipped. Each line
    is traced up and down by windows that follow its slope, fitted with x = a*y**2 + b*y + c
    (straight when short), refitted once on the pixels near the fit, and kept with the rows where it
    has pixels. Traces nearer than that gap over their common rows are merged (refitted on both
    pixel sets). Left to right is compared where two lines are both seen.

    Parameters
    ----------
    binary : the 0/255 lane mask of the view (``lines.view.LinesView``).
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
