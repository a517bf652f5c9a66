"""Double lines: two parallel stripes that are one lane boundary, read at the inner stripe.

``two_stripes`` fits a line's pixels as two parallel stripes about one curve; ``inner_stripe``
keeps the stripe nearer the lane where the pixels form a resolved double line (as a whole, or on
its rows nearest the car); ``stripe_spacing_px`` measures the stripes' spacing band by band, whose
change along the rows is the change of the flat view's scale across the road. The search
(``search.fit_side``) calls ``double_line_fit`` on every line (which changes nothing while
``SearchConfig.double_line_px`` is off), a window's ``centre_side`` with
``SearchConfig.centre_first`` and its ``fullest_column`` with ``SearchConfig.window_histogram``.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..fit import fit_line, least_squares_rss, normal_sums
from ..params import SearchConfig
from ..records import LineFit, polyval2


def double_line_fit(fit: LineFit, first: tuple, pixels: tuple[np.ndarray, np.ndarray], side: str,
                    height_px: int, config: SearchConfig, missing: str, top_px: int = 0
                    ) -> tuple[LineFit, tuple[np.ndarray, np.ndarray]]:
    """Return the fit of a line whose pixels scatter from their fit ``fit`` like a double line,
    and the pixels it rests on (``search.fit_side`` asks; ``first``: ``fit_line``'s first fit of
    the same pixels, ``fit.fit_line_with_first``): those of its inner stripe (``inner_stripe``)
    where the stripes are resolved, else all of them. ``fit`` and all the pixels as they are with
    ``SearchConfig.double_line_px`` off, or pixels scattering less than a quarter of it (RMS).

    A line resolved as a double line as a whole is its inner stripe's fit, found or not: a fit
    through both stripes runs between them, never on the line (a patch of double line too short
    to fit, with a stray pixel further on lending the whole its span, is not found rather than
    fitted through both stripes and bent by that pixel). An inner stripe resolved only on the rows
    nearest the car is taken when its fit is found and as well founded as the fit of the whole
    line (second order where that one is: spanning ``min_span_fraction`` of the view); a short
    stub of it is not worth the line, which was not shown to be two stripes beyond it. A line
    that scatters so but is not narrowed to a stripe keeps its pixels' spread about two stripes
    (``two_stripes``, fitted once for both: ``LineFit.stripe_scatter_px``) when each stripe holds
    at least a fifth of them.
    """
    if not (config.double_line_px and fit.found and fit.scatter_px > config.double_line_px / 4):
        return fit, pixels  # a single line costs no second fit
    stripes = two_stripes(*pixels, 2, height_px, first=first)
    keep, whole = inner_stripe_mask(*pixels, side, config.double_line_px, height_px, stripes, first)
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
    is not resolved as a whole; fitted through them it runs between the stripes, off the inner
    one even at the car. Its near rows may still be resolved: the eight bands are then
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
    keep, _ = inner_stripe_mask(ys, xs, side, spacing_px, height_px, stripes)
    return (ys, xs) if keep is None else (ys[keep], xs[keep])


def inner_stripe_mask(ys: np.ndarray, xs: np.ndarray, side: str, spacing_px: float, height_px: int,
                       stripes: tuple | None, first: tuple | None = None) -> tuple[np.ndarray | None, bool]:
    """Return which pixels ``inner_stripe`` keeps (None: all, not a double line) and whether the
    line was resolved as a double line as a whole (False: on its near rows only). ``first``:
    ``fit_line``'s first fit of the same pixels (``fit_line_with_first``) when already made
    (``double_line_fit``)."""
    n = len(ys)
    if spacing_px <= 0 or n < 20:
        return None, False
    y_min = ys.min()
    span = float(ys.max() - y_min)
    if span <= 0:
        return None, False
    degree = 2 if span >= 0.3 * height_px else 1
    rss = first[3] if first is not None and degree == 2 else least_squares_rss(ys, xs, degree, float(height_px))[3]
    if rss < n * (spacing_px / 4) ** 2:
        return None, False  # close to one fit (a single stripe): no second stripe to look for
    model = two_stripes(ys, xs, 2, height_px, first=first) if stripes is None else stripes
    bands, counts, distinct = _row_bands(ys, y_min, span)
    y = ys.astype(np.float64)
    r = xs - polyval2(model[0], y)  # from the centre curve
    inner = _inner_side(bands, None, model, side, spacing_px, r, ys)
    if inner is not None:
        return inner, True
    # the near rows: the run of bands from the car's end where the stripes are resolved
    held = counts >= 20
    near = None  # all the pixels
    for _ in range(3):
        coeffs, spacing, upper, _ = model
        if r is None:
            r = xs - polyval2(coeffs, y)
        run = []
        for band in range(7, -1, -1):
            if not held[band]:
                continue
            g = bands == band
            if not (_stripes_resolved(r[g], spacing[g], upper[g], ys[g], spacing_px, pair=False)
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
        r = xs - polyval2(model[0], y)
    return _inner_side(bands, near, model, side, spacing_px, r, ys), False


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


def _inner_side(bands: np.ndarray, rows: np.ndarray | None, model: tuple, side: str, spacing_px: float,
                r: np.ndarray, ys: np.ndarray) -> np.ndarray | None:
    """Return which pixels of ``rows`` (a mask; None: all) lie on the inner stripe of the
    two-stripe ``model`` (``two_stripes``' curve, spacing per pixel and side per pixel; ``r``:
    each pixel's residual from its curve; ``ys``: each pixel's row), or None when those pixels
    are not a double line there (``inner_stripe``: resolved, side by side)."""
    _, spacing, upper, _ = model
    on_rows, r, spacing, up, ys = (bands, r, spacing, upper, ys) if rows is None else (
        bands[rows], r[rows], spacing[rows], upper[rows], ys[rows])
    if not _stripes_resolved(r, spacing, up, ys, spacing_px):
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
    if least_squares_rss(ys, xs, 1, float(height_px))[3] < len(ys) * (BAND_ONE_STRIPE_RMS * spacing_px) ** 2:
        return False
    coeffs, spacing, upper, _ = two_stripes(ys, xs, 1, height_px)
    return _stripes_resolved(xs - polyval2(coeffs, ys.astype(np.float64)), spacing, upper, ys, spacing_px)


def _stripes_resolved(r: np.ndarray, spacing: np.ndarray, upper: np.ndarray, ys: np.ndarray,
                      spacing_px: float, pair: bool = True) -> bool:
    """Return whether pixels at residuals ``r`` (px) from a two-stripe curve, with the stripes'
    ``spacing`` (px) on their rows ``ys`` and ``upper`` their side, lie on two resolved stripes: each
    stripe is narrow (its pixels' RMS distance from it under a quarter of their median spacing:
    the view's scale and the stripes' width scale alike) and the gap between them is clear
    (under 5 % of the pixels within an eighth of the spacing of its middle). With ``pair`` the
    pixels must also show both: each stripe holds at least a fifth of them and their median
    spacing is 0.6-1.5 x ``spacing_px``; without it a band of rows where one stripe is worn
    away still counts (which stripe its pixels lie on is clear). The spacing is linear in the
    row, pixel by pixel (``_median_spacing`` reads its median from the rows)."""
    n = len(r)
    if n == 0:
        return False
    right = int(np.count_nonzero(upper))
    if pair and min(n - right, right) < 0.2 * n:
        return False
    # the median lies between the least and the greatest spacing: those decide most lines at once
    if pair and (float(spacing.max()) < 0.6 * spacing_px or float(spacing.min()) > 1.5 * spacing_px):
        return False
    apart = _median_spacing(spacing, ys)
    if pair and not 0.6 * spacing_px <= apart <= 1.5 * spacing_px:
        return False
    off = r - np.where(upper, 0.5, -0.5) * spacing  # from the pixel's stripe
    if max(float(np.sqrt(np.mean(off[g] ** 2))) for g, held in ((~upper, right < n), (upper, right > 0))
           if held) > abs(apart) / 4:
        return False
    # no clear gap between them: one line the first fit misses (or a blur of both), not two
    return np.count_nonzero(np.abs(r) < np.abs(spacing) / 8) <= 0.05 * n


def _median_spacing(spacing: np.ndarray, ys: np.ndarray) -> float:
    """Return ``np.median(spacing)`` to the bit, for a spacing computed pixel by pixel as a line in
    the pixel's row ``ys`` (``two_stripes``: ``p + q * t``, t from the row), without sorting it.

    Each step of that sum is a rounded operation, which never reverses the order of its inputs:
    the spacing rises (or falls) with the row, equal on one row. Its middle values are then its
    values on the middle rows of ``ys``, read from the count of pixels per row (integer rows);
    the middle two are averaged as ``np.median`` does (their sum halved). Rows that are not
    integers, or a spacing not finite on the first and last row, take ``np.median``.
    """
    n = len(ys)
    if n < 2 or ys.dtype.kind not in "iu":
        return float(np.median(spacing))
    first, last = int(np.argmin(ys)), int(np.argmax(ys))
    s0, s1 = float(spacing[first]), float(spacing[last])
    if not (math.isfinite(s0) and math.isfinite(s1)):
        return float(np.median(spacing))
    y0 = int(ys[first])
    below = np.cumsum(np.bincount(ys - y0))  # pixels on each row and the rows above it
    middle = (n // 2,) if n % 2 else (n // 2 - 1, n // 2)
    if s1 < s0:  # falling with the row: the k-th least spacing lies on the k-th greatest row
        middle = tuple(n - 1 - k for k in middle)
    rows = np.searchsorted(below, middle, side="right") + y0
    values = [float(spacing[int(np.argmax(ys == row))]) for row in rows]
    return sum(values) / len(values)


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
    ``first``: ``fit_line``'s first fit (a, b, c, rss and its ``normal_sums``) of the same
    pixels when already made (``double_line_fit``; used for degree 2 only).
    """
    scale = float(height_px)
    k = degree + 1  # terms of the centre curve: 1, t (, t**2)
    n = len(ys)
    if first is not None and degree == 2 and (xs.dtype.kind in "iu" or xs.dtype == np.float64):
        # fit_line's first fit read the same arrays and sums (x's mean the same: integer or
        # float64 pixels' sums do not depend on the order they are added in)
        a, b, c, rss, sums = first
    else:
        sums = normal_sums(ys, xs, scale)
        a, b, c, rss = least_squares_rss(ys, xs, degree, scale, sums)
    # the normal equations from sums of t**j and x * t**j over all pixels and over the right-hand
    # stripe's (s = +-1/2 per stripe: sums of s * t**j are the right stripe's less half the
    # whole), by numpy reductions as in ``least_squares_rss`` (no BLAS threads)
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
    upper = xs > polyval2((a, b, c), y)
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


