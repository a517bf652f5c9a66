"""The bird's-eye points of the estimate, and whether the ego lane runs parallel through them.

In coordinates about the vanishing point turned by the roll (u along the horizon, v its distance
below it), a road line at lateral offset t is u = k v with
k = t cos(pitch) / (H cos(yaw)) + tan(yaw) sin(pitch); the ego lane's lines give
r = k_right - k_left. The src trapezoid is centred on the camera's own line
(k = tan(yaw) sin(pitch); 0 when the focal length is unknown: the camera is assumed on the car's
centre line) and r/2 wide on each side; its bottom edge lies parallel to the horizon just above
the hood (1 % of the height above it, and raised until its corners are inside the frame), its
top edge parallel to the horizon where the road is ``look_ahead_m`` ahead of the camera (pulled
in, and said so, when that is within 5 % of the height of the horizon). Edges parallel to the
horizon make the warp an affine rectification of the road: lane lines become vertical and the
scale is the same all over the view. dst is the rectangle of columns w/4 and 3w/4 over the
whole height.

Through a pinhole over a flat road the ego lane's lines are parallel in the view; when its width
at the top differs from that at the bottom by more than LANE_PARALLEL_TOLERANCE (frames' median,
``_view_widening``) a lens that distorts and was not given (a straight line's image bends), or a
road that is not flat, makes the scale not to be trusted.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import GeometryError
from .horizon import _Basis
from .road import _Road

# the ego lane may widen or narrow by this fraction from the bottom third of the bird's-eye view to
# its top third (frames' median) before the view is taken as wrong: a lens not given, a road not flat
LANE_PARALLEL_TOLERANCE = 0.025
IMPLAUSIBLE_CONFIDENCE = 0.4   # the confidence is multiplied by this then (below LOW_CONFIDENCE)


@dataclass(frozen=True)
class _View:
    """The bird's-eye points (``_view``) and the road between their bottom and top edges."""

    src: tuple
    dst: tuple
    near_m: float
    look_ahead_m: float
    visible_m: float



def _view(road: _Road, C: float, k_c: float, s0: float, look_ahead_m: float, assumptions: list[str]) -> _View:
    """Return the bird's-eye points: the ego lane's width about the camera's own line (u = ``k_c`` v),
    with s = C / v + ``s0`` the distance ahead of a row v px below the horizon, from just
    above the hood to ``look_ahead_m`` ahead (pulled in, and said in ``assumptions``, when that
    is within 5 % of the height of the horizon).

    Raises
    ------
    GeometryError
        If no road is seen above the hood, or the look-ahead is nearer than the road seen.
    """
    w, h = road.look.size
    basis = road.basis
    half = road.r_k / 2
    margin = max(2.0, 0.01 * h)
    v_bottom = _bottom_v(basis, (k_c - half, k_c + half), road.hood, margin, (w, h))
    if v_bottom is None:
        raise GeometryError("no road is seen above the hood between the lane lines; give "
                            "hood_row_px, or frames where the road is seen below the horizon")
    near_m = C / v_bottom + s0
    v_min = max(8.0, 0.05 * h)
    if look_ahead_m - s0 <= 0 or C / (look_ahead_m - s0) > v_bottom - 0.1 * h:
        raise GeometryError(f"look-ahead {look_ahead_m:g} m: the nearest road seen above the hood is "
                            f"{near_m:.1f} m ahead; choose a look-ahead of at least {near_m + 5:.0f} m")
    v_top = C / (look_ahead_m - s0)
    if v_top < v_min:
        v_top = v_min
        new = C / v_top + s0
        assumptions.append(f"look-ahead cut from {look_ahead_m:g} m to {new:.1f} m: farther rows lie within "
                           f"{v_min:.0f} px of the horizon, where a pixel is metres of road")
        look_ahead_m = new
    corners = [(k_c - half, v_top), (k_c - half, v_bottom), (k_c + half, v_bottom), (k_c + half, v_top)]
    src = tuple(tuple(float(c) for c in basis.to_xy(k * v, v)) for k, v in corners)
    dst = ((w / 4, 0.0), (w / 4, float(h)), (3 * w / 4, float(h)), (3 * w / 4, 0.0))
    return _View(src, dst, near_m, look_ahead_m, C / v_top - C / v_bottom)



