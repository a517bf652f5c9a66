"""Every lane line in the lines view by a vote over straight lines (``LinesConfig.method = "vote"``).

On real roads a line is seen in pieces: dashes, the gaps between vehicles that hide it, worn
paint. Tracing it window by window stops at the first long gap; a vote does not. In the
bird's-eye lines view every lane line runs nearly along the road, so each is close to a straight
line ``x = x0 + s * t`` (``t`` the distance ahead of the view's bottom row, ``s`` its slope
across the road, set by the car's heading). The search, in the order it runs:

1. **Runs.** Each row's runs of mask pixels no wider than ``max_paint_width_m`` are paint; a
   wider run (a car, a shadow's edge, a verge) casts no vote (``run_centres``).
2. **Vote.** Each run's centre votes for the ``(x0, s)`` cells it lies on, within
   ``vote_tolerance_m``; a cell's votes are the metres of road along which the line has paint,
   a far row counting less when ``row_weights`` say it sees less of the frame, and a run less
   when its ``strength`` says it is barely brighter than the road beside it; a cell keeps
   what stands above the mean of its slope's cells (texture votes everywhere alike).
3. **Heading.** Lane lines are parallel: only slopes within ``heading_spread`` of a common
   heading count. The ``headings`` slopes with the most strong votes are tried, and the one whose
   reported lines hold the most paint is kept (junk beside the road can outvote the paint for a
   heading, but it does not pass as lines). On a bend or where a lane merges the lines do not
   share one heading: with ``tight_scatter_m``, a line of another heading whose runs scatter less
   than that about its fit is reported too, apart from the lines kept (``_tight_others``).
4. **Lines.** The strongest cell left is weighed, then every cell that is the same line as it
   (nearer than ``min_gap_fraction`` of a lane width, or crossing it, within the view) is
   cleared. Its runs are fitted (a parabola when they span ``curved_span_m``); with
   ``follow_bends`` they are followed by windows where the line bends away from the straight one.
5. **Checks.** A line is seen over the rows where its runs hug its fit (``seen_span``,
   ``seen_window_m``). It is refused, saying why (``Candidate.refused``), with less than
   ``min_peak_m`` of paint, paint spanning less than ``min_span_m``, runs scattering more than
   ``max_scatter_m`` about the fit, or when it runs under the car (``min_offset_m``) while its
   paint starts more than ``near_paint_m`` ahead (a vehicle's edge). With ``min_lane_fraction``,
   of two reported lines on one side of the car nearer than that share of a lane, the outer one
   is refused: no lane is that narrow (``_lanes_apart``).

With ``follow_ahead_m`` the view goes on beyond ``view_ahead_m``: the vote weighs only the rows
within it, and ``follow_ahead`` follows each line found along its paint beyond.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from ..fit import joined_fit, least_squares_poly
from ..params import LinesConfig
from .trace import ViewLine, trace_line


@dataclass(frozen=True)
class Candidate:
    """A straight line the vote weighed: where it lies in the view (``x0_px`` on the bottom row,
    ``slope`` px across per px along), the metres of paint that voted for it beyond the mean of
    the lines of its slope (``paint_m``), the line fitted on
    the runs near it (None with fewer than 3) and why it is not reported ("" when it is)."""

    x0_px: float
    slope: float
    paint_m: float
    line: ViewLine | None
    refused: str = ""


def run_centres(binary: np.ndarray, max_width_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows and centre columns of the horizontal runs of a 0/255 mask no wider than
    ``max_width_px``, row by row from the top.

    Examples
    --------
    >>> m = np.zeros((2, 10), np.uint8); m[0, 2:5] = 255; m[1, 0:9] = 255
    >>> run_centres(m, 4)
    (array([0]), array([3.]))
    """
    on = (binary > 0).astype(np.int8)
    edges = np.diff(np.pad(on, ((0, 0), (1, 1))), axis=1)
    rs, starts = np.nonzero(edges == 1)
    _, ends = np.nonzero(edges == -1)  # row-major order: each run's end follows its start
    narrow = (ends - starts) <= max_width_px
    return rs[narrow], (starts[narrow] + ends[narrow] - 1) / 2.0