def stripe_spread(binary: np.ndarray, coeffs_px, spacing_px: float, top_px: int,
                  size: tuple[int, int]) -> np.ndarray | None:
    """Return the flat view's scale across the road relative to the bottom row's, as a straight
    line in (bottom row - row), from the stripes of a double line along the fit ``coeffs_px``
    (``stripe_spacing_px``), or None.

    None unless the stripes show on at least 4 bands of rows covering half the look-ahead (from
    ``top_px``, down from where the line lies in the view of ``size`` (w, h): on a tight bend it
    leaves the view sideways, and no stripes show above that), their spacing lies within an
    eighth of ``spacing_px`` (RMS) of the straight line, and the scale at the look-ahead's top is
    0.7-2.5: a spread read from fewer or scattered bands is noise, and a line inferred at that
    spread would follow it. None with ``spacing_px`` 0 (no double lines looked for).
    """
    if not spacing_px:
        return None
    w, h = size
    bottom = float(h - 1)
    ys, gaps = stripe_spacing_px(binary, coeffs_px, spacing_px, top_px)
    rows = np.arange(float(top_px), bottom + 1.0)
    x = np.polyval(coeffs_px, rows)
    outside = np.flatnonzero((x < 0) | (x >= w))
    in_view = float(top_px) if not len(outside) else float(rows[outside[-1]] + 1.0)
    depth = bottom - max(float(top_px), in_view)
    if len(ys) < 4 or ys.max() - ys.min() < 0.5 * depth:
        return None
    slope, at_car = np.polyfit(bottom - ys, gaps, 1)
    residual = gaps - np.polyval((slope, at_car), bottom - ys)
    if at_car <= 0 or float(np.sqrt(np.mean(residual ** 2))) > spacing_px / 8:
        return None
    if not 0.7 <= 1.0 + slope / at_car * depth <= 2.5:
        return None
    return np.array([slope / at_car, 1.0])