def _parallel_confidence(road: _Road, view: _View, assumptions: list[str]) -> float:
    """Return IMPLAUSIBLE_CONFIDENCE when the ego lane widens or narrows through the view by more
    than LANE_PARALLEL_TOLERANCE (``_view_widening``; said in ``assumptions``), else 1."""
    analyses, ego, calibration = road.look.analyses, road.ego, road.look.calibration
    widening = _view_widening([(analyses[i].mask, [analyses[i].line_fits[j] for j in ego[i][:2]]) for i in ego],
                              view.src, view.dst, road.look.size)
    if widening is not None and abs(widening - 1) > LANE_PARALLEL_TOLERANCE:
        assumptions.append(
            f"the ego lane {'widens' if widening > 1 else 'narrows'} by {100 * abs(widening - 1):.1f} % from the "
            "bottom third of the bird's-eye view to the top third (frames' median): "
            + ("a lens that distorts (give --calibration)" if calibration is None else "")
            + (" or " if calibration is None else "") + "a road that is not flat; the scale is not to be trusted")
        return IMPLAUSIBLE_CONFIDENCE
    return 1.0



def _view_widening(frames: list[tuple[np.ndarray, tuple]], src, dst, size: tuple[int, int]) -> float | None:
    """Return the median over frames of the ego lane's width at the top of the bird's-eye view
    (a sixth down) over its width at the bottom (a sixth up): 1 when its lines are parallel, as
    they are through a pinhole over a flat road (a lens not given bends them, a road not flat
    spreads them). ``frames``: (mask, the ego lane's two line fits) each. Each line is a straight
    line fitted to the paint of the view within w/32 of the line fit carried into the view (not
    to a seam or the next line); frames where either spans under half the view are left out,
    and fewer than 3 frames give None."""
    w, h = size
    M = cv2.getPerspectiveTransform(np.float32(src), np.float32(dst))
    band = w / 32
    ratios = []
    for mask, fits in frames:
        top_down = cv2.warpPerspective(mask, M, (w, h), flags=cv2.INTER_NEAREST)
        ys, xs = np.nonzero(top_down)
        ends = []
        for c, d, top, bottom in fits:
            pts = np.array([c + d * (r - c[1]) / d[1] for r in (top, bottom)], np.float64)
            (x0, y0), (x1, y1) = cv2.perspectiveTransform(pts[None], M)[0]
            if abs(y1 - y0) < 1.0:
                break
            on = np.abs(xs - (x0 + (ys - y0) * (x1 - x0) / (y1 - y0))) <= band
            if on.sum() < 20 or np.ptp(ys[on]) < h / 2:
                break
            slope, icpt = np.polyfit(ys[on].astype(np.float64), xs[on].astype(np.float64), 1)
            ends.append(icpt + slope * np.array([h / 6, 5 * h / 6]))
        if len(ends) == 2:
            top, bottom = np.abs(ends[1] - ends[0])
            ratios.append(top / bottom)
    return float(np.median(ratios)) if len(ratios) >= 3 else None



def _bottom_v(basis: _Basis, ks: tuple[float, float], hood: np.ndarray, margin: float,
              size: tuple[int, int]) -> float | None:
    """Return the largest v (distance below the horizon) whose horizon-parallel segment between
    the lines u = k v stays above the hood by ``margin`` and inside the frame."""
    w, h = size
    v_hi = float(np.max(basis.to_uv(np.array([[0, h], [w, h]], np.float64))[:, 1]))
    for v in np.arange(math.floor(v_hi), 4.0, -1.0):
        u = np.linspace(ks[0] * v, ks[1] * v, 64)
        xy = basis.to_xy(u, np.full_like(u, v))
        if xy[0, 0] < 0 or xy[-1, 0] > w - 1:
            continue
        cols = np.clip(np.round(xy[:, 0]).astype(int), 0, w - 1)
        if np.all(xy[:, 1] <= hood[cols] - margin):
            return float(v)
    return None

