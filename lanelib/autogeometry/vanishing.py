"""One frame: its painted lines and the vanishing point of the road (``RoadLineFinder``).

- **Vanishing point of one frame.** The band segments of the paint mask (``segments``) meet in
  a point found by RANSAC. Stubs of dashes cut by a band row join the inliers when they continue
  one across the cut and point at the point within 3 deg. The inliers are grouped into lines by
  their angle about the point (a gap of 1.2 deg or more starts a new line); each line is
  refitted through all its run centres, and the frame's point is the weighted least-squares
  intersection of those lines. A point outside the middle 70 % of the width or 5-85 % of the
  height, or fewer than two lines 4 deg apart below it, gives no point (the frame is rotated,
  or shows no road).
- **Straightness** ("the segments of each line are collinear"; frames where the road bends are
  left out). Each line is followed up the image through the segments that continue it across
  the band rows (bending or not), and a parabola fitted to all their run centres must bow less
  than ``MAX_BOW_PX`` + 0.3 % of the line's length from its chord (lines spanning a fifth of the
  road's rows or more); and the vanishing point of the far segments (the third of the road
  nearest the horizon) must lie within 0.8 % of the image width of that of the near ones, in x
  (a bend) and in y (a crest or a dip).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .. import io
from ..camera import Calibration, Lens, Undistorter
from ..thresholds import combine
from .segments import (RANSAC_SEED, _angle_errors, _fit_line, _follow_up, _intersect, _normals, _ransac,
                       _segments, _Segments, _up_links, paint_mask_config)

LINE_GAP_DEG = 1.2
MIN_SEGMENTS = 4
MIN_LINE_SEPARATION_DEG = 4.0
MIN_LINE_ROWS_FRACTION = 0.02  # a line spans at least this share of the rows (and 10)
MAX_BOW_PX = 1.5
BAND_FRACTION = 1 / 24
FAR_FRACTION = 0.35
NEAR_FRACTION = 0.45
FAR_NEAR_TOLERANCE = 0.008
Point = tuple[float, float]


@dataclass(frozen=True)
class RoadLine:
    """One straight painted line found in a frame (undistorted image, px).

    ``point_px`` is the centroid of its run centres and ``direction`` its unit direction
    (pointing down the image); ``rows_px`` the rows it spans; ``angle_deg`` its angle about the
    frame's vanishing point, from straight down, positive to the right; ``bow_px`` how far a
    parabola fitted along it bows from its chord; ``segments`` how many band segments it joins.
    """

    point_px: Point
    direction: Point
    rows_px: tuple[float, float]
    angle_deg: float
    bow_px: float
    points: int
    segments: int


@dataclass(frozen=True)
class VanishingPoint:
    """The vanishing point of the road direction in one frame, or None and why.

    ``point_px`` is in the undistorted image; ``segments`` the line segments found,
    ``inlier_segments`` those that point at it; ``lines`` the straight lines they form;
    ``straight`` whether every long line is straight; ``reason`` is '' when the point is good
    (found and straight), else what went wrong and what to do.
    """

    point_px: Point | None
    segments: int
    inlier_segments: int
    lines: tuple[RoadLine, ...]
    straight: bool
    reason: str

    @property
    def ok(self) -> bool:
        """Return True when the frame gave a vanishing point on a straight road."""
        return self.point_px is not None and not self.reason


@dataclass(frozen=True)
class _FrameAnalysis:
    vp: VanishingPoint
    mask: np.ndarray
    line_fits: tuple[tuple[np.ndarray, np.ndarray, float, float], ...]   # (point, dir, top row, bottom row)
    line_points: tuple[np.ndarray, ...] = ()   # per line, its run centres (N, 2), followed up across bends


class RoadLineFinder:
    """Finds the painted lines and the vanishing point in frames of one size.

    Parameters
    ----------
    size_px : (width, height) of the frames.
    lens : a ``camera.Lens`` or ``camera.Calibration`` to undistort the frames with, or None
        (frames taken as undistorted).
    hood_top_px : the hood's top row, one number or one per column; rows from there down are
        left out. None: none are.
    """

    def __init__(self, size_px: tuple[int, int], lens: Lens | Calibration | None = None,
                 hood_top_px: float | np.ndarray | None = None):
        self.size = (int(size_px[0]), int(size_px[1]))
        calibration = lens.calibration if isinstance(lens, Lens) else lens
        self.undistorter = Undistorter(calibration, self.size)
        self.calibration = self.undistorter.calibration
        self.config = paint_mask_config(self.size)
        w, h = self.size
        self.band_px = max(6, int(round(BAND_FRACTION * h)))
        self.max_run_px = self.config.line_tophat.width_px
        if hood_top_px is None:
            hood = np.full(w, float(h))
        else:
            hood = np.broadcast_to(np.asarray(hood_top_px, np.float64), (w,)).copy()
        self.hood_top = hood
        rows = np.arange(h)[:, None]
        self.keep = (rows < np.floor(hood)[None, :]).astype(np.uint8) * 255

    def undistort(self, frame: np.ndarray) -> np.ndarray:
        """Return the undistorted frame (unchanged without a lens)."""
        return self.undistorter.undistort(frame)

    def mask(self, undistorted: np.ndarray) -> np.ndarray:
        """Return the 0/255 mask of painted lines of an undistorted frame, hood left out."""
        return cv2.bitwise_and(combine(undistorted, self.config), self.keep)

    def analyse(self, frame: np.ndarray, undistorted: bool = False) -> _FrameAnalysis:
        """Return the frame's vanishing point, lines and mask (``frame`` raw unless ``undistorted``)."""
        und = frame if undistorted else self.undistort(frame)
        mask = self.mask(und)
        return self._analyse_mask(mask)

    def vanishing_point(self, frame: np.ndarray, undistorted: bool = False) -> VanishingPoint:
        """Return the vanishing point of the road in one frame (``VanishingPoint``)."""
        return self.analyse(frame, undistorted).vp

    def _analyse_mask(self, mask: np.ndarray) -> _FrameAnalysis:
        """Return the frame's analysis from its paint mask: the segments' vanishing point, the lines
        through it, the point refitted through those lines, and whether the road is straight."""
        w, h = self.size
        seg = _segments(mask, self.band_px, self.max_run_px)
        n = len(seg.length)

        def fail(reason: str, vp=None, inl: int = 0, lines=()) -> _FrameAnalysis:
            return _FrameAnalysis(VanishingPoint(vp, n, inl, lines, False, reason), mask, ())

        if n == 0:
            return fail("no road: no painted line was found; give frames of a road with painted "
                        "lane lines, in daylight")
        if n < MIN_SEGMENTS:
            return fail(f"too few line segments ({n}, need {MIN_SEGMENTS}): the lane lines are "
                        "faint, worn or hidden; give frames where both lane lines are visible")
        found = _ransac(seg, np.random.default_rng(RANSAC_SEED))
        if found is None:
            return fail(f"inconsistent: the {n} line segments meet in no one point; give frames "
                        "of a straight road with both lane lines visible")
        vp, inliers = found
        if inliers.sum() < MIN_SEGMENTS or seg.length[inliers].sum() < 0.25 * seg.length.sum():
            return fail(f"inconsistent: only {int(inliers.sum())} of {n} line segments point at one "
                        "vanishing point; give frames of a straight road with both lane lines "
                        "visible", None, int(inliers.sum()))
        up = _up_links(seg)
        inliers = _with_stubs(seg, vp, inliers, up)
        lines, fits, points = _lines_of(seg, _angle_groups(seg, vp, inliers), up, vp, h)
        if len(lines) < 2 or (max(l.angle_deg for l in lines) - min(l.angle_deg for l in lines)
                              < MIN_LINE_SEPARATION_DEG):
            return fail(f"too few lines: the segments form {len(lines)} line(s) through the vanishing "
                        "point, and it takes two lane lines; give frames where both lane lines are "
                        "visible", None, int(inliers.sum()), tuple(lines))
        vp, lines = _refitted_point(fits, lines, vp)
        below = [i for i, l in enumerate(lines) if abs(l.angle_deg) < 88.0]
        if len(below) < 2:
            return fail("too few lines: fewer than two lines lie below the point where they meet; give "
                        "frames of a road ahead (is the video rotated?)", None, int(inliers.sum()), tuple(lines))
        lines, fits, points = [lines[i] for i in below], [fits[i] for i in below], [points[i] for i in below]
        vpt = (float(vp[0]), float(vp[1]))
        if not (0.15 * w <= vp[0] <= 0.85 * w and 0.05 * h <= vp[1] <= 0.85 * h):
            return fail(f"inconsistent: the lines meet at ({vp[0]:.0f}, {vp[1]:.0f}) px, far from where "
                        "a camera looking along the road sees its vanishing point; is the frame "
                        "rotated, or the camera not looking ahead?", None, int(inliers.sum()),
                        tuple(lines))
        straight, reason = _straightness(seg, lines, vp, w)
        fits_out = tuple((f[0], f[1], f[2], f[3]) for f in fits)
        return _FrameAnalysis(VanishingPoint(vpt, n, int(inliers.sum()), tuple(lines), straight, reason),
                              mask, fits_out, tuple(points))