def centre_side(row_xs: np.ndarray, inside: np.ndarray, minpix: int, toward_centre: int) -> np.ndarray:
    """Return which of a sliding window's pixels (``inside``: indices into ``row_xs``, their x) it
    takes with ``SearchConfig.centre_first``: of its runs of occupied columns (split at empty
    columns) holding ``minpix`` pixels or more, the one nearest the lane centre (``toward_centre``
    1: to the right, -1: to the left), else all of them."""
    full = [c for c in _window_clusters(row_xs[inside]) if len(c) >= minpix]
    if not full:
        return inside
    near = max(full, key=lambda c: toward_centre * float(row_xs[inside[c[0]]]))
    return np.sort(inside[near])


def fullest_column(xs: np.ndarray) -> float:
    """Return the x a sliding window recentres the next one on with ``SearchConfig.window_histogram``:
    the column holding most of its pixels (``xs``, not empty), the leftmost of equals."""
    x0 = int(xs.min())
    return float(x0 + int(np.argmax(np.bincount(xs - x0))))


def _window_clusters(xs: np.ndarray) -> list[np.ndarray]:
    """Return the indices into ``xs`` of each run of occupied columns (split at empty columns)."""
    order = np.argsort(xs, kind="stable")
    sx = xs[order]
    cuts = np.nonzero(np.diff(sx) > 1)[0] + 1
    return np.split(order, cuts)
