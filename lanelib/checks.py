"""Plausibility checks: whether fitted lines are a lane (``LaneChecks`` holds the limits).

A lane is found only when both lines pass ``check_lane``, in an image (``LanePipeline.detect``)
as in a video (``LaneTracker``); a ``result.FrameResult`` that failed says why in ``reason`` and
keeps the fits apart in ``rejected``, with NaN measurements: no lane rather than a confident
wrong one. Each check returns "" when it passes, else the reason in words.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fit import curvature, fit_to_metres
from .params import LaneChecks, SearchConfig
from .records import LaneSearch, LineFit, polyval2


def line_problem(fit: LineFit, band_px: float, checks: LaneChecks = LaneChecks(),
                 xm_per_px: float | None = None, side: str = "left") -> str:
    """Return why one fitted line is not a plausible lane line ("" when it is, or is not found).

    Measured against its search band, so the rules hold for any view scale and margin: a line
    filling the band is a bright patch (``max_band_fill``), one spreading evenly across it is
    texture (``max_band_scatter``), unless it is two narrow stripes (a double line) whose spread
    about them (``LineFit.stripe_scatter_px``) is within that limit for half the band.

    Parameters
    ----------
    fit : the line's fit, with the pixel count, rows spanned and scatter of its pixels.
    band_px : width (px) of its search band inside the view (``search_bands_px``; 0: not checked).
    checks : the limits.
    xm_per_px : metres per bird's-eye pixel across, to state the scatter in metres (optional).
    side : "left" or "right", for the message.
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
    turn there, or only where its pixels are (``LineFit.gap_px``, ``span_px``; a fit without
    pixels rests on none). With ``width_px`` (the view's width) only the part inside the view
    counts: a tight bend's line leaves the view sideways, where its fit is not drawn.

    Examples
    --------
    A parabola turning on row 300, fitted to rows 400-719, comes back 300**2 * a px above row 300:

    >>> from dataclasses import replace
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
    """Return why a found line's fit hooks back more than ``max_turn_back_m`` beyond its pixels
    (``turn_back_m``) within the look-ahead ("" when it does not, or is not found).
    """
    if not fit.found:
        return ""
    back = turn_back_m(fit, height_px, xm_per_px, top_px, width_px)
    if back <= checks.max_turn_back_m:
        return ""
    return (f"{side} line hooks back {back:.2f} m beyond its pixels within the view (its x turns "
            f"around; limit {checks.max_turn_back_m} m)")


def holds_from_px(left: LineFit, right: LineFit, height_px: int, width_px: int, xm_per_px: float,
                  checks: LaneChecks = LaneChecks(), top_px: int = 0) -> int:
    """Return the first row from which a lane's found lines hold down to the car: above it a line
    leaves the view's columns, hooks back beyond its pixels (from its turning row, ``turn_back_m``
    over ``max_turn_back_m``) or the lines touch or cross. A lane is drawn, and an inferred line
    reported, only below it: a second-order fit extrapolated beyond its paint may swing across
    the road.

    Examples
    --------
    A straight pair holds over the whole view; a line leaving a 1280 px view on row 200 holds
    from row 201; a fit on rows 400-719 turning on row 300 holds from its turn:

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
    """Return why a line is not seen at the car: its pixels stop more than ``max_gap_m`` short of
    the view's bottom row (``LineFit.gap_px`` times ``ym_per_px``, m per pixel along the road), so
    its position there is an extrapolation ("" when nearer, or the line is not found).
    """
    gap_m = fit.gap_px * ym_per_px
    if not fit.found or gap_m <= max_gap_m:
        return ""
    return (f"{side} line seen only from {gap_m:.1f} m ahead of the view's bottom row "
            f"(limit {max_gap_m} m): at the car it is an extrapolation")


def pair_problem(left: LineFit, right: LineFit, height_px: int, xm_per_px: float, ym_per_px: float,
                 checks: LaneChecks = LaneChecks(), top_px: int = 0,
                 width_reference_px: np.ndarray | None = None) -> str:
    """Return why two found lines are not a plausible lane ("" when they are).

    On a few rows from the look-ahead's top (``top_px``) to the bottom: the width at the car lies
    within ``min_width_m``-``max_width_m``; the lines never touch or cross; the width varies by at
    most ``max_width_spread_m`` times the look-ahead's share of the view's height, and the
    curvatures at the car differ by at most ``max_curvature_diff_per_m`` divided by it. A curvature
    fitted over fewer metres is measured less well (its error grows as 1 / span**2, and a
    parabola's reading of an arc depends on the arc's length), so a fixed limit refuses the true
    lane of a tight bend seen a short way; divided so, the parting it allows (dk * L**2 / 2 over
    the look-ahead's L) still shrinks with L, as the width's does.

    With ``width_reference_px`` (the tracked lane's width, px, on those rows) the width's spread
    is taken about it: a grade widens or narrows the lane ahead in the flat view and the track
    follows that, so only a change from one frame to the next is refused.
    """
    rows = np.linspace(float(top_px), height_px - 1.0, checks.check_rows)
    width = (polyval2(right.coeffs_px, rows) - polyval2(left.coeffs_px, rows)) * xm_per_px  # np.polyval's
    spread_of = width if width_reference_px is None else width - np.asarray(width_reference_px) * xm_per_px
    if not checks.min_width_m <= width[-1] <= checks.max_width_m:
        return (f"lane width {width[-1]:.2f} m at the car outside {checks.min_width_m}-"
                f"{checks.max_width_m} m")
    dense = np.linspace(float(top_px), height_px - 1.0, 4 * checks.check_rows)
    apart = polyval2(right.coeffs_px, dense) - polyval2(left.coeffs_px, dense)
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

    At a pitch other than the one its points were chosen for (a grade, the load, another mount)
    the flat view scales the road across linearly with the distance ahead, so a lane's lines
    converge or diverge steadily and ``pair_problem`` refuses them. Here the width's least-squares
    line over the check rows is taken as the view's pitch when it changes the width by at most
    ``max_change`` of its width at the car over the view (pro rata over a shorter look-ahead); the
    pair must then pass ``pair_problem`` with that trend as its width reference.

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
    """Why the fits of one search are not a plausible lane, per line and for the pair ("" = passes).

    A line not found is not checked (its own ``reason`` says why); the pair is checked only when
    both lines were found and passed.
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
    """Return the plausibility checks of two fits: ``line_problem`` (with ``width_px``, also
    ``turn_back_problem``) of each, then ``pair_problem``.

    Parameters
    ----------
    left, right : the fits of one search (bird's-eye pixels).
    bands_px : width (px) of each line's search band (``search_bands_px``).
    height_px : height of the bird's-eye view.
    xm_per_px, ym_per_px : metres per bird's-eye pixel across and along the road.
    checks : the limits.
    top_px : the look-ahead's first row (``LaneSearch.top_px``).
    width_px : the view's width, for the turn-back check (None: not checked; the tracker checks
        its searches against the track instead).
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
    """Return the mean width (px), cut to the view, of the band each line was searched in.

    Sliding windows: the mean of the line's windows. Around prior fits: ``2 * prior_margin_px``
    around the new fit on eight rows. Cut to the view, so that texture along its edge, in half a
    window, is compared with the half it could fill.

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
