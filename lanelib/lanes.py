"""Lane-pixel search in the bird's-eye mask, polynomial fits, curvature, offset and lane width.

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

from dataclasses import dataclass, field

import cv2
import numpy as np

RADIUS_MAX_M = 100_000.0


@dataclass(frozen=True)
class SearchConfig:
    """Parameters of the lane-pixel search and the fits.

    Parameters
    ----------
    n_windows : sliding windows stacked over the image height.
    margin_px : half width of a sliding window.
    minpix : pixels a window must hold to recentre the next one on their mean x.
    histogram_fraction : lower share of the image whose column sums locate the line bases.
    prior_margin_px : half width of the band searched around a previous fit.
    min_line_pixels : fewer pixels than this and the line is "not found".
    min_span_fraction : pixels must span this share of the image height for a 2nd-order fit;
        below it the line is fitted as a straight line (a = 0).
    min_found_span_fraction : below this share of the height the line is "not found".
    """

    n_windows: int = 9
    margin_px: int = 80
    minpix: int = 50
    histogram_fraction: float = 0.5
    prior_margin_px: int = 60
    min_line_pixels: int = 150
    min_span_fraction: float = 0.3
    min_found_span_fraction: float = 0.08


@dataclass(frozen=True)
class LineFit:
    """One fitted line: pixel coefficients (a, b, c) of x = f(y), or not found with a reason."""

    coeffs_px: tuple[float, float, float] | None
    n_pixels: int = 0
    span_px: float = 0.0
    reason: str = ""

    @property
    def found(self) -> bool:
        return self.coeffs_px is not None

    def x_at(self, y) -> np.ndarray:
        """Return x (px) of the line at rows ``y`` (px); raises if the line was not found."""
        if self.coeffs_px is None:
            raise ValueError(f"line not found: {self.reason}")
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


@dataclass(frozen=True)
class LaneMeasurement:
    """Lane geometry at the car in metres (NaN where a line needed for it was not found)."""

    curvature_1pm: float
    radius_m: float
    offset_m: float
    lane_width_m: float
    left_curvature_1pm: float
    right_curvature_1pm: float


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


def sliding_windows(binary: np.ndarray, config: SearchConfig = SearchConfig(),
                    bases: tuple[float | None, float | None] | None = None,
                    car_x: float | None = None) -> LaneSearch:
    """Return the lane pixels found by sliding windows from the histogram bases, and their fits."""
    h = binary.shape[0]
    ys, xs = lane_pixels(binary)
    if bases is None:
        bases = find_bases(histogram(binary, config.histogram_fraction), car_x)
        if None in bases:  # a dashed line may have no dash in the lower part: look at all rows
            whole = find_bases(histogram(binary, 1.0), car_x)
            bases = tuple(b if b is not None else w for b, w in zip(bases, whole))
    win_h = h / config.n_windows
    windows: list[Window] = []
    picked = {}
    for side, base in zip(("left", "right"), bases):
        chosen = []
        x = base
        for i in range(config.n_windows):
            if x is None:
                break
            y_high = int(round(h - i * win_h))
            y_low = int(round(h - (i + 1) * win_h))
            lo, hi = np.searchsorted(ys, [y_low, y_high])
            row_xs = xs[lo:hi]
            inside = np.nonzero((row_xs >= x - config.margin_px) & (row_xs < x + config.margin_px))[0]
            windows.append(Window(side, int(x - config.margin_px), int(x + config.margin_px), y_low, y_high))
            chosen.append(inside + lo)
            if len(inside) >= config.minpix:
                x = float(row_xs[inside].mean())
        idx = np.concatenate(chosen) if chosen else np.empty(0, np.int64)
        picked[side] = (ys[idx], xs[idx])
    left = fit_line(*picked["left"], h, config, missing="no lane pixels left of the car")
    right = fit_line(*picked["right"], h, config, missing="no lane pixels right of the car")
    return LaneSearch(left, right, "windows", picked["left"], picked["right"], tuple(windows), bases)


def search_around(binary: np.ndarray, left: LineFit, right: LineFit,
                  config: SearchConfig = SearchConfig()) -> LaneSearch:
    """Return the lane pixels within ``prior_margin_px`` of previous fits, and their new fits."""
    h = binary.shape[0]
    ys, xs = lane_pixels(binary)
    picked = {}
    for side, prior in (("left", left), ("right", right)):
        if not prior.found:
            picked[side] = (ys[:0], xs[:0])
            continue
        near = np.abs(xs - prior.x_at(ys)) < config.prior_margin_px
        picked[side] = (ys[near], xs[near])
    new_left = fit_line(*picked["left"], h, config, missing="no previous left fit to search around"
                        if not left.found else "no lane pixels near the previous left fit")
    new_right = fit_line(*picked["right"], h, config, missing="no previous right fit to search around"
                         if not right.found else "no lane pixels near the previous right fit")
    return LaneSearch(new_left, new_right, "prior", picked["left"], picked["right"])


# --------------------------------------------------------------------------- fits

def fit_line(ys: np.ndarray, xs: np.ndarray, height_px: int, config: SearchConfig = SearchConfig(),
             missing: str = "no lane pixels") -> LineFit:
    """Return the 2nd-order fit x = f(y) of a line's pixels, or a not-found LineFit saying why."""
    n = len(ys)
    if n == 0:
        return LineFit(None, 0, 0.0, missing)
    span = float(ys.max() - ys.min())
    if n < config.min_line_pixels:
        return LineFit(None, n, span, f"only {n} lane pixels (need {config.min_line_pixels})")
    if span < config.min_found_span_fraction * height_px:
        return LineFit(None, n, span, f"pixels span only {span:.0f} px of the height")
    degree = 1 if span < config.min_span_fraction * height_px else 2
    a, b, c = least_squares_poly(ys, xs, degree, float(height_px))
    return LineFit((a, b, c), n, span)


def least_squares_poly(ys: np.ndarray, xs: np.ndarray, degree: int, scale: float) -> tuple[float, float, float]:
    """Return (a, b, c) of the least-squares x = a*y**2 + b*y + c (a = 0 for degree 1).

    The same fit as ``np.polyfit`` (to rounding), from the normal equations in y centred on its
    mean and divided by ``scale`` (e.g. the image height), which keeps them well conditioned; it
    costs a few sums instead of an SVD of an n x 3 matrix (the video hot path).
    """
    y = ys.astype(np.float64)
    x = xs.astype(np.float64)
    m = float(y.mean())
    t = (y - m) / scale
    # sums of products by numpy reductions, not BLAS dot products: BLAS threads spin on a busy machine
    t2 = t * t
    st = [float(len(t)), float(t.sum()), float(t2.sum()), float((t2 * t).sum()), float((t2 * t2).sum())]
    sx = [float(x.sum()), float((x * t).sum()), float((x * t2).sum())]
    k = degree + 1
    gram = np.array([[st[i + j] for j in range(k)] for i in range(k)])
    p = np.linalg.solve(gram, np.array(sx[:k]))  # x = p0 + p1*t (+ p2*t**2)
    p2 = p[2] if degree == 2 else 0.0
    a = p2 / scale ** 2
    b = p[1] / scale - 2 * p2 * m / scale ** 2
    c = p[0] - p[1] * m / scale + p2 * m * m / scale ** 2
    return float(a), float(b), float(c)


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
