"""The asphalt edge of a side without paint, and the stretch of road the camera sees ahead.

A verge (grass, dirt, gravel) differs from the road surface in saturation or grain, both free of
the light's brightness (``verge_features``): ``road_edge`` finds the road-to-verge step row by row
on a shrunk bird's-eye view (``verge_grid``) and fits it like a line. ``road_view_top_px`` ends the
look-ahead where the lane's interior stops looking like the road near the car (a crest, a vehicle
ahead).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import cv2
import numpy as np

from ..fit import fit_line
from ..params import EdgeConfig, LaneChecks, SearchConfig
from ..records import LineFit


TRACE_START = 4  # edge points the trace starts from and extends by a straight line (``road_edge``)
DARK_V = 80.0  # saturation below this value (V, 0-255) is measured against it: a shadow's tint is not colour


def saturation(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the saturation ((max - min) / max of R, G, B, 0-1, the max taken as at least
    ``DARK_V``: the tint of a shadow or the noise of a dark pixel is not colour) and the value
    (max of R, G, B, 0-255) of each pixel of an RGB image, float32."""
    r, g, b = cv2.split(np.ascontiguousarray(rgb))
    hi = cv2.max(cv2.max(r, g), b).astype(np.float32)
    return (hi - cv2.min(cv2.min(r, g), b)) / np.maximum(hi, DARK_V), hi


