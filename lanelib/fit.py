"""Polynomial fits of lane pixels, and the lane they measure: curvature, radius, offset and width.

Coordinates are bird's-eye pixels, x to the right and y down; a line is fitted as
``x = a*y**2 + b*y + c`` (``fit_line``). Metric fits scale the pixel coefficients exactly (no
refit): with ``x_m = xm*x``, ``y_m = ym*y``, ``x_m = (xm/ym**2)*a*y_m**2 + (xm/ym)*b*y_m + xm*c``
(``fit_to_metres``).

Signs (as the synthetic ground truth's): curvature (1/m) is positive when the road bends RIGHT
ahead, the radius is ``1/|curvature|`` capped at ``RADIUS_MAX_M`` (straight); the offset (m) is
positive when the car is RIGHT of the lane centre, the car being where the undistorted frame's
bottom-centre pixel lands in the view. All are read on the view's bottom row, the nearest road
seen (the Udacity convention, ``measure``), not extrapolated to the car: a heading off the lane
shifts the offset there by the heading times that row's distance, which ``evaluate`` counts as
error against truth given at the car.

The lines of a lane are parallel: a line too short for a curve of its own takes the other's
(``parallel_fits``, ``shared_curvature``); ``offset_line`` places a line a distance along
another's normal, ``normal_width_m`` reads the width along it.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .params import SearchConfig
from .records import LaneMeasurement, LineFit, near_row_px


RADIUS_MAX_M = 100_000.0


def fit_line(ys: np.ndarray, xs: np.ndarray, height_px: int, config: SearchConfig = SearchConfig(),
             missing: str = "no lane pixels", top_px: int = 0) -> LineFit:
    """Return the 2nd-order fit x = f(y) of a line's pixels, or a not-found LineFit saying why.

    Pixels spanning less than ``min_span_fraction`` of the height are fitted straight, unless in a
    look-ahead (``top_px`` > 0) the curve bows over the span by ``short_bend_resolution`` times the
    pixels' RMS scatter or more: a resolved bend, a tight bend's line leaving the view sideways.
    """
    return fit_line_with_first(ys, xs, height_px, config, missing, top_px)[0]


def fit_line_with_first(ys: np.ndarray, xs: np.ndarray, height_px: int, config: SearchConfig, missing: str,
              top_px: int) -> tuple[LineFit, tuple | None]:
    """Return ``fit_line``'s fit and its first fit (a, b, c, rss, ``normal_sums`` of degree 2 of all
    the pixels; None when turned down before), which ``fit_side`` hands to the stripe test.
    """
    n = len(ys)
    if n == 0:
        return LineFit(None, 0, 0.0, missing), None
    span = float(ys.max() - ys.min())
    if n < config.min_line_pixels:
        return LineFit(None, n, span, f"only {n} lane pixels (need {config.min_line_pixels})"), None
    if span < config.min_found_span_fraction * height_px:
        return LineFit(None, n, span, f"pixels span only {span:.0f} px of the height"), None
    degree = 2
    sums = normal_sums(ys, xs, float(height_px))
    a, b, c, rss = least_squares_rss(ys, xs, degree, float(height_px), sums)
    first = (a, b, c, rss, sums)
    if span < config.min_span_fraction * height_px and not (
            top_px > 0 and config.short_bend_resolution > 0
            and abs(a) * span * span / 4 >= config.short_bend_resolution * math.sqrt(rss / n)):
        degree = 1
        a, b, c, rss = least_squares_rss(ys, xs, degree, float(height_px))
    if 0 < config.trim_outliers_pct < 100:
        keep = max(degree + 1, int(round(n * config.trim_outliers_pct / 100)))
        if keep < n:
            residual = np.abs(xs - np.polyval((a, b, c), ys))
            idx = np.sort(np.argpartition(residual, keep - 1)[:keep])
            ys, xs, n = ys[idx], xs[idx], keep
            span = float(ys.max() - ys.min())
            a, b, c, rss = least_squares_rss(ys, xs, degree, float(height_px))
    gap = max(0.0, height_px - 1.0 - near_row_px(ys))
    return LineFit((a, b, c), n, span, scatter_px=math.sqrt(rss / n), gap_px=gap), first


def least_squares_poly(ys: np.ndarray, xs: np.ndarray, degree: int, scale: float) -> tuple[float, float, float]:
    """Return (a, b, c) of the least-squares x = a*y**2 + b*y + c (a = 0 for degree 1).

    ``np.polyfit``'s fit (to rounding) from the normal equations in y centred and divided by
    ``scale`` (e.g. the height), which keeps them well conditioned: a few sums instead of an SVD
    (the video hot path).
    """
    return least_squares_rss(ys, xs, degree, scale)[:3]


def joined_fit(seen_rows: np.ndarray, seen_xs: np.ndarray, reference_px, reference_rows: np.ndarray,
               height_px: int) -> tuple[float, float, float]:
    """Return one second-order fit to a line where it is seen and to a reference line where not.

    A line seen only far ahead is joined to a reference near the car (its track, or the line
    inferred from the other), an asphalt edge near the car to a guide far ahead: one sample per row
    of each (``seen_xs`` on ``seen_rows``, ``reference_px`` on ``reference_rows``), so the fit
    follows each where it is the evidence.

    Examples
    --------
    >>> rows = np.arange(0.0, 50.0)
    >>> a, b, c = joined_fit(rows, 100.0 + 0 * rows, (0.0, 0.0, 100.0), np.arange(50.0, 100.0), 100)
    >>> round(a, 9), round(b, 9), round(c, 6)
    (0.0, 0.0, 100.0)
    """
    ys = np.concatenate([np.asarray(seen_rows, float), np.asarray(reference_rows, float)])
    xs = np.concatenate([np.asarray(seen_xs, float), np.polyval(reference_px, reference_rows)])
    return least_squares_poly(ys, xs, 2, float(height_px))


def least_squares_rss(ys: np.ndarray, xs: np.ndarray, degree: int, scale: float,
                   sums: tuple | None = None) -> tuple[float, float, float, float]:
    """Return (a, b, c) of ``least_squares_poly`` and the residual sum of squares (px**2), from the
    same sums: sum(x**2) - p . s for the solution p of G p = s, x about its mean to keep its
    digits. ``sums``: ``normal_sums(ys, xs, scale)`` when already made.
    """
    _, m, _, _, _, st, x0, x, _, sx = normal_sums(ys, xs, scale) if sums is None else sums
    k = degree + 1
    gram = np.array([[st[i + j] for j in range(k)] for i in range(k)])
    p = np.linalg.solve(gram, np.array(sx[:k]))  # x - x0 = p0 + p1*t (+ p2*t**2)
    rss = max(0.0, float(np.add.reduce(x * x)) - sum(float(p[i]) * sx[i] for i in range(k)))
    p2 = p[2] if degree == 2 else 0.0
    a = p2 / scale ** 2
    b = p[1] / scale - 2 * p2 * m / scale ** 2
    c = x0 + p[0] - p[1] * m / scale + p2 * m * m / scale ** 2
    return float(a), float(b), float(c), rss


def normal_sums(ys: np.ndarray, xs: np.ndarray, scale: float) -> tuple:
    """Return what ``least_squares_rss`` fits from: y (float), its mean m, t = (y - m) / ``scale``,
    t**2, t**3, the sums of t**0..4, x's mean x0, x - x0, (x - x0) * t and the sums of (x - x0) *
    t**0..2; ``two_stripes`` starts from the same arrays and sums."""
    total = np.add.reduce  # ``ndarray.sum``'s and ``mean``'s pairwise sum, without their Python wrappers
    y = ys.astype(np.float64)
    x = xs.astype(np.float64)
    n = len(y)
    m = float(total(y)) / n
    t = (y - m) / scale
    # sums of products by numpy reductions, not BLAS dot products: BLAS threads spin on a busy machine
    t2 = t * t
    t3 = t2 * t
    st = [float(n), float(total(t)), float(total(t2)), float(total(t3)), float(total(t2 * t2))]
    x0 = float(total(x)) / n
    x -= x0
    xt = x * t
    sx = [float(total(x)), float(total(xt)), float(total(x * t2))]
    return y, m, t, t2, t3, st, x0, x, xt, sx


def parallel_fits(left: LineFit, right: LineFit, left_pixels, right_pixels, height_px: int,
                  config: SearchConfig = SearchConfig()) -> tuple[LineFit, LineFit]:
    """Return the two fits with a short line's curvature taken from the other, longer line.

    A line spanning less than ``min_span_fraction`` of the view (one dash, a stub leaving the view
    on a bend) is fitted straight unless its bend is resolved: beside a curved line it fails the
    pair's curvature check and runs off the lane ahead. The lines being parallel, it takes the
    other's second-order coefficient when that one is long enough, fitting only its slope and
    position. Two short lines, one of which kept its bend, share one coefficient fitted to both
    (``shared_curvature``): two bends each read from a few metres part the lines ahead. Two long
    lines, or two short straight ones, are left as they are.
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
    _, b, c, rss = least_squares_rss(ys, xs - a * y * y, 1, float(height_px))
    shared = replace(line, coeffs_px=(a, b, c), scatter_px=math.sqrt(rss / max(len(ys), 1)))
    return (shared, right) if line is left else (left, shared)