def _votes(t: np.ndarray, xc: np.ndarray, slopes: np.ndarray, bin_px: float, width: int,
           weights: np.ndarray | None = None) -> np.ndarray:
    """Return the vote table (slope, x0 bin): how many run centres lie on each straight line
    beyond the mean of the lines of that slope."""
    n_bins = int(np.ceil(width / bin_px)) + 1
    table = np.zeros((len(slopes), n_bins), np.float32)
    for k, s in enumerate(slopes):
        b = np.rint((xc - s * t) / bin_px).astype(np.int64)
        ok = (b >= 0) & (b < n_bins)
        table[k] = np.bincount(b[ok], None if weights is None else weights[ok], minlength=n_bins)
    # a line straddles two bins: a cell counts its neighbours' votes too
    table = table + np.roll(table, 1, axis=1) * 0.5 + np.roll(table, -1, axis=1) * 0.5
    # texture spread over the road votes for every cell alike: a line is what stands above the
    # mean of its slope's cells
    return np.maximum(table - table.mean(axis=1, keepdims=True), 0.0)


def _headings(table: np.ndarray, slopes: np.ndarray, least: float, spread: float, count: int) -> list[int]:
    """Return up to ``count`` candidate common headings (slope indices), each more than ``spread``
    (px across per px along) from the others: the slopes whose cells above ``least`` hold the
    most votes, strongest first."""
    strong = np.where(table >= least, table, 0.0).sum(axis=1)
    chosen: list[int] = []
    for k in np.argsort(-strong, kind="stable"):
        if strong[k] <= 0 or len(chosen) >= count:
            break
        if all(abs(slopes[k] - slopes[c]) > spread for c in chosen):
            chosen.append(int(k))
    return chosen


def _same_cells(x0s: np.ndarray, slopes: np.ndarray, x0: float, s: float, t_max: float,
                gap_px: float, crossing: bool = True) -> np.ndarray:
    """Return which cells of the vote table (slope, x0) are the same line as (x0, s): nearer than
    ``gap_px`` to it, or (``crossing``) crossing it, anywhere between the bottom of the view (t=0)
    and ``t_max``; without ``crossing``, only those nearer than ``gap_px`` all along."""
    d0 = x0s[None, :] - x0
    d1 = d0 + (slopes[:, None] - s) * t_max
    if not crossing:
        return np.maximum(np.abs(d0), np.abs(d1)) < gap_px
    return (np.minimum(np.abs(d0), np.abs(d1)) < gap_px) | (d0 * d1 < 0)