def _with_stubs(seg: _Segments, vp: np.ndarray, inliers: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Return the inliers joined by the stubs of dashes: a short dash cut by a band row leaves a
    stub whose direction is poor, so the segments that continue an inlier across a cut (``up``)
    and point at ``vp`` within 3 deg join the inliers."""
    n = len(seg.length)
    sin, below = _angle_errors(vp, seg.centre, _normals(seg.direction))
    loose = (sin < math.sin(math.radians(3.0))) & below
    for _ in range(2):
        linked = np.zeros(n, bool)
        has_up = up >= 0
        linked[up[has_up & inliers]] = True                 # the segment above an inlier
        linked[has_up] |= inliers[up[has_up]]               # the segment below an inlier
        inliers = inliers | (linked & loose)
    return inliers


def _angle_groups(seg: _Segments, vp: np.ndarray, inliers: np.ndarray) -> list[list[int]]:
    """Return the inlier segments grouped into lines by their angle about ``vp``: a gap of
    LINE_GAP_DEG or more starts a new line."""
    idx = np.flatnonzero(inliers)
    dv = seg.centre[idx] - vp
    ang = np.degrees(np.arctan2(dv[:, 0], dv[:, 1]))
    order = np.argsort(ang)
    groups, current = [], [idx[order[0]]]
    for a_prev, a, i in zip(ang[order[:-1]], ang[order[1:]], idx[order[1:]]):
        if a - a_prev >= LINE_GAP_DEG:
            groups.append(current)
            current = []
        current.append(i)
    groups.append(current)
    return groups


def _lines_of(seg: _Segments, groups: list[list[int]], up: np.ndarray, vp: np.ndarray, h: int) -> tuple[list, list, list]:
    """Return (lines, fits, points) of the groups long enough to be lines: each line's
    ``RoadLine`` (its bow measured along the segments that continue it up the image, ``up``),
    its straight fit (centroid, direction, top row, bottom row, run count) and its run centres."""
    lines, fits, points = [], [], []
    for g in groups:
        runs = np.isin(seg.run_segment, g)
        x, y = seg.run_x[runs], seg.run_y[runs]
        if len(x) < 6 or y.max() - y.min() < max(10.0, MIN_LINE_ROWS_FRACTION * h):
            continue
        c, d, _ = _fit_line(x, y)
        chain = np.isin(seg.run_segment, _follow_up(g, up))
        _, _, bow = _fit_line(seg.run_x[chain], seg.run_y[chain])
        a = math.degrees(math.atan2(c[0] - vp[0], c[1] - vp[1]))
        lines.append(RoadLine((float(c[0]), float(c[1])), (float(d[0]), float(d[1])),
                              (float(y.min()), float(y.max())), a, bow, len(x), len(g)))
        fits.append((c, d, float(y.min()), float(y.max()), len(x)))
        both = runs | chain
        points.append(np.column_stack([seg.run_x[both], seg.run_y[both]]))
    return lines, fits, points


def _refitted_point(fits: list, lines: list[RoadLine], vp: np.ndarray) -> tuple[np.ndarray, list[RoadLine]]:
    """Return the weighted least-squares intersection of the lines' fits (weighted by their run
    counts and spans, and by their slant), and the lines with their angles about it."""
    c = np.array([f[0] for f in fits])
    d = np.array([f[1] for f in fits])
    span = np.array([f[3] - f[2] for f in fits])
    cnt = np.array([f[4] for f in fits], np.float64)
    vp = _intersect(c, _normals(d), cnt * span ** 2 / np.maximum(np.abs(d[:, 1]), 0.05) ** 2, vp)
    lines = [RoadLine(l.point_px, l.direction, l.rows_px,
                      math.degrees(math.atan2(l.point_px[0] - vp[0], l.point_px[1] - vp[1])),
                      l.bow_px, l.points, l.segments) for l in lines]
    return vp, lines


def _straightness(seg: _Segments, lines: list[RoadLine], vp: np.ndarray, w: int) -> tuple[bool, str]:
    """Return (straight, reason): a long line bows more than MAX_BOW_PX + 0.3 % of its length, or
    the far segments' vanishing point lies aside of (a bend) or above or below (a crest, a dip)
    the near ones' by more than FAR_NEAR_TOLERANCE of the width, and the road is not straight."""
    bottom = max(l.rows_px[1] for l in lines)
    road_rows = max(bottom - vp[1], 1.0)
    for l in lines:
        length = (l.rows_px[1] - l.rows_px[0]) / max(l.direction[1], 1e-3)
        if l.rows_px[1] - l.rows_px[0] >= 0.2 * road_rows and l.bow_px > MAX_BOW_PX + 0.003 * length:
            return False, (f"road not straight: a lane line bows {l.bow_px:.1f} px from a straight "
                           "line; give frames of a straight stretch of road")
    found = _near_far_vps(seg, vp, road_rows)
    if found is not None:
        dx, dy = found[1] - found[0]
        tol = max(4.0, FAR_NEAR_TOLERANCE * w)
        if abs(dx) > tol:
            side = "right" if dx > 0 else "left"
            return False, (f"road not straight: the far lines point {abs(dx):.0f} px {side} of the near "
                           "ones (a bend); give frames of a straight stretch of road")
        if abs(dy) > tol:
            return False, (f"road not flat: the far lines vanish {abs(dy):.0f} px {'below' if dy > 0 else 'above'} "
                           "the near ones (a crest or a dip); give frames of a level stretch of road")
    return True, ""