def shared_curvature(left: LineFit, right: LineFit, left_pixels, right_pixels,
                     height_px: int) -> tuple[LineFit, LineFit]:
    """Return the two lines refitted with one second-order coefficient, x = a*y**2 + b_i*y + c_i, by
    least squares over both lines' pixels (the lines of a lane are parallel; ``parallel_fits``).

    The normal equations of the five unknowns, y centred on both lines' mean row and divided by
    ``height_px``; each ``scatter_px`` is its own pixels' RMS distance. Unchanged when singular.
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
    """Return curvature, radius, offset and lane width in metres on the view's bottom row. The lane's
    centre has the lines' mean position and their shape (a, b) weighted by ``support``, so a line on
    one dash does not bend the lane. A value needing a line not found is NaN.
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


def offset_line(coeffs_px, offset_m, xm_per_px: float, ym_per_px: float, height_px: int,
                top_px: int = 0) -> tuple[float, float, float]:
    """Return the pixel fit (a, b, c) of the curve parallel to a line at ``offset_m`` along its normal.

    The lines of a lane are parallel curves: the other line lies a lane width along the normal,
    not at the same x shift on every row (on a tight bend the two differ by over half a metre).
    The line is sampled from ``top_px`` to the bottom, each point moved along the normal in metres
    and x = f(y) refitted.

    Parameters
    ----------
    coeffs_px : (a, b, c) of the line in bird's-eye pixels.
    offset_m : signed normal distance (m), + to the right (larger x). One value, or one per
        sampled row (``offset_rows_px``), as a tracked width that a grade changes along the view.
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
    """Return the distance (m) between two lines along their normal on row ``y_px`` (a float), or on
    several rows (an array): the horizontal width times the cosine of the lane's heading there (the
    lines' mean slope), the lane width on a bend where the horizontal width is wider.
    """
    xl, xr = np.polyval(left_px, y_px), np.polyval(right_px, y_px)
    dl = np.polyval(np.polyder(np.asarray(left_px, float)), y_px)
    dr = np.polyval(np.polyder(np.asarray(right_px, float)), y_px)
    slope_m = 0.5 * (dl + dr) * xm_per_px / ym_per_px
    out = (xr - xl) * xm_per_px / np.sqrt(1.0 + slope_m * slope_m)
    return float(out) if np.ndim(out) == 0 else out