def seen_span(rows: np.ndarray, residual_px: np.ndarray, tol_px: float, window_px: float,
              height: int) -> tuple[float, float]:
    """Return the first and last view rows (top, bottom) where a voted line is seen, from the
    rows of its runs and their distances from its fit (px).

    The runs within ``tol_px`` of a line are its paint and whatever else lies there: texture, a
    vehicle ahead. Paint hugs the fit; the rest spreads evenly over the tolerance, a quarter of
    it within ``tol_px / 4``. The line is seen in the windows of ``window_px`` rows (from the
    bottom row up) where at least half of its runs lie that close, twice the share of runs spread
    evenly, and its span runs from the first to the last such run; ``window_px`` 0, or no such
    window: every run's row.

    Examples
    --------
    Paint on rows 40-99; on rows 0-39 (a vehicle ahead) runs spread over the tolerance:

    >>> rows = np.arange(100.0)
    >>> residual = np.where(rows < 40, np.tile([-10.0, -5.0, 5.0, 10.0], 25), 0.0)
    >>> seen_span(rows, residual, 12.0, 20, 100)
    (40.0, 99.0)
    """
    if window_px > 0:
        tight = np.abs(residual_px) <= tol_px / 4
        window = ((height - 1 - rows) // max(1.0, round(window_px))).astype(np.int64)
        runs = np.bincount(window)
        close = np.bincount(window, tight.astype(np.float64))
        seen = tight & (close[window] >= 0.5 * runs[window])
        if seen.any():
            return float(rows[seen].min()), float(rows[seen].max())
    return float(rows.min()), float(rows.max())


def _fit(t: np.ndarray, xc: np.ndarray, near: np.ndarray, h: int, curved_px: float) -> tuple | None:
    """Return the fit (a, b, c) of x against the view row of the run centres ``near``, with its
    robust scatter (px), or None when too few."""
    if np.count_nonzero(near) < 3:
        return None
    y = (h - 1) - t[near]
    x = xc[near]
    degree = 2 if np.ptp(y) >= curved_px else 1
    a, b, c = least_squares_poly(y, x, degree, float(h))
    scatter = 1.4826 * float(np.median(np.abs(x - np.polyval((a, b, c), y))))
    return (a, b, c), scatter


def vote_candidates(binary: np.ndarray, config: LinesConfig = LinesConfig(), xm_per_px: float = 0.016,
                    ym_per_px: float = 0.1, car_x_px: float | None = None,
                    row_weights: np.ndarray | None = None, strength: np.ndarray | None = None) -> list[Candidate]:
    """Return every straight line the vote weighs in a bird's-eye lane mask, strongest first, each
    with its fit and why it is refused ("" for a reported line): those of the heading kept, then
    the tight lines of other headings reported with them (``tight_scatter_m``).

    Each distinct line is weighed once: the strongest cell left is weighed, then the cells that
    are the same line as it (nearer than ``min_gap_fraction`` of a lane width, or crossing it,
    within the view) are cleared; at most ``4 * max_lines`` lines are weighed. The weighing goes
    down to half of ``min_peak_m`` of paint, so that a line that narrowly misses says so.
    Refusals: too little paint, more than ``max_lines``, fewer than 3 runs near it, paint
    spanning less than ``min_span_m``, runs scattering more than ``max_scatter_m`` around the
    fit, a line under the car whose paint starts ahead (``min_offset_m``, ``near_paint_m``), or a
    line nearer than ``min_lane_fraction`` of a lane beside the line inside it.

    Parameters
    ----------
    binary, config, xm_per_px, ym_per_px : as for ``vote_lines``.
    car_x_px : the car's centre line in the view (px); None: the view's middle column.
    row_weights : how much each row of the view counts in the vote (None: every row alike).
    strength : how much a run centred on each pixel of the view counts in the vote, 0-1
        (``lines.detect.paint_strength``; None: every run alike).

    Examples
    --------
    >>> m = np.zeros((400, 600), np.uint8)
    >>> m[:, 110:118] = 255; m[360:, 300:308] = 255            # a 40 m line; a 4 m mark
    >>> [(round(c.paint_m, 1), c.refused) for c in vote_candidates(m, LinesConfig(min_span_m=5), 0.02, 0.1)]
    [(38.9, ''), (2.9, 'its paint spans 3.9 m along the road, less than min_span_m 5.0 m')]
    """
    h, w = binary.shape[:2]
    rows, xc = run_centres(binary, config.max_paint_width_m / xm_per_px)
    if len(rows) < 3:
        return []
    t = (h - 1) - rows.astype(np.float64)  # view rows ahead of the bottom row
    max_slope = config.max_slope * ym_per_px / xm_per_px  # px across per px along
    tol = config.vote_tolerance_m / xm_per_px
    slopes = np.arange(-max_slope, max_slope + 1e-9, max(tol / 2, 1.0) / max(h, 1))
    weights = None if row_weights is None else row_weights[rows]
    if strength is not None:
        clear = strength[rows, np.clip(np.rint(xc).astype(np.int64), 0, w - 1)]
        weights = clear if weights is None else weights * clear
    table = _votes(t, xc, slopes, tol, w, weights)
    least = config.min_peak_m / ym_per_px
    spread = config.heading_spread * ym_per_px / xm_per_px
    votes = _Votes(rows, t, xc, slopes, np.arange(table.shape[1]) * tol, h, tol,
                   w / 2.0 if car_x_px is None else float(car_x_px))
    every = []
    for k in _headings(table, slopes, least, spread, config.headings) or [None]:
        kept = table.copy()
        if k is not None:  # None: no slope holds a strong cell, every one is weighed
            kept[np.abs(slopes - slopes[k]) > spread] = 0.0
        every.append(_weigh(kept, votes, config, xm_per_px, ym_per_px))
    best = max(every, key=lambda found: sum(c.paint_m for c in found if not c.refused))  # the first of equals
    return _tight_others(best, every, config, xm_per_px, votes)


def _tight_others(best: list[Candidate], every: list[list[Candidate]], config: LinesConfig, xm_per_px: float,
                  v: _Votes) -> list[Candidate]:
    """Return the kept heading's candidates ``best`` with the reported lines of the other headings
    (``every``, in turn) that are tighter than ``tight_scatter_m`` and stay ``min_gap_fraction``
    of a lane from every reported line without crossing one (on rows 10 apart), up to
    ``max_lines`` in all; ``_lanes_apart`` then weighs them with the rest."""
    if config.tight_scatter_m <= 0 or len(every) < 2:
        return best
    gap = config.min_gap_fraction * config.lane_width_m / xm_per_px
    ts = np.arange(0.0, v.height, 10.0)
    out = list(best)
    kept = [c.line.x_at(ts) for c in best if not c.refused]  # each reported line's x on those rows
    for found in every:
        if found is best:
            continue
        for c in found:
            tight = not c.refused and c.line.scatter_px * xm_per_px < config.tight_scatter_m
            if not tight or len(kept) >= config.max_lines:
                continue
            xs = c.line.x_at(ts)
            if all(np.abs(xs - k).min() >= gap and not np.any(np.diff(np.sign(xs - k))) for k in kept):
                out.append(c)
                kept.append(xs)
    return _lanes_apart(out, config, xm_per_px, v)


class _Votes(NamedTuple):
    """The run centres (rows, ``t`` ahead of the bottom row, x) and the vote table's axes."""
    rows: np.ndarray
    t: np.ndarray
    xc: np.ndarray
    slopes: np.ndarray
    x0s: np.ndarray
    height: int
    tol: float
    car_x: float


def _weigh(table: np.ndarray, v: _Votes, config: LinesConfig, xm_per_px: float,
           ym_per_px: float) -> list[Candidate]:
    """Return the lines of a vote table, strongest first, each weighed once with why it is refused."""
    least = config.min_peak_m / ym_per_px
    gap = config.min_gap_fraction * config.lane_width_m / xm_per_px
    curved = config.curved_span_m / ym_per_px
    found: list[Candidate] = []
    reported = 0
    while len(found) < 4 * config.max_lines:
        k, b = divmod(int(np.argmax(table)), table.shape[1])
        paint = float(table[k, b])
        if paint < least / 2:
            break
        x0, s = float(v.x0s[b]), float(v.slopes[k])
        near = np.abs(v.xc - (x0 + s * v.t)) <= v.tol
        fitted = _fit(v.t, v.xc, near, v.height, curved)
        if config.follow_bends and fitted is not None:
            near, fitted = _followed(v, near, fitted, s, config, xm_per_px, ym_per_px)
        line = None
        if fitted is not None:
            y_near = v.rows[near].astype(np.float64)
            top, bottom = seen_span(y_near, v.xc[near] - np.polyval(fitted[0], y_near), v.tol,
                                    config.seen_window_m / ym_per_px, v.height)
            line = ViewLine(fitted[0], top, bottom, int(near.sum()), fitted[1])
        why = _refusal(paint * ym_per_px, line, reported, config, xm_per_px, ym_per_px, v)
        # weighed once (``refused_clear_crossings``: a refused line is no line, and the lines
        # that only cross it may stay)
        crossing = not why or config.refused_clear_crossings
        table[_same_cells(v.x0s, v.slopes, x0, s, v.height - 1, gap, crossing=crossing)] = 0.0
        reported += not why
        found.append(Candidate(x0, s, paint * ym_per_px, line, why))
    return _lanes_apart(found, config, xm_per_px, v)


def _lanes_apart(found: list[Candidate], config: LinesConfig, xm_per_px: float, v: _Votes) -> list[Candidate]:
    """Return the candidates with each reported line refused that lies nearer than
    ``min_lane_fraction`` of a lane width, on the view's bottom row, to the reported line kept
    next to it towards the car on its side (the lines nearest the car first)."""
    least_px = config.min_lane_fraction * config.lane_width_m / xm_per_px
    if least_px <= 0:
        return found
    bottom = v.height - 1.0
    at = {i: float(c.line.x_at(bottom)) - v.car_x for i, c in enumerate(found) if not c.refused}
    out = list(found)
    for side in (-1.0, 1.0):
        kept = None
        for i in sorted((i for i, x in at.items() if x * side >= 0), key=lambda i: abs(at[i])):
            if kept is not None and abs(at[i] - kept) < least_px:
                out[i] = replace(found[i], refused=(
                    f"it runs {abs(at[i] - kept) * xm_per_px:.1f} m beside the line inside it, less than "
                    f"min_lane_fraction {config.min_lane_fraction:.2f} of a lane: no lane is that narrow"))
            else:
                kept = at[i]
    return out


def _followed(v: _Votes, near: np.ndarray, voted: tuple, s: float, config: LinesConfig, xm_per_px: float,
              ym_per_px: float) -> tuple[np.ndarray, tuple]:
    """Return the run centres of a voted line (``near``, fitted as ``voted``), followed where it
    bends, with their fit.

    A line bends away from the straight line the vote found (a curve of the road, the lens): it
    is traced by windows (``lines.trace.trace_line``) from its paint in the near half of the view. The
    traced runs replace the voted ones when their fit scatters less, over at least the same span
    of the road, and they hold at least half of the voted runs of the near half (the trace has
    not wandered off to other paint).
    """
    lower = near & (v.t < v.height / 2)
    if np.count_nonzero(lower) < 3:
        return near, voted
    curved = config.curved_span_m / ym_per_px
    start = np.flatnonzero(lower)[np.count_nonzero(lower) // 2]  # a run of its paint midway up
    y0 = float(v.rows[start])
    win = max(2, int(round(config.window_m / ym_per_px)))
    idx = trace_line((v.height - 1) - v.t, v.xc, float(v.xc[start]), y0, v.height, win,
                     v.tol, config.grow_margin_m / xm_per_px, config.max_empty_windows,
                     max(3, config.min_window_pixels // 3),
                     config.max_slope * ym_per_px / xm_per_px + 0.5, slope=-s)
    traced = np.zeros_like(near)
    traced[idx] = True
    followed = _fit(v.t, v.xc, traced, v.height, curved)
    if followed is None:
        return near, voted
    tighter = followed[1] < voted[1]
    as_long = np.ptp(v.rows[traced]) >= np.ptp(v.rows[near])
    same_paint = np.count_nonzero(traced & lower) >= np.count_nonzero(lower) / 2
    return (traced, followed) if tighter and as_long and same_paint else (near, voted)


def _refusal(paint_m: float, line: ViewLine | None, reported: int, config: LinesConfig,
             xm_per_px: float, ym_per_px: float, v: _Votes) -> str:
    """Return why a weighed line is not reported ("" when it is)."""
    if paint_m < config.min_peak_m:
        return f"only {paint_m:.1f} m of paint votes for it, less than min_peak_m {config.min_peak_m:.1f} m"
    if reported >= config.max_lines:
        return f"{config.max_lines} stronger lines are reported already (max_lines)"
    if line is None:
        return "fewer than 3 runs of paint lie near it"
    span_m = (line.y_bottom_px - line.y_top_px) * ym_per_px
    if span_m < config.min_span_m:
        return f"its paint spans {span_m:.1f} m along the road, less than min_span_m {config.min_span_m:.1f} m"
    if line.scatter_px * xm_per_px > config.max_scatter_m:
        return (f"its paint scatters {line.scatter_px * xm_per_px:.2f} m about the fit, more than "
                f"max_scatter_m {config.max_scatter_m:.2f} m")
    bottom = v.height - 1.0
    off_m = (float(line.x_at(bottom)) - v.car_x) * xm_per_px
    start_m = (bottom - line.y_bottom_px) * ym_per_px
    if abs(off_m) < config.min_offset_m and start_m > config.near_paint_m:
        return (f"it runs {abs(off_m):.1f} m from the car's centre line (min_offset_m "
                f"{config.min_offset_m:.1f} m) but its paint starts {start_m:.1f} m ahead: a vehicle's edge")
    return ""


def follow_ahead(lines: list[ViewLine], binary: np.ndarray, first_row: int, config: LinesConfig,
                 xm_per_px: float, ym_per_px: float) -> list[ViewLine | None]:
    """Return, for each line found within ``view_ahead_m``, its paint followed beyond the search's
    first row ``first_row`` (``LinesConfig.follow_ahead_m``) towards the top of the view, as a
    line of its own over those rows (None where no paint goes on).

    Each line is traced by windows (``lines.trace.trace_line``: ``window_m`` high,
    ``vote_tolerance_m`` either side, ``max_empty_windows``) from its first window in the search's
    rows, at the slope of its fit there. At least ``min_window_pixels // 3`` runs traced beyond
    are fitted joined to the line over the search's first ``window_m`` (``fit.joined_fit``):
    the far part continues the line without moving it where it was found. It is kept when the
    traced runs scatter about it by at most ``max_scatter_m``; it is seen from the furthest
    traced run down to ``first_row``.

    Examples
    --------
    A straight line with paint from the bottom of a 300-row view to row 40, searched from row 150
    on:

    >>> m = np.zeros((300, 400), np.uint8); m[40:, 198:203] = 255
    >>> voted = ViewLine((0.0, 0.0, 200.0), 150.0, 299.0, 150, 0.0)
    >>> far, = follow_ahead([voted], m, 150, LinesConfig(), 0.02, 0.1)
    >>> far.y_top_px, far.y_bottom_px, round(float(far.x_at(60.0)), 6)
    (40.0, 150.0, 200.0)
    """
    h = binary.shape[0]
    win = max(2, int(round(config.window_m / ym_per_px)))
    # the rows beyond and the first window searched, where each trace starts: the trace upwards
    # reads nothing below them
    reach = min(h, first_row + win)
    rows, xc = run_centres(binary[:reach], config.max_paint_width_m / xm_per_px)
    if len(rows) < 3:
        return [None] * len(lines)
    ys = rows.astype(np.float64)
    tol = config.vote_tolerance_m / xm_per_px
    least = max(3, config.min_window_pixels // 3)
    reference_rows = np.arange(first_row, reach, dtype=np.float64)
    y0 = first_row + win / 2.0
    out: list[ViewLine | None] = []
    for line in lines:
        a, b, _ = line.coeffs_px
        idx = trace_line(ys, xc, float(line.x_at(y0)), y0, reach, win, tol, 0.0, config.max_empty_windows,
                         least, config.max_slope * ym_per_px / xm_per_px + 0.5, slope=float(2 * a * y0 + b))
        far = idx[ys[idx] < first_row]
        if len(far) < least:
            out.append(None)
            continue
        coeffs = joined_fit(ys[far], xc[far], line.coeffs_px, reference_rows, h)
        scatter = 1.4826 * float(np.median(np.abs(xc[far] - np.polyval(coeffs, ys[far]))))
        out.append(None if scatter * xm_per_px > config.max_scatter_m else
                   ViewLine(coeffs, float(ys[far].min()), float(first_row), len(far), scatter))
    return out


def vote_lines(binary: np.ndarray, config: LinesConfig = LinesConfig(), xm_per_px: float = 0.016,
               ym_per_px: float = 0.1) -> list[ViewLine]:
    """Return every line of a bird's-eye lane mask found by a vote over straight lines, left to right.

    The lines are the candidates of ``vote_candidates`` that are not refused, each taken to go on
    ``extend_m`` beyond its paint at either end, within the view.

    Parameters
    ----------
    binary : the 0/255 lane mask of the lines view (``lines.view.LinesView``).
    config : the search in metres (``LinesConfig``: ``max_paint_width_m``, ``vote_tolerance_m``,
        ``max_slope``, ``heading_spread``, ``min_gap_fraction``, ``min_peak_m``, ``min_span_m``,
        ``max_scatter_m``, ``curved_span_m``, ``max_lines``, ``extend_m``).
    xm_per_px, ym_per_px : metres per view pixel across and along the road.

    Examples
    --------
    Two dashed lines 3.7 m apart, one of them tilted, in a view of 0.02 m x 0.1 m pixels:

    >>> m = np.zeros((400, 600), np.uint8)
    >>> for y in range(400):
    ...     if y % 60 < 30:                                # 3 m dashes, 3 m gaps
    ...         m[y, 110:118] = 255                        # straight, centre 113.5 px
    ...         x = int(round(485 + 0.25 * (399 - y)))     # 0.05 m across per m along
    ...         m[y, x - 4:x + 4] = 255                    # centre x - 0.5 px
    >>> lines = vote_lines(m, LinesConfig(min_span_m=5, extend_m=0), 0.02, 0.1)
    >>> [round(float(line.x_at(399)), 1) for line in lines]
    [113.5, 484.5]
    """
    return reported(vote_candidates(binary, config, xm_per_px, ym_per_px), config, binary.shape[0], ym_per_px)


def reported(candidates: list[Candidate], config: LinesConfig, height_px: int, ym_per_px: float) -> list[ViewLine]:
    """Return the lines of the candidates that are not refused, left to right, each taken to go
    on ``config.extend_m`` beyond its paint at either end within a view ``height_px`` rows high."""
    lines = [c.line for c in candidates if not c.refused]
    if config.extend_m > 0:
        more = config.extend_m / ym_per_px
        lines = [replace(line, y_top_px=max(0.0, line.y_top_px - more),
                         y_bottom_px=min(height_px - 1.0, line.y_bottom_px + more)) for line in lines]
    return sorted(lines, key=lambda line: float(line.x_at(height_px - 1)))