def verge_features(rgb: np.ndarray, grain: bool = True) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Return the per-pixel features that tell a verge from the road surface in a (shrunk)
    bird's-eye image: saturation (``saturation``: the bluish tint of a shadow or the noise of a
    dark pixel is not colour), grain (local std / mean of V over 3 x 3 px; None without
    ``grain``, for an edge found by saturation alone) and where the camera
    sees (not black). Both are free of the light's brightness, so a shadow on
    the road, a repaved strip, a tar seam and a concrete barrier (grey and smooth like the road)
    look like road; grass and dirt differ in saturation, gravel in grain."""
    sat, hi = saturation(rgb)
    if not grain:
        return sat, None, hi > 0
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
    grain: np.ndarray | None  # None where not measured (``EdgeConfig.min_texture_ratio`` 0)
    seen: np.ndarray
    row0: int
    height_px: int
    scale: int


def verge_grid(bird: np.ndarray, scale: int, row0_px: int = 0, height_px: int | None = None,
               sampled: bool = False, cells: tuple[int, int, int, int] | None = None,
               grain: bool = True) -> VergeGrid:
    """Return the ``VergeGrid`` of a bird's-eye image, or of its rows from ``row0_px`` (a multiple
    of ``scale``) down when ``bird`` holds only those (``height_px``: the whole view's height).
    ``sampled``: ``bird`` holds one row of each ``scale`` rows (``grid_rows_px``), shrunk only
    across (a quarter of the remap and of the features for a grid read on every frame).
    ``cells``: (first row, last row + 1, first column, last column + 1) of the grid, the only
    cells measured, the others left unseen and 0 (``road_edge`` measures what it reads); for an
    image whose size is a multiple of ``scale`` each way, where a cell is the mean of its
    ``scale`` x ``scale`` pixels whichever cells are shrunk with it. ``grain``: the grain is measured
    (``verge_features``; ``road_edge`` reads it only with ``EdgeConfig.min_texture_ratio``)."""
    h, w = bird.shape[:2]
    rows = h if sampled else h // scale
    if cells is not None:
        sat, texture, seen = _cell_features(bird, scale, cells, grain)
    else:
        small = cv2.resize(bird, (w // scale, rows), interpolation=cv2.INTER_AREA) if scale > 1 else bird
        sat, texture, seen = verge_features(small, grain)
    return VergeGrid(sat, texture, seen, row0_px // scale, h if height_px is None else height_px, scale)


def _cell_features(bird: np.ndarray, scale: int, cells: tuple[int, int, int, int], grain: bool
                   ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Return ``verge_features`` of the whole grid of ``bird`` measured on ``cells`` only (see
    ``verge_grid``), 0 and unseen elsewhere: those cells, and with ``grain`` one more around them
    (the grain's 3 x 3 blur reads them; its sums of whole levels are exact in any order), are
    shrunk and measured, so each cell measured is the whole grid's."""
    h, w = bird.shape[0] // scale, bird.shape[1] // scale
    r0, r1, c0, c1 = cells
    out = [np.zeros((h, w), np.float32), np.zeros((h, w), np.float32) if grain else None,
           np.zeros((h, w), bool)]
    if r1 <= r0 or c1 <= c0:
        return out[0], out[1], out[2]
    m = 1 if grain else 0
    a0, a1, b0, b1 = max(0, r0 - m), min(h, r1 + m), max(0, c0 - m), min(w, c1 + m)
    crop = bird[a0 * scale:a1 * scale, b0 * scale:b1 * scale]
    small = cv2.resize(crop, (b1 - b0, a1 - a0), interpolation=cv2.INTER_AREA) if scale > 1 else crop
    for whole, part in zip(out, verge_features(small, grain)):
        if whole is not None:
            whole[r0:r1, c0:c1] = part[r0 - a0:r1 - a0, c0 - b0:c1 - b0]
    return out[0], out[1], out[2]


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
    once (the same sums in the same order, so the same columns).

    A row whose verge score stays below ``min_outer`` by more than the rounding of its float32
    running sums (n**2 * 2**-24 / ``win`` for n columns, at most 1 each) has no outer window that
    reaches it, and is left out before its sums (on a road without a verge in view, most rows)."""
    lo, hi = a - pad[0], b + pad[1]
    length = hi - lo
    keep = b > a
    if not keep.any():
        return np.zeros(0, int), np.zeros(0)
    offs = np.arange(int(length[keep].max()))
    inside = offs[None, :] < length[:, None]
    cols = (lo[:, None] + offs[None, :]) if sign > 0 else (hi[:, None] - 1 - offs[None, :])
    cols = np.clip(cols, 0, sat.shape[1] - 1)
    cells = rows[:, None] * sat.shape[1] + cols  # flat indices: ``take`` gathers them fastest
    score = np.clip((sat.take(cells) - road_sat[:, None]) / config.min_saturation_step, 0, 1)
    if config.min_texture_ratio > 0:
        score = np.maximum(score, np.clip((grain.take(cells) / road_grain[:, None] - 1.0)
                                          / config.min_texture_ratio, 0, 1))
    score = np.where(inside, score, 0.0)
    slack = (len(offs) + 1) ** 2 * 2.0 ** -24 / win
    keep &= score.max(axis=1) >= config.min_outer - slack
    keep[keep] &= np.all(seen.take(cells[keep]) | ~inside[keep], axis=1)
    if not keep.any():
        return np.zeros(0, int), np.zeros(0)
    idx_rows = np.flatnonzero(keep)
    score, length = score[keep], length[keep]
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
    k = config.scale if grid is None else grid.scale
    shape = (k, 0, bird.shape[0] // k, bird.shape[1] // k) if grid is None else \
        (k, grid.row0, grid.sat.shape[0], grid.sat.shape[1])
    s = _edge_search(shape, other, side, xm_per_px, ym_per_px, checks, config, top_px, guide_px, range_m,
                     bottom_px)
    if grid is None:  # without a trace, only the cells read are measured (``_cells_read``)
        whole = s.trace_half > 0 or bird.shape[0] % k or bird.shape[1] % k
        grid = verge_grid(bird, k, cells=None if whole else _cells_read(s),
                          grain=config.min_texture_ratio > 0)
    refs = _road_references(grid, s)
    if s.trace_half <= 0:  # every row at once: its own road surface, its range from the guide
        ys, xs = _edge_points_every_row(grid, s, refs, config)
    else:
        ys, xs = _edge_points_traced(grid, s, refs, config)
    return _fit_edge(ys, xs, side, grid, top_px, bottom_px, config)


class _EdgeSearch(NamedTuple):
    """What ``road_edge`` reads on the shrunk grid's rows, from the bottom up (``_edge_search``)."""

    rows: np.ndarray       # the shrunk grid's rows, from the bottom up
    yf: np.ndarray         # the full view's rows at the shrunk rows' centres
    x_line: np.ndarray     # the other line's x (px) on them
    stretch: np.ndarray    # px across per metre along the other line's normal
    x_guide: np.ndarray    # the guide's x (px) on them
    stretch_g: np.ndarray  # px across per metre along the guide's normal
    sign: float            # +1: the edge lies right of the other line; -1: left
    near_m: float          # the range (m along the normal from the guide) searched for the edge
    far_m: float
    win: int               # the inner window (shrunk px, ``step_m``); the outer one is twice as wide
    pad: tuple[int, int]   # the columns the windows reach beyond a search range, inside and outside
    trace_half: float      # half the width (shrunk px) a traced row is searched in (0: no trace)
    gap_rows: int          # rows without a point that end a trace
    ref0: np.ndarray       # the first and last-plus-one column (shrunk px) of each row's road reference
    ref1: np.ndarray
    a: np.ndarray          # the first and last column (shrunk px) of each row's range from the guide
    b: np.ndarray


def _edge_search(shape: tuple[int, int, int, int], other: LineFit, side: str, xm_per_px: float,
                 ym_per_px: float, checks: LaneChecks, config: EdgeConfig, top_px: int, guide_px, range_m,
                 bottom_px: int | None) -> _EdgeSearch:
    """Return the rows ``road_edge`` reads (from ``top_px`` to ``bottom_px``), the other line and
    the guide on them, and its windows and columns in shrunk pixels, on a grid of ``shape``: its
    scale, first row (``VergeGrid.row0``), rows and columns."""
    k, row0, n_rows, sw = shape
    sh = row0 + n_rows
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

    near_m, far_m = (checks.min_width_m - 0.2, checks.max_width_m + 0.2) if range_m is None else range_m
    win = max(2, int(round(config.step_m / xm_per_px / k)))
    pad = (win, 2 * win) if sign > 0 else (2 * win, win)  # the outer window is 2 x step_m
    stretch, stretch_g = stretch_of(np.asarray(other.coeffs_px, float)), stretch_of(guide)
    # the road reference: from 0.3 x the least lane width beyond the other line to 0.3 m short of it
    near = np.round((x_line + sign * 0.3 * checks.min_width_m * stretch) / k).astype(int)
    far = np.round((x_line + sign * (checks.min_width_m - 0.3) * stretch) / k).astype(int)
    # the edge's range from the guide, the windows inside the grid
    x0, x1 = x_guide + sign * near_m * stretch_g, x_guide + sign * far_m * stretch_g
    a, b = (x0 // k).astype(int), np.ceil(x1 / k).astype(int)
    return _EdgeSearch(rows, yf, x_line, stretch, x_guide, stretch_g, sign, near_m, far_m, win, pad,
                       config.trace_margin_m / xm_per_px / k,
                       max(1, int(round(config.trace_gap_m / ym_per_px / k))),
                       np.maximum(0, np.minimum(near, far)), np.minimum(sw, np.maximum(near, far) + 1),
                       np.maximum(np.minimum(a, b), pad[0]), np.minimum(np.maximum(a, b), sw - pad[1]))


def _cells_read(s: _EdgeSearch) -> tuple[int, int, int, int]:
    """Return the grid cells (first row, last row + 1, first column, last column + 1) that
    ``road_edge`` reads without a trace: its rows, and on them each row's road reference and its
    range from the guide with the windows' reach beyond it."""
    if not len(s.rows):
        return 0, 0, 0, 0
    c0 = min(int(s.ref0.min()), int(s.a.min()) - s.pad[0])
    c1 = max(int(s.ref1.max()), int(s.b.max()) + s.pad[1])
    return int(s.rows.min()), int(s.rows.max()) + 1, max(0, c0), c1


def _road_references(grid: VergeGrid, s: _EdgeSearch) -> np.ndarray:
    """Return the road surface of each row, (saturation, grain): the medians of the row between
    the other line and the nearest the edge may be, for all rows at once; NaN where a row's
    window is shorter than the inner window or not all seen, and the grain NaN where the grid
    has none."""
    row0, sw = grid.row0, grid.sat.shape[1]
    rows, win = s.rows, s.win
    p0, p1 = s.ref0, s.ref1
    span = p1 - p0
    refs = np.full((len(rows), 2), np.nan)
    if len(rows) and span.max() > 0:
        offs = np.arange(int(span.max()))
        inside = offs[None, :] < span[:, None]
        cols = np.clip(p0[:, None] + offs[None, :], 0, sw - 1)
        cells = (rows - row0)[:, None] * sw + cols  # flat indices: ``take`` gathers them fastest
        ok = (span >= win) & np.all(grid.seen.take(cells) | ~inside, axis=1)
        if ok.any():
            lo_i, hi_i = (span[ok] - 1) // 2, span[ok] // 2
            pick = np.arange(int(ok.sum()))
            features = (grid.sat,) if grid.grain is None else (grid.sat, grid.grain)
            for j, feature in enumerate(features):
                vals = np.sort(np.where(inside, feature.take(cells), np.nan)[ok], axis=1)  # NaN last
                refs[ok, j] = (vals[pick, lo_i] + vals[pick, hi_i]) / 2  # np.median's, in float32
    return refs


def _edge_points_every_row(grid: VergeGrid, s: _EdgeSearch, refs: np.ndarray,
                           config: EdgeConfig) -> tuple[np.ndarray, np.ndarray]:
    """Return the edge points (y, x in view px) of every row with a road reference, each searched
    over the range from the guide (``road_edge`` without a trace)."""
    k, row0 = grid.scale, grid.row0
    use = refs[:, 0] <= config.max_road_saturation  # False where a row has no road reference (NaN)
    a, b = s.a, s.b
    ys, xs = _edge_steps(grid.sat, grid.grain, grid.seen, s.rows[use] - row0, a[use], b[use], s.pad, s.win,
                         s.sign, refs[use, 0].astype(grid.sat.dtype),
                         np.maximum(refs[use, 1], 1e-3).astype(grid.sat.dtype), config)
    ys = s.yf[use][ys] if len(ys) else np.zeros(0)
    return ys, xs * float(k)


def _edge_points_traced(grid: VergeGrid, s: _EdgeSearch, refs: np.ndarray,
                        config: EdgeConfig) -> tuple[np.ndarray, np.ndarray]:
    """Return the edge points (y, x in view px) found row by row from the bottom up, followed
    along the straight line through the last ``TRACE_START`` of them once there are so many
    (``road_edge`` with ``trace_margin_m``)."""
    k, row0, sw = grid.scale, grid.row0, grid.sat.shape[1]
    ys, xs = [], []
    road_sat, road_grain, missed = None, 1e-3, 0
    for i, r in enumerate(s.rows):
        tracing = len(xs) >= TRACE_START
        if not np.isnan(refs[i, 0]):
            if refs[i, 0] > config.max_road_saturation:
                missed += 1
                continue
            road_sat, road_grain = float(refs[i, 0]), max(float(refs[i, 1]), 1e-3)
        elif not tracing or road_sat is None:
            continue
        if tracing:
            if missed > s.gap_rows:
                break  # the edge is no longer seen: the trace ends
            last_y, last_x = np.asarray(ys[-TRACE_START:]) / k, np.asarray(xs[-TRACE_START:]) / k
            slope, at = np.polyfit(last_y, last_x, 1)
            centre = slope * r + at
            half = s.trace_half + missed
            a, b = int(np.floor(centre - half)), int(np.ceil(centre + half))
        else:
            x0 = s.x_guide[i] + s.sign * s.near_m * s.stretch_g[i]
            x1 = s.x_guide[i] + s.sign * s.far_m * s.stretch_g[i]
            a, b = sorted((int(x0 // k), int(np.ceil(x1 / k))))
        a, b = max(a, s.pad[0]), min(b, sw - s.pad[1])
        if b <= a or not grid.seen[r - row0, a - s.pad[0]:b + s.pad[1]].all():
            missed += 1
            continue
        grain_row = None if grid.grain is None else grid.grain[r - row0]
        x = _edge_step(grid.sat[r - row0], grain_row, a, b, s.pad, s.win, s.sign, road_sat, road_grain, config)
        if x is None:
            missed += 1
            continue
        missed = 0
        ys.append(s.yf[i])
        xs.append(float(x * k))
    return np.asarray(ys, float), np.asarray(xs, float)


def _fit_edge(ys: np.ndarray, xs: np.ndarray, side: str, grid: VergeGrid, top_px: int,
              bottom_px: int | None, config: EdgeConfig) -> tuple[LineFit, np.ndarray]:
    """Return ``road_edge``'s robust fit of the edge points and the points it kept ((N, 2) x, y)."""
    k, h = grid.scale, grid.height_px
    order = np.argsort(ys, kind="stable")  # the points from the view's top down
    ys, xs = ys[order], xs[order]
    depth = (h if bottom_px is None else bottom_px + 1) - top_px
    fit_cfg = SearchConfig(min_line_pixels=config.min_points, min_span_fraction=0.3,
                           min_found_span_fraction=config.min_span_fraction * depth / h,
                           trim_outliers_pct=config.trim_outliers_pct)
    fit = fit_line(ys, xs, h, fit_cfg, missing=f"no {side} asphalt edge (no road-to-verge step)")
    for _ in range(3):  # refit without the points far from the fit (robust: a patch, a shadow)
        if not fit.found:
            break
        res = np.abs(xs - fit.x_at(ys))
        keep = res <= max(2.0 * k, 3.0 * 1.4826 * float(np.median(res)))
        if keep.all():
            break
        ys, xs = ys[keep], xs[keep]
        fit = fit_line(ys, xs, h, replace(fit_cfg, trim_outliers_pct=0.0),
                       missing=f"no {side} asphalt edge (no road-to-verge step)")
    if not fit.found:
        fit = replace(fit, reason=f"{side} asphalt edge: {fit.reason}")
    return fit, np.column_stack([xs, ys])
