"""The records the lane stages share: ``LineFit`` (one fitted line), ``Window`` (one sliding
window), ``LaneSearch`` (a search's pixels, windows and fits) and ``LaneMeasurement`` (the lane
in metres). Coordinates are bird's-eye pixels, x right, y down, a line being
``x = a*y**2 + b*y + c`` (``fit``). Searches fill them; checks, ``roads`` and ``lines`` read them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


NEAR_SHARE = 0.02  # share of a line's pixels nearest the car left out of where it reaches (LineFit.gap_px)


def near_row_px(ys: np.ndarray) -> float:
    """Return the row all but ``NEAR_SHARE`` of the pixels on rows ``ys`` lie above (how near the car a
    line's pixels reach): ``np.quantile(ys, 1 - NEAR_SHARE)``, to the bit. The two rows it lies
    between are read from the count of pixels per row when the rows are integers from 0 (no partial
    sort), then interpolated as ``np.quantile`` does.

    Examples
    --------
    >>> near_row_px(np.arange(101)) == float(np.quantile(np.arange(101), 1 - NEAR_SHARE))
    True
    """
    ys = np.asarray(ys)
    n = len(ys)
    at = (n - 1) * (1.0 - NEAR_SHARE)
    if at >= n - 1:
        return float(ys.max())
    i = math.floor(at)
    t = at - i
    if ys.dtype.kind in "iu" and ys.min() >= 0:
        below = np.cumsum(np.bincount(ys))  # pixels on each row and the rows above it
        a, b = (int(v) for v in np.searchsorted(below, (i, i + 1), side="right"))
    else:
        part = np.partition(ys, (i, i + 1))
        a, b = part[i], part[i + 1]
    diff = b - a
    return float(a + diff * t) if t < 0.5 else float(b - diff * (1 - t))


@dataclass(frozen=True)
class LineFit:
    """One fitted line: pixel coefficients (a, b, c) of x = f(y), or not found with a reason.

    ``scatter_px``: the RMS horizontal distance (px) of its pixels from the fit (0 when not fitted to
    pixels, e.g. a tracked line). ``stripe_scatter_px``: their RMS distance from the nearer of two
    parallel stripes (``two_stripes``), measured by the search where they scatter like a double line
    (``scatter_px`` above a quarter of ``SearchConfig.double_line_px``) without being narrowed, and
    split into stripes of at least a fifth of them each; else None (the texture rule reads
    ``scatter_px``). ``gap_px``: the rows from the view's bottom row (the car's end) to the row all
    but ``NEAR_SHARE`` of its pixels lie above, so a few stray pixels near the car do not count as
    reaching it (0 when not fitted to pixels).
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
            return polyval2(self.coeffs_px, y)  # np.polyval's values, without its array of zeros
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
    # faded out, ``roads.proposers.Shoulder``), not seen
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


def polyval2(coeffs, y: np.ndarray) -> np.ndarray:
    """Return ``np.polyval`` of a second-order ``coeffs`` (a, b, c) on ``y`` (the same values:
    Horner's rule, without polyval's array of zeros)."""
    a, b, c = coeffs
    return (a * y + b) * y + c