def _band_vp(seg: _Segments, vp: np.ndarray, v_from: float, v_to: float) -> np.ndarray | None:
    """Return the vanishing point of the segments between ``v_from`` and ``v_to`` px below ``vp``,
    or None when they do not tell one: too few, fewer than two lines of some length (20 px or a
    tenth of the band's rows), or a point no nearer ``vp`` than the band itself."""
    v = seg.centre[:, 1] - vp[1]
    band = (v > v_from) & (v < v_to)
    if band.sum() < MIN_SEGMENTS:
        return None
    sub = _Segments(seg.centre[band], seg.direction[band], seg.length[band], seg.count[band],
                    seg.run_x[:0], seg.run_y[:0], seg.run_segment[:0])
    found = _ransac(sub, np.random.default_rng(RANSAC_SEED))
    if found is None or found[1].sum() < 3:
        return None
    p, inl = found
    if p[1] > vp[1] + v_from or abs(p[1] - vp[1]) > 0.5 * max(v_from, 20.0) + 20.0:
        return None
    ang = np.degrees(np.arctan2(sub.centre[inl, 0] - p[0], sub.centre[inl, 1] - p[1]))
    length = sub.length[inl]
    order = np.argsort(ang)
    cuts = np.flatnonzero(np.diff(ang[order]) >= LINE_GAP_DEG) + 1
    rows = min(v_to, float(v.max())) - v_from
    enough = max(20.0, 0.1 * rows)
    lines = sum(length[order][a:b].sum() >= enough
                for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(order)]))
    return p if lines >= 2 else None


def _near_far_vps(seg: _Segments, vp: np.ndarray, road_rows: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Return the vanishing points of the far part of the road (up to FAR_FRACTION of its rows
    below ``vp``: all segments there) and of the near part (from NEAR_FRACTION down: the segments
    within 3 deg of pointing at ``vp``, as the grain of near asphalt makes short segments of every
    direction), or None when either is unknown."""
    far = _band_vp(seg, vp, 2.0, FAR_FRACTION * road_rows)
    if far is None:
        return None
    sin, below = _angle_errors(vp, seg.centre, _normals(seg.direction))
    keep = (sin < math.sin(math.radians(3.0))) & below
    sub = _Segments(seg.centre[keep], seg.direction[keep], seg.length[keep], seg.count[keep],
                    seg.run_x[:0], seg.run_y[:0], seg.run_segment[:0])
    near = _band_vp(sub, vp, NEAR_FRACTION * road_rows, 1e9)
    return None if near is None else (near, far)


def vanishing_point(frame: np.ndarray, lens: Lens | Calibration | None = None,
                    hood_row_px: float | None = None) -> VanishingPoint:
    """Return the vanishing point of the road in one RAW frame (undistorted with ``lens``).

    A video checks for drift (a hill, a bump) by comparing it with the estimated geometry's
    ``vanishing_point_px`` every few seconds; for many frames make one ``RoadLineFinder``
    (it undistorts with maps computed once).
    """
    frame = _check_frame(frame, "frame")
    return RoadLineFinder((frame.shape[1], frame.shape[0]), lens, hood_row_px).vanishing_point(frame)


def _check_frame(frame, name: str) -> np.ndarray:
    """Return ``frame`` as a contiguous RGB uint8 array, or raise ``InputError`` (``io.check_rgb``)."""
    return io.check_rgb(frame, name)
