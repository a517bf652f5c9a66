"""The road geometry of a camera, estimated from frames of the road itself.

``estimate_geometry(frames)`` returns a ``RoadGeometry``: the vanishing point of the road
direction, the horizon (with the camera's roll), the hood, the points of a bird's-eye view that
reaches ``look_ahead_m`` ahead, its metric scale, and when a focal length is known (given, from a
calibration, or measured from the dashes) the camera's pitch, yaw and height. It says how
confident it is, what it assumed, and which frames it used and why it left the others out.
``RoadGeometry.perspective_config()`` is the ``perspective.PerspectiveConfig`` to run with.
``vanishing_point(frame)`` is the cheap per-frame part, for a video to check every few seconds
whether the vanishing point drifts (a hill, a bump, a camera knocked) and, from the straight
frames through the video, where the road heads on average: ``refined_geometry`` moves the point
(and the bird's-eye view with it) along the horizon to there (``runs.GeometryWatch``).

How each quantity is found (all in the undistorted image: frames are undistorted first when a
``camera.Lens`` or ``camera.Calibration`` is given):

- **Line segments.** The painted lines are masked (``thresholds``: paint 25 grey levels brighter
  than the road beside it, a horizontal top-hat as wide as 12 % of the image height).
  The mask is cut into horizontal bands (1/24 of the height); every connected piece of a band is
  a segment, described by the centres of its horizontal runs (one per row), so a segment is thin
  whatever the line's width. Segments that are not straight and thin (RMS off their axis above
  1 px), shorter than 1.2 % of the height or within 3 deg of horizontal are dropped.
- **Vanishing point of one frame.** RANSAC (fixed seed): the intersection of two segments drawn
  with probability by length, scored by the length of the segments that point at it within
  1.5 deg and lie below it; then weighted least squares on the inliers (each segment's distance
  to the point, weighted by its length squared over its distance squared: equal weight per
  angle), twice, the second time with 1 deg. Stubs of dashes cut by a band row join the inliers
  when they continue one across the cut and point at the point within 3 deg. The inliers are
  grouped into lines by their angle about the point (a gap of 1.2 deg or more starts a new
  line); each line is refitted through all its run centres, and the frame's point is the
  weighted least-squares intersection of those lines. A point outside the middle 70 % of the
  width or 5-85 % of the height, or fewer than two lines 4 deg apart below it, gives no point
  (the frame is rotated, or shows no road).
- **Straightness** ("the segments of each line are collinear"; frames where the road bends are
  left out). Each line is followed up the image through the segments that continue it across
  the band rows (bending or not), and a parabola fitted to all their run centres must bow less
  than ``MAX_BOW_PX`` + 0.3 % of the line's length from its chord (lines spanning a fifth of the
  road's rows or more); and the vanishing point of the far segments (the third of the road
  nearest the horizon) must lie within 0.8 % of the image width of that of the near ones, in x
  (a bend) and in y (a crest or a dip). On the bundled video both reject every frame on its
  900-2200 m curves. Across frames, a frame whose point lies more than 1 % of the image height
  (at least 3 px) from the median row, or 2.5 % of the width from the median column, is left out
  as inconsistent (a hill, a bump, a lane change).
- **The ego lane.** A road line at lateral offset t (m) from the camera, seen from height H,
  runs from the vanishing point at atan(t / H) from straight down (in coordinates turned by the
  roll). The ego lane's two lines are one on either side among the two nearest there, each
  20-80 deg from straight down. Its width r (below) is the one the road's lines agree on (lanes
  are equally wide): the width of the most frames' pairs plus frames with two adjacent lines on
  one side that far apart, so that neither the neighbour lanes' outer lines (three lanes wide,
  as centred on a car in a middle lane as its own) nor a dashed line not seen (two lanes wide)
  nor a bright seam in the lane is taken for the ego lane; each frame takes its most centred
  pair within 20 % of r, and frames with none are left out.
- **Horizon and roll.** The vanishing point of the road lies on the horizon. Its slope is the
  camera's roll, which lane lines of one direction cannot show by themselves: it is measured
  from the spacing of three or more lines (the ego lane's two and any line beyond them up to
  80 deg from straight down), assuming every lane has the same width. Along any image line
  parallel to the horizon, lines equally spaced on the road are equally spaced in the image
  (that image line is the picture of a road line whose own vanishing point is at infinity, so
  the map between them is affine); the roll that makes the lines' spacings whole multiples of
  the ego lane's in all frames is used when at least 3 frames give it one by one within 0.3 deg.
  On the synthetic cameras this gives the roll within 0.05 deg. Otherwise the roll is assumed 0
  and the assumptions say so; measured on the synthetic cameras rolled by 1.5 deg, ignoring the
  roll moves the horizon at the image centre by |w/2 - vp_x| tan(1.5 deg) (0.1 px with the
  vanishing point at the centre, 3.6 px on the narrow camera turned by 3 deg), puts the lane
  width 1.3 % off and the scale along the road 6-8 % off (the dashes are measured square to
  the wrong horizon).
- **Hood.** Given (``hood_row_px``), or from three frames or more (``detect_hood``): the hood is
  still while the road moves, and its top is an edge that stays put. The hood row is the
  highest row of that edge over the middle 80 % of the columns. When none is found (a still
  car, a single frame, no hood in view): just below the lowest lane-line pixel found.
- **Bird's-eye points.** In coordinates about the vanishing point turned by the roll (u along
  the horizon, v its distance below it), a road line at lateral offset t is u = k v with
  k = t cos(pitch) / (H cos(yaw)) + tan(yaw) sin(pitch); the ego lane's lines give
  r = k_right - k_left. The src trapezoid is centred on the camera's own line
  (k = tan(yaw) sin(pitch); 0 when the focal length is unknown: the camera is assumed on the
  car's centre line) and r/2 wide on each side; its bottom edge lies parallel to the horizon
  just above the hood (1 % of the height above it, and raised until its corners are inside the
  frame), its top edge parallel to the horizon where the road is ``look_ahead_m`` ahead of the
  camera (pulled in, and said so, when that is within 5 % of the height of the horizon). Edges
  parallel to the horizon make the warp an affine rectification of the road: lane lines become
  vertical and the scale is the same all over the view. dst is the rectangle of columns w/4
  and 3w/4 over the whole height.
- **Metric scale.** Across the road: the src sides are one lane width apart (``lane_width_m``,
  3.7 m by default), so xm_per_px = lane_width_m / (w/2). Along the road: the distance ahead
  of a point v px below the horizon is s = C / v + s0 (a pinhole over a flat road; s0 =
  -H tan(pitch)/cos(yaw), a few cm, 0 when the focal length is unknown). C is measured, in this
  order: from the dash period where dashed lines are seen (``_dash_scale``: along each lane
  line the dashes fall at even steps of 1/v, (dash_m + gap_m) / C apart; only lines a whole
  lane width from the ego lane's count, runs that are not a dash's length once the blur is
  allowed for (raised markers, flecks, merged dashes) are dropped, and the period must hold
  without any one frame), else from the focal length
  (a calibration's K or ``focal_px``) and the lane width
  (C = f lane_width_m / (r cos(pitch) cos^2(yaw))), else from an assumed focal length (a 60 deg
  horizontal field of view), which the result states. With the dash period, the focal length
  follows from the same formula, so the pitch, yaw and camera height are given too (with the
  principal point at the image centre unless a calibration gives it).
- **Confidence** (0-1): the product of min(1, frames used / 5), how well the frames pin the
  vanishing point (1 up to 1 px of standard error of their mean row, falling off beyond: a car
  pitching over bumps scatters single frames by a few px, and many frames still pin it), min(1, frames showing the
  ego lane / 5), the source of the scale (dashes 1, focal length 0.9 (FOCAL_CONFIDENCE), dashes and focal length
  disagreeing by more than 8 % 0.75, and then the focal length is used, assumed focal length 0.4), 0.9 when the hood was not
  found, and 0.4 when the focal length and the lane width put the camera at an implausible
  height (``CAMERA_HEIGHT_RANGE_M``, 0.7-4 m: the lines were paired wrongly; the assumptions
  say so), and 0.4 again when the ego lane's lines, carried into the bird's-eye view, are not
  parallel: its width at the top differs from that at the bottom by more than
  LANE_PARALLEL_TOLERANCE (2.5 %; frames' median; ``_view_widening``): a lens that distorts
  and was not given (a straight line's image bends), or a road that is not flat. Below ``LOW_CONFIDENCE`` a pipeline should refuse the result unless told to use it.

- **Lens** (no ``lens`` given; ``estimate_lens``): the bend of the lines on the straight frames
  measures a one-parameter radial model about the image centre; when it is clearly non-zero
  and well determined the frames are undistorted with it, everything above is measured again
  in the undistorted frames, and ``RoadGeometry.lens`` holds it (a ``camera.Calibration`` marked
  ``estimated``, its focal length the one the geometry found or assumed). Undistortion with the
  frame's own camera matrix pushes the near dashes out of the frame: when too few are left for
  a period, it is measured on the frames undistorted onto a canvas LENS_CANVAS_PAD (10 %)
  larger each side, and its focal length sets the scale; failing that, the raw frames' dash
  period does, with the confidence multiplied by RAW_DASH_CONFIDENCE (0.6): measured through
  the lens, it is a few % off. Otherwise the assumptions say why no lens was used.

Frames that give no consistent vanishing point raise ``errors.GeometryError`` naming the reason:
no road (no line segments), too few segments, inconsistent (segments that meet in no point, or
points that disagree between frames), road not straight.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Iterable

import cv2
import numpy as np

from . import io
from .camera import Calibration, Lens, Undistorter
from .errors import GeometryError, InputError
from .perspective import DEFAULT_LANE_WIDTH_M, Perspective, PerspectiveConfig
from .thresholds import ThresholdConfig, TopHatMask, combine

DEFAULT_LOOK_AHEAD_M = 25.0
DEFAULT_DASH_M = 3.0
DEFAULT_GAP_M = 9.0
ASSUMED_HFOV_DEG = 60.0
LOW_CONFIDENCE = 0.5
DRIFT_PX = 3.0          # a vanishing point this far off the horizon has drifted (see horizon_shift_px)
MIN_GOOD_FRAMES = 5     # frames on straight road for full confidence
RANSAC_SEED = 15
RANSAC_HYPOTHESES = 200
MAX_SEGMENTS = 250
RANSAC_TOL_DEG = 1.5
INLIER_TOL_DEG = 1.0
LINE_GAP_DEG = 1.2
MIN_SEGMENTS = 4
MIN_LINE_SEPARATION_DEG = 4.0
MIN_LINE_ROWS_FRACTION = 0.02  # a line spans at least this share of the rows (and 10)
MAX_BOW_PX = 1.5
# A frame's vanishing point more than this share of the width from the others' is left out: the
# car's heading moves it by about f tan(heading) (1 deg: 1.6 % of the width at a 60 deg field of
# view); more is a bend whose lines still pass as straight (a 900 m curve: 3.5 %).
VP_X_TOLERANCE = 0.025
BAND_FRACTION = 1 / 24
TOPHAT_FRACTION = 0.12
TOPHAT_GREY = 25
HOOD_STATIC_GREY = 1.5
HOOD_EDGE_GREY = 6.0
HOOD_MAX_FRAMES = 15            # frames (evenly spread) the hood is looked for in
HOOD_MAX_FRACTION = 0.35
MAX_ROLL_DEG = 4.0
ROLL_MAX_LINE_ANGLE_DEG = 80.0  # lines flatter than this (|k| > 5.7) tell the roll too loosely
ROLL_MIN_FRAMES = 3
EGO_ANGLES_DEG = (20.0, 80.0)
ROLL_MAX_SPREAD_DEG = 0.3
DASH_DISAGREEMENT = 0.08
FAR_FRACTION = 0.35
NEAR_FRACTION = 0.45
FAR_NEAR_TOLERANCE = 0.008
DASH_V_MIN_FRACTION = 0.02
DASH_MIN_PERIODS = 1.5
DASH_MIN_FIT = 0.5             # mean cos of the dash pairs' phase at the period found
DASH_MIN_PAIRS = 3
DASH_LANE_TOLERANCE = 0.25     # lane widths: a line this near a whole number of lanes from the ego lane's is a lane line
DASH_BLUR_MIN_RUNS = 5         # long single dashes it takes to fit the blur (b); fewer: b = 0
DASH_LENGTH_WINDOW = (0.6, 1.6)  # a run less its blur, in dash lengths, to be a dash
DASH_CONSISTENCY = DASH_DISAGREEMENT  # a sub-sample's best period within this fraction of the period found
# The period is searched from C / DASH_LENGTH_RANGE to C * DASH_LENGTH_UP, C what the dashes'
# lengths say. Higher up because a dash's length in the image is biased long (blur, a smeared or
# dilated mask, a raised marker at its end), so its C low; never up to 2: the period's harmonic
# at twice C fits the dash pairs as well as the period itself.
DASH_LENGTH_RANGE = 1.35
DASH_LENGTH_UP = 1.7
DASH_FOCAL_RANGE = 1.35        # with a known focal length, C is searched within this factor of its C
FOCAL_RANGE_W = (0.3, 3.5)     # else focal lengths from 0.3 to 3.5 image widths (hfov 16-118 deg)
# A camera this high above the road or more, or this low or less, is no road camera (a car's
# dashcam sits 1.0-1.6 m up, a truck's 2-3 m): the lane width was measured between the wrong lines
CAMERA_HEIGHT_RANGE_M = (0.7, 4.0)
# the ego lane may widen or narrow by this fraction from the bottom third of the bird's-eye view to
# its top third (frames' median) before the view is taken as wrong: a lens not given, a road not flat
LANE_PARALLEL_TOLERANCE = 0.025
IMPLAUSIBLE_CONFIDENCE = 0.4   # the confidence is multiplied by this then (below LOW_CONFIDENCE)
FOCAL_CONFIDENCE = 0.9         # ... by this when the scale along the road is a focal length's, not dashes'

Point = tuple[float, float]


# --------------------------------------------------------------------------- records

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
class RoadGeometry:
    """The bird's-eye geometry of a camera estimated from frames of the road (``estimate_geometry``).

    Positions are in the undistorted image (px, y down), angles in degrees. ``horizon_row_px`` is
    the horizon's row at the image centre column (w/2) and ``horizon_slope`` its rows per column;
    ``roll_deg`` is positive when the camera's right side dips (the horizon rises to the right).
    ``pitch_deg`` (positive down), ``yaw_deg`` (positive right, the optical axis from the road
    direction) and ``camera_height_m`` are None when no focal length is known. ``src_px`` and
    ``dst_px`` are the bird's-eye points (tl, bl, br, tr), ``near_m`` and ``look_ahead_m`` the
    distances ahead of the camera of their bottom and top edges, ``visible_length_m`` the road
    between them. ``inverse_depth_scale_px_m`` is C in s = C / v + s0 and ``lane_width_ratio``
    the ego lane's r (see the module docstring); ``dash_fit`` how well the dashes fit the dash
    period found (1: perfectly; 0: no dashes seen; used from DASH_MIN_FIT).
    ``frames_rejected`` holds (frame index, reason) pairs. ``lens`` is the lens estimated from
    the road's lines when none was given (``estimate_lens``; a ``camera.Calibration`` marked
    ``estimated``): the positions are then in the image undistorted with it, and a pipeline
    must undistort with it too. None: the lens given, or none (see the assumptions).
    """

    size_px: tuple[int, int]
    vanishing_point_px: Point
    horizon_row_px: float
    horizon_slope: float
    roll_deg: float
    roll_source: str
    pitch_deg: float | None
    yaw_deg: float | None
    camera_height_m: float | None
    focal_px: float | None
    focal_source: str
    hood_row_px: float
    hood_source: str
    src_px: tuple[Point, ...]
    dst_px: tuple[Point, ...]
    lane_width_m: float
    look_ahead_m: float
    near_m: float
    visible_length_m: float
    xm_per_px: float
    ym_per_px: float
    scale_source: str
    inverse_depth_scale_px_m: float
    lane_width_ratio: float
    dash_fit: float
    confidence: float
    assumptions: tuple[str, ...]
    frames_used: tuple[int, ...]
    frames_rejected: tuple[tuple[int, str], ...]
    frame_vanishing_points: tuple[tuple[int, float, float], ...] = field(default=(), repr=False)
    lens: Calibration | None = field(default=None, repr=False)

    def perspective_config(self) -> PerspectiveConfig:
        """Return the ``PerspectiveConfig`` of these bird's-eye points and scale."""
        d = np.asarray(self.dst_px, np.float64)
        car_x = float((d[:, 0].min() + d[:, 0].max()) / 2)  # the camera's own line: the car's centre
        return PerspectiveConfig(self.src_px, self.dst_px, self.size_px, self.lane_width_m,
                                 self.visible_length_m, car_x)

    def perspective(self) -> Perspective:
        """Return the ``Perspective`` (undistorted image <-> bird's-eye view) of these points."""
        return Perspective(self.perspective_config())

    def horizon_shift_px(self, point_px: Point) -> float:
        """Return how far (px) a frame's vanishing point lies below this horizon (negative: above).

        A video checks for drift with it: a bend or the car's heading moves the vanishing point
        along the horizon, a crest, a dip or a knocked camera moves it off; more than
        ``DRIFT_PX`` (or 1 % of the height) on several checks in a row calls for a new estimate.
        """
        r = math.radians(self.roll_deg)
        return float((point_px[0] - self.vanishing_point_px[0]) * math.sin(r)
                     + (point_px[1] - self.vanishing_point_px[1]) * math.cos(r))

    @property
    def low_confidence(self) -> bool:
        """Return True when the confidence is below ``LOW_CONFIDENCE``."""
        return self.confidence < LOW_CONFIDENCE

    def summary(self) -> str:
        """Return the geometry in a few lines of text (what the CLI prints)."""
        vx, vy = self.vanishing_point_px
        angles = ("pitch, yaw: unknown (no focal length)" if self.pitch_deg is None else
                  f"pitch {self.pitch_deg:+.2f} deg, yaw {self.yaw_deg:+.2f} deg, camera "
                  f"{self.camera_height_m:.2f} m above the road (focal {self.focal_px:.0f} px, "
                  f"{self.focal_source})")
        return "\n".join([
            f"vanishing point ({vx:.1f}, {vy:.1f}) px, horizon row {self.horizon_row_px:.1f} px at the "
            f"centre, roll {self.roll_deg:+.2f} deg ({self.roll_source})",
            angles,
            f"hood row {self.hood_row_px:.0f} px ({self.hood_source}); bird's-eye view from "
            f"{self.near_m:.1f} m to {self.look_ahead_m:.1f} m ahead",
            f"{self.xm_per_px:.5f} m/px across, {self.ym_per_px:.5f} m/px along ({self.scale_source})",
            f"confidence {self.confidence:.2f}; {len(self.frames_used)} frames used, "
            f"{len(self.frames_rejected)} left out",
        ])

    def to_dict(self) -> dict:
        """Return the geometry as JSON-able values."""
        r = lambda v, nd=4: None if v is None else round(float(v), nd)  # noqa: E731
        pts = lambda ps: [[r(x, 3), r(y, 3)] for x, y in ps]  # noqa: E731
        return {
            "size_px": list(self.size_px),
            "vanishing_point_px": [r(v, 3) for v in self.vanishing_point_px],
            "horizon_row_px": r(self.horizon_row_px, 3), "horizon_slope": r(self.horizon_slope, 6),
            "roll_deg": r(self.roll_deg), "roll_source": self.roll_source,
            "pitch_deg": r(self.pitch_deg), "yaw_deg": r(self.yaw_deg),
            "camera_height_m": r(self.camera_height_m), "focal_px": r(self.focal_px, 2),
            "focal_source": self.focal_source,
            "hood_row_px": r(self.hood_row_px, 1), "hood_source": self.hood_source,
            "src_px": pts(self.src_px), "dst_px": pts(self.dst_px),
            "lane_width_m": self.lane_width_m, "look_ahead_m": r(self.look_ahead_m, 3),
            "near_m": r(self.near_m, 3), "visible_length_m": r(self.visible_length_m, 4),
            "xm_per_px": r(self.xm_per_px, 7), "ym_per_px": r(self.ym_per_px, 7),
            "scale_source": self.scale_source,
            "inverse_depth_scale_px_m": r(self.inverse_depth_scale_px_m, 2),
            "lane_width_ratio": r(self.lane_width_ratio, 5),
            "dash_fit": r(self.dash_fit, 3),
            "confidence": r(self.confidence, 3), "assumptions": list(self.assumptions),
            "frames_used": list(self.frames_used),
            "frames_rejected": [[i, why] for i, why in self.frames_rejected],
        } | ({} if self.lens is None else {"lens": self.lens.to_dict()})


# --------------------------------------------------------------------------- masks and segments

def paint_mask_config(size_px: tuple[int, int]) -> ThresholdConfig:
    """Return the mask of painted lines used for the geometry, for frames of ``size_px``.

    Pixels TOPHAT_GREY (25) grey levels (HLS lightness) brighter than the road beside them: a horizontal
    top-hat 12 % of the image height wide, wider than a line's run across any row of the road.
    No colour test: far from the lens centre, vignetting and haze leave white paint at a
    lightness of 100 or less, and yellow paint is brighter than asphalt too.
    """
    width = max(15, int(round(TOPHAT_FRACTION * size_px[1])) | 1)
    return ThresholdConfig(line_tophat=TopHatMask("hls", "l", width, TOPHAT_GREY, 255), rule="line_tophat")


@dataclass(frozen=True)
class _Segments:
    """Band segments of a mask: per segment centre, unit direction (down), length, count; per run
    its centre and its segment (-1: none)."""

    centre: np.ndarray      # (N, 2)
    direction: np.ndarray   # (N, 2), dy >= 0
    length: np.ndarray      # (N,)
    count: np.ndarray       # (N,)
    run_x: np.ndarray
    run_y: np.ndarray
    run_segment: np.ndarray


def _segments(mask: np.ndarray, band_px: int, max_run_px: int) -> _Segments:
    """Return the straight thin band segments of a 0/255 mask (see the module docstring)."""
    h, w = mask.shape
    cut = mask.copy()
    cut[::band_px] = 0
    _, labels = cv2.connectedComponents(cut, connectivity=8)
    padded = np.zeros((h, w + 2), np.int8)
    padded[:, 1:-1] = cut > 0
    d = np.diff(padded, axis=1)
    ys, x0 = np.nonzero(d == 1)
    _, x1 = np.nonzero(d == -1)
    keep = (x1 - x0) <= max_run_px
    ys, x0, x1 = ys[keep], x0[keep], x1[keep]
    xc = (x0 + x1 - 1) * 0.5
    lab = labels[ys, x0]
    n_lab = int(lab.max()) + 1 if lab.size else 1
    yf = ys.astype(np.float64)
    cnt = np.bincount(lab, minlength=n_lab).astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx = np.bincount(lab, xc, n_lab) / cnt
        my = np.bincount(lab, yf, n_lab) / cnt
        vxx = np.bincount(lab, xc * xc, n_lab) / cnt - mx * mx
        vyy = np.bincount(lab, yf * yf, n_lab) / cnt - my * my
        vxy = np.bincount(lab, xc * yf, n_lab) / cnt - mx * my
    half_tr = (vxx + vyy) / 2
    disc = np.sqrt(np.maximum(half_tr ** 2 - (vxx * vyy - vxy ** 2), 0.0))
    lam1, lam2 = half_tr + disc, np.maximum(half_tr - disc, 0.0)
    theta = 0.5 * np.arctan2(2 * vxy, vxx - vyy)
    dx, dy = np.cos(theta), np.sin(theta)
    flip = dy < 0
    dx[flip], dy[flip] = -dx[flip], -dy[flip]
    length = np.sqrt(12 * np.maximum(lam1, 0.0))
    ok = ((cnt >= 5) & (length >= max(8.0, 0.012 * h)) & (np.sqrt(lam2) <= 1.0)
          & (dy >= math.sin(math.radians(3.0))))
    ok[0] = False
    idx = np.flatnonzero(ok)
    if len(idx) > MAX_SEGMENTS:       # the longest: the rest are flecks of asphalt, leaves, noise
        idx = np.sort(idx[np.argsort(-length[idx], kind="stable")[:MAX_SEGMENTS]])
    seg_of_label = np.full(n_lab, -1)
    seg_of_label[idx] = np.arange(len(idx))
    return _Segments(np.column_stack([mx[idx], my[idx]]), np.column_stack([dx[idx], dy[idx]]),
                     length[idx], cnt[idx], xc, yf, seg_of_label[lab])


def _normals(direction: np.ndarray) -> np.ndarray:
    return np.column_stack([-direction[:, 1], direction[:, 0]])


def _angle_errors(vp: np.ndarray, centre: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (sin of the angle between each segment and the direction to ``vp``, whether the
    segment lies below ``vp``) for vp of shape (2,) or (K, 2) (then (K, N) arrays)."""
    dv = vp[..., None, :] - centre                      # (..., N, 2)
    dist = np.hypot(dv[..., 0], dv[..., 1])
    sin = np.abs((dv * normal).sum(-1)) / np.maximum(dist, 1e-9)
    return sin, dv[..., 1] < -2.0


def _intersect(centre: np.ndarray, normal: np.ndarray, weight: np.ndarray, start: np.ndarray,
               iterations: int = 3) -> np.ndarray:
    """Return the weighted least-squares intersection of lines (centre, normal), re-weighted by
    1 / distance^2 from the current point (equal weight per angle)."""
    p = start.astype(np.float64)
    nn = normal[:, :, None] * normal[:, None, :]            # (N, 2, 2)
    for _ in range(iterations):
        d2 = np.maximum(((centre - p) ** 2).sum(1), 1.0)
        wt = weight / d2
        a = (wt[:, None, None] * nn).sum(0)
        b = (wt[:, None, None] * nn @ centre[:, :, None])[:, :, 0].sum(0)
        if abs(np.linalg.det(a)) < 1e-12 * max(np.abs(a).max(), 1e-300) ** 2:
            break
        p = np.linalg.solve(a, b)
    return p


def _ransac(seg: _Segments, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray] | None:
    """Return (vanishing point, inlier mask) of the segments, or None when no point gathers them."""
    n = len(seg.length)
    normal = _normals(seg.direction)
    prob = seg.length / seg.length.sum()
    pairs = rng.choice(n, size=(RANSAC_HYPOTHESES, 2), p=prob)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    lines = np.column_stack([normal, -(normal * seg.centre).sum(1)])
    hom = np.cross(lines[pairs[:, 0]], lines[pairs[:, 1]])
    good = np.abs(hom[:, 2]) > 1e-9
    if not good.any():
        return None
    vps = hom[good, :2] / hom[good, 2:3]
    sin, below = _angle_errors(vps, seg.centre, normal)
    inl = (sin < math.sin(math.radians(RANSAC_TOL_DEG))) & below
    score = (inl * seg.length).sum(1)
    best = int(np.argmax(score))
    vp, inliers = vps[best], inl[best]
    for tol in (RANSAC_TOL_DEG, INLIER_TOL_DEG):
        if inliers.sum() < 2:
            return None
        vp = _intersect(seg.centre[inliers], normal[inliers], seg.length[inliers] ** 2, vp)
        sin, below = _angle_errors(vp, seg.centre, normal)
        inliers = (sin < math.sin(math.radians(tol))) & below
    return vp, inliers


def _up_links(seg: _Segments) -> np.ndarray:
    """Return, for every segment, the segment that continues it in the band above (-1: none).

    The continuation's bottom end lies within 3 px (plus 2 px per unit of the line's slant) of
    the segment's top end and points the same way within 10 deg: the same painted line across
    the cut row, straight or bending.
    """
    n = len(seg.length)
    if n < 2:
        return np.full(n, -1)
    half = seg.direction * (seg.length / 2)[:, None]
    top, bottom = seg.centre - half, seg.centre + half
    dist = np.hypot(*(top[:, None, :] - bottom[None, :, :]).transpose(2, 0, 1))    # [j, i]
    cos = seg.direction @ seg.direction.T
    tol = 3.0 + 2.0 / np.maximum(seg.direction[:, 1], 0.1)
    ok = (dist <= tol[:, None]) & (cos >= math.cos(math.radians(10.0)))
    ok &= seg.centre[None, :, 1] < seg.centre[:, None, 1]
    np.fill_diagonal(ok, False)
    dist = np.where(ok, dist, np.inf)
    best = np.argmin(dist, axis=1)
    return np.where(np.isfinite(dist[np.arange(n), best]), best, -1)


def _follow_up(start, up: np.ndarray) -> list[int]:
    """Return ``start`` and every segment reached from it by following ``up`` links."""
    seen = set(int(i) for i in start)
    todo = list(seen)
    while todo:
        j = int(up[todo.pop()])
        if j >= 0 and j not in seen:
            seen.add(j)
            todo.append(j)
    return sorted(seen)


def _along_across(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (unit direction pointing down, along, across) of points ``q`` about their centroid:
    the line's straight fit (SVD) and each point's coordinates along it and across it."""
    _, _, vt = np.linalg.svd(q, full_matrices=False)
    d = vt[0] if vt[0, 1] >= 0 else -vt[0]
    return d, q @ d, q @ np.array([-d[1], d[0]])


def _fit_line(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Return (centroid, unit direction pointing down, bow px) of points along one line."""
    c = np.array([x.mean(), y.mean()])
    d, along, across = _along_across(np.column_stack([x, y]) - c)
    span = along.max() - along.min()
    bow = 0.0
    if span > 0 and len(along) >= 5:
        a2 = np.polyfit(along / span, across, 2)[0]
        bow = abs(a2) * 0.25
    return c, d, float(bow)


# --------------------------------------------------------------------------- one frame

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
        # a short dash cut by a band row leaves a stub whose direction is poor: the segments that
        # continue an inlier across a cut and point at the point within 3 deg join the inliers
        up = _up_links(seg)
        sin, below = _angle_errors(vp, seg.centre, _normals(seg.direction))
        loose = (sin < math.sin(math.radians(3.0))) & below
        for _ in range(2):
            linked = np.zeros(n, bool)
            has_up = up >= 0
            linked[up[has_up & inliers]] = True                 # the segment above an inlier
            linked[has_up] |= inliers[up[has_up]]               # the segment below an inlier
            inliers = inliers | (linked & loose)
        # group the inlier segments into lines by their angle about the point
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
        if len(lines) < 2 or (max(l.angle_deg for l in lines) - min(l.angle_deg for l in lines)
                              < MIN_LINE_SEPARATION_DEG):
            return fail(f"too few lines: the segments form {len(lines)} line(s) through the vanishing "
                        "point, and it takes two lane lines; give frames where both lane lines are "
                        "visible", None, int(inliers.sum()), tuple(lines))
        c = np.array([f[0] for f in fits])
        d = np.array([f[1] for f in fits])
        span = np.array([f[3] - f[2] for f in fits])
        cnt = np.array([f[4] for f in fits], np.float64)
        vp = _intersect(c, _normals(d), cnt * span ** 2 / np.maximum(np.abs(d[:, 1]), 0.05) ** 2, vp)
        lines = [RoadLine(l.point_px, l.direction, l.rows_px,
                          math.degrees(math.atan2(l.point_px[0] - vp[0], l.point_px[1] - vp[1])),
                          l.bow_px, l.points, l.segments) for l in lines]
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
        bottom = max(l.rows_px[1] for l in lines)
        road_rows = max(bottom - vp[1], 1.0)
        reason, straight = "", True
        for l in lines:
            length = (l.rows_px[1] - l.rows_px[0]) / max(l.direction[1], 1e-3)
            if l.rows_px[1] - l.rows_px[0] >= 0.2 * road_rows and l.bow_px > MAX_BOW_PX + 0.003 * length:
                straight = False
                reason = (f"road not straight: a lane line bows {l.bow_px:.1f} px from a straight "
                          "line; give frames of a straight stretch of road")
                break
        if straight:
            found = _near_far_vps(seg, vp, road_rows)
            if found is not None:
                dx, dy = found[1] - found[0]
                tol = max(4.0, FAR_NEAR_TOLERANCE * w)
                if abs(dx) > tol:
                    straight = False
                    side = "right" if dx > 0 else "left"
                    reason = (f"road not straight: the far lines point {abs(dx):.0f} px {side} of the near "
                              "ones (a bend); give frames of a straight stretch of road")
                elif abs(dy) > tol:
                    straight = False
                    reason = (f"road not flat: the far lines vanish {abs(dy):.0f} px {'below' if dy > 0 else 'above'} "
                              "the near ones (a crest or a dip); give frames of a level stretch of road")
        fits_out = tuple((f[0], f[1], f[2], f[3]) for f in fits)
        return _FrameAnalysis(VanishingPoint(vpt, n, int(inliers.sum()), tuple(lines), straight, reason),
                              mask, fits_out, tuple(points))


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


# --------------------------------------------------------------------------- hood

# --------------------------------------------------------------------------- the lens, from the lines' bend

@dataclass(frozen=True)
class LensEstimate:
    """A one-parameter radial model of a lens, measured from straight road lines (plumb lines).

    A point at distance r_u from the image centre in the undistorted image lies at
    r_d = r_u (1 + lam r_u^2) in the raw one (lam in px^-2: negative for barrel distortion,
    positive for pincushion; OpenCV's k1 is lam f^2 for a focal length f, and no focal length is
    needed to measure it). ``kappa`` is lam times the squared half-diagonal R (dimensionless: the
    relative shift of a point R from the centre). ``bend_px`` is the lines' mean bow (px,
    weighted by their points) through no model and ``residual_bend_px`` through this one;
    ``frames``, ``lines`` how many gave it; ``frame_kappas`` each frame's own kappa; ``kappa_se``
    kappa's standard error (from the points' scatter about each line's parabola).
    ``applied`` says whether it is clearly non-zero and well determined (``reason`` why not).
    """

    lam: float
    kappa: float
    kappa_se: float
    bend_px: float
    residual_bend_px: float
    frames: int
    lines: int
    frame_kappas: tuple[float, ...]
    applied: bool
    reason: str

    def calibration(self, size_px: tuple[int, int], focal_px: float) -> Calibration:
        """Return the model as a ``camera.Calibration`` (principal point at the centre, focal
        ``focal_px``, k1 and k2 fitted to the division model over the frame's radii), marked
        estimated."""
        w, h = size_px
        K = np.array([[focal_px, 0.0, w / 2], [0.0, focal_px, h / 2], [0.0, 0.0, 1.0]])
        k1 = self.lam * focal_px ** 2
        return Calibration(K, np.array([k1, 0.0, 0.0, 0.0, 0.0]), (int(w), int(h)),
                           estimated=(f"from the road's straight lines (radial model lam {self.lam:.4g} "
                                      f"px^-2, kappa {self.kappa:+.4f}); focal length "
                                      f"{focal_px:.0f} px as the geometry has it"))


LENS_KAPPA_RANGE = (-0.6, 0.3)   # searched: a point at the corner's distance moved up to 45 % in, 30 % out
LENS_KAPPA_STEP = 0.03
LENS_MIN_SIGMAS = 5.0           # kappa this many standard errors from 0 to be used
LENS_MIN_BEND_PX = 0.3           # the lines' mean bow (px) the model must explain to be used
LENS_MIN_EXPLAINED = 0.6         # share of that bow it must explain
LENS_MIN_FRAMES = 3
LENS_MAX_SPREAD = 0.35           # frames' kappas' median absolute deviation, of |kappa|
LENS_MIN_SAME_SIGN = 0.65        # share of the frames whose kappa has its sign
LENS_CANVAS_PAD = 0.1           # undistorted frames on a canvas this much of the frame larger each side, for dashes
RAW_DASH_CONFIDENCE = 0.6       # the confidence is multiplied by this when the scale is the raw frames' dashes'
LENS_MIN_LINE_ROWS = 0.1         # a line spans this share of the height to count


def radial_undistort(points: np.ndarray, lam: float, size_px: tuple[int, int]) -> np.ndarray:
    """Return ``points`` (N, 2) of the raw image undistorted by the one-parameter radial model
    about the centre: the raw point lies at r_d = r_u (1 + lam r_u^2) (px) from the centre, r_u its
    undistorted distance. Points past the model's fold (barrel, lam < 0: r_d above
    2 / (3 sqrt(-3 lam))) are NaN (they are left out of the fits of that model)."""
    c = np.array([size_px[0] / 2, size_px[1] / 2])
    d = np.asarray(points, np.float64) - c
    rd = np.hypot(d[:, 0], d[:, 1])
    ru = rd.copy()
    for _ in range(8):   # Newton on r + lam r^3 = r_d, from r = r_d
        ru = ru - (ru + lam * ru ** 3 - rd) / (1 + 3 * lam * ru ** 2)
    if lam < 0:
        ru[rd > 2 / (3 * math.sqrt(-3 * lam))] = np.nan
    scale = np.where(rd > 0, ru / np.maximum(rd, 1e-12), 1.0)
    return c + d * scale[:, None]


def _signed_bows(points: np.ndarray, line_id: np.ndarray, n_lines: int) -> tuple[np.ndarray, np.ndarray]:
    """Return per line (signed bow px: how far the parabola fitted along it bows from its chord,
    across its own straight fit; the RMS px of its points off that parabola)."""
    bows, rms = np.zeros(n_lines), np.full(n_lines, np.inf)
    ok = np.isfinite(points[:, 0])
    for i in range(n_lines):
        p = points[(line_id == i) & ok]
        if len(p) < 10:
            continue
        _, along, across = _along_across(p - p.mean(0))
        span = max(float(np.ptp(along)), 1e-9)
        coef = np.polyfit(along / span, across, 2)
        bows[i] = coef[0] * 0.25
        rms[i] = float(np.sqrt(np.mean((across - np.polyval(coef, along / span)) ** 2)))
    return bows, rms


def estimate_lens(lines_by_frame: list[list[np.ndarray]], size_px: tuple[int, int]) -> LensEstimate | None:
    """Return the division model (``LensEstimate``) that makes the lines straight, or None when
    fewer than two lines are long enough.

    ``lines_by_frame``: per frame, the run centres (N, 2) of each painted line found on straight
    road (``_FrameAnalysis.line_points``). Each line's signed bow (the parabola fitted along it,
    from its chord) is nearly linear in kappa; kappa is the weighted least-squares zero of all
    the bows (weights: the bow's inverse variance from the points' scatter about the parabola),
    by Newton steps. Lines through the centre do not bend whatever the lens (a radial line stays
    straight), so they weigh nothing. It is applied when the lines' mean bow through no model is
    ``LENS_MIN_BEND_PX`` or more, the model removes ``LENS_MIN_EXPLAINED`` of it, kappa is
    ``LENS_MIN_SIGMAS`` standard errors from 0, and ``LENS_MIN_FRAMES`` frames or more each give
    a kappa of its sign within ``LENS_MAX_SPREAD`` (median absolute deviation) of it: a lens
    bends every line its way about the centre, a bend of the road bends them all one way.
    """
    w, h = size_px
    pts, lid, fid = [], [], []
    n_lines = 0
    for f, lines in enumerate(lines_by_frame):
        for p in lines:
            if len(p) < 20 or np.ptp(p[:, 1]) < LENS_MIN_LINE_ROWS * h:
                continue
            pts.append(p)
            lid.append(np.full(len(p), n_lines))
            fid.append(f)
            n_lines += 1
    if n_lines < 2:
        return None
    pts_all = np.concatenate(pts).astype(np.float64)
    lid_all = np.concatenate(lid)
    fid = np.array(fid)
    cnt = np.bincount(lid_all, minlength=n_lines).astype(np.float64)
    r2 = (math.hypot(w, h) / 2) ** 2

    def bows(kappa: float) -> tuple[np.ndarray, np.ndarray]:
        return _signed_bows(radial_undistort(pts_all, kappa / r2, size_px), lid_all, n_lines)

    b0, rms0 = bows(0.0)
    weight = cnt / (11.25 * np.maximum(rms0, 0.1) ** 2)     # 1 / var(bow) of a parabola's fit
    grid = np.arange(LENS_KAPPA_RANGE[0], LENS_KAPPA_RANGE[1] + 1e-9, LENS_KAPPA_STEP)
    chi = np.array([weight * bows(k)[0] ** 2 for k in grid])   # (grid, lines)
    step = float(grid[1] - grid[0])

    def best(total: np.ndarray) -> tuple[float, float]:
        """(kappa, standard error) at the least chi-square, refined by a parabola."""
        i = int(np.argmin(total))
        if 0 < i < len(grid) - 1:
            y0, y1, y2 = total[i - 1:i + 2]
            den = y0 - 2 * y1 + y2
            if den > 0:
                return float(grid[i] + 0.5 * (y0 - y2) / den * step), math.sqrt(2 * step ** 2 / den)
        return float(grid[i]), float("inf")

    kappa, se = best(chi.sum(1))
    frames = np.unique(fid)
    frame_kappas = tuple(best(chi[:, fid == f].sum(1))[0] for f in frames)
    bend = float(np.sqrt(np.average(b0 ** 2, weights=weight)))
    rest = float(np.sqrt(np.average(bows(kappa)[0] ** 2, weights=weight)))
    fk = np.array(frame_kappas)
    spread = float(np.median(np.abs(fk - kappa)))
    same = float(np.mean(np.sign(fk) == np.sign(kappa)))
    if bend < LENS_MIN_BEND_PX:
        reason = f"the lines bow {bend:.2f} px on average, under {LENS_MIN_BEND_PX:g} px: too little to measure a lens by"
    elif bend - rest < LENS_MIN_EXPLAINED * bend:
        reason = f"the model straightens the lines' {bend:.2f} px bow only to {rest:.2f} px: the bends are not a lens's"
    elif abs(kappa) < LENS_MIN_SIGMAS * se:
        reason = f"kappa {kappa:+.3f} is within {LENS_MIN_SIGMAS:g} standard errors ({se:.3f}) of 0"
    elif len(frames) < LENS_MIN_FRAMES:
        reason = f"only {len(frames)} frames show long lines (it takes {LENS_MIN_FRAMES})"
    elif same < LENS_MIN_SAME_SIGN or spread > LENS_MAX_SPREAD * abs(kappa):
        reason = (f"the frames disagree (their kappas {np.min(fk):+.3f} to {np.max(fk):+.3f}, median "
                  f"deviation {spread:.3f}): the bends are the road's, not the lens's")
    else:
        reason = ""
    return LensEstimate(kappa / r2, kappa, se, bend, rest, len(frames), n_lines, frame_kappas,
                        not reason, reason)


def detect_hood(frames: list[np.ndarray]) -> np.ndarray | None:
    """Return the hood's top row in every column (float; h where there is none) from 3+ frames of
    a moving car, or None when no hood is seen (or it cannot be told: fewer frames, a car
    standing still).

    The hood is still while the road moves, and its top is an edge that stays put. Per pixel of
    the bottom HOOD_MAX_FRACTION of the frame: the standard deviation across frames of the frame
    minus its local mean (a box 2 % of the height wide, which cancels exposure changes) is below
    ``HOOD_STATIC_GREY`` on the hood; going up each column from the bottom row, the hood ends at
    the first pixel that changes, and only where the median across frames of the vertical
    gradient there is a near-horizontal edge of ``HOOD_EDGE_GREY`` or more (smooth asphalt near
    the car changes little too, but has no such edge). A hood must be seen in a third of the
    middle 80 % of the columns.
    """
    if len(frames) < 3:
        return None
    h, w = frames[0].shape[:2]
    top = int(h * (1 - HOOD_MAX_FRACTION))
    k = max(5, int(0.02 * h) | 1)
    pick = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), HOOD_MAX_FRAMES)).round().astype(int))
    grey = [cv2.cvtColor(frames[i][top:], cv2.COLOR_RGB2GRAY).astype(np.float32) for i in pick]
    std = cv2.blur(np.stack([g - cv2.blur(g, (k, k)) for g in grey]).std(0), (9, 3))
    gy = np.median(np.stack([cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=0.25) for g in grey]), axis=0)
    gx = np.median(np.stack([cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=0.25) for g in grey]), axis=0)
    strength = np.where(np.abs(gy) >= 2 * np.abs(gx), np.abs(gy), 0.0)
    up = (std >= HOOD_STATIC_GREY)[::-1]
    seen = up.any(0)
    if seen.mean() < 0.5:
        return None          # most columns never change: the car stands still
    n_rows = up.shape[0]
    first = np.where(seen, np.argmax(up, axis=0), 0)
    rows = n_rows - 1 - first                        # row (in the region) where the stillness ends
    # the edge: the strongest near-horizontal one from 2 rows below that to k rows above (the
    # local mean lets the road's changes reach k / 2 rows into the hood)
    offsets = np.arange(-k, 3)
    cand = np.clip(rows[None, :] + offsets[:, None], 0, n_rows - 1)
    cols = np.arange(w)
    vals = strength[cand, cols[None, :]]
    best = np.argmax(vals, axis=0)
    edge_row = cand[best, cols]
    has = seen & (first > 0) & (vals[best, cols] >= HOOD_EDGE_GREY)
    lo, hi = int(0.1 * w), int(0.9 * w)
    if has[lo:hi].mean() < 1 / 3:
        return None
    hood = np.where(has, top + edge_row + 0.5, h).astype(np.float64)
    return _running_median(hood, max(3, (w // 40) | 1))


def _running_median(values: np.ndarray, k: int) -> np.ndarray:
    pad = k // 2
    v = np.pad(values, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(v, k)
    return np.median(windows, axis=1)


# --------------------------------------------------------------------------- roll

def _k(angle_deg: np.ndarray, roll_deg: float) -> np.ndarray:
    """Return k = du/dv of lines at ``angle_deg`` about the vanishing point, in coordinates rotated by the roll."""
    return np.tan(np.radians(np.asarray(angle_deg) - roll_deg))


def _ego_frames(angle_lists: dict[int, np.ndarray], roll_deg: float) -> dict[int, tuple[int, int, float]]:
    """Return {frame: (left line, right line, r = k_right - k_left)} of the ego lane in the frames
    where it is seen.

    The candidates of each frame are the pairs of one line on either side of the camera's line
    among the two nearest there, each EGO_ANGLES_DEG from straight down (atan of half a lane
    over the camera's height: 56 deg for 3.7 m lanes seen from 1.25 m; 37 deg from a 2.5 m
    truck cab). Some pairs are not the ego lane: a dashed line not seen or a bright seam in the
    lane make the nearest pair two lanes wide or part of one, and on a road of three lanes or
    more a car in a middle lane sees the neighbour lanes' outer lines as a pair three lanes wide,
    centred on it as well as its own. So the lane's width r is chosen by the road's other lines
    too: lanes are equally wide, so neighbour lines lie one lane width apart. A width's support
    is the number of frames with a candidate pair within 20 % of it plus the number of frames
    with two adjacent lines on one side of the camera (up to ROLL_MAX_LINE_ANGLE_DEG from
    straight down) that far apart; r is the median width of the frames' pairs within 20 % of
    the candidate width of the most support (ties: the narrowest), or of a half or a third of it
    (within 10 %) when a width there has a third of its support or more (lanes whose dashed lines
    are missed in most frames). Each frame takes its most nearly
    centred pair within 20 % of r (a car drives near its lane's centre); frames with none are
    left out.
    """
    lo, hi = (math.tan(math.radians(a)) for a in EGO_ANGLES_DEG)
    k_far = math.tan(math.radians(ROLL_MAX_LINE_ANGLE_DEG))
    pairs: dict[int, list[tuple[float, int, int, float]]] = {}
    gaps: dict[int, np.ndarray] = {}
    for i, ang in angle_lists.items():
        k = _k(ang, roll_deg)
        # an ego line lies EGO_ANGLES_DEG from straight down: atan(half a lane / camera height)
        left = [j for j in np.argsort(-k) if -hi <= k[j] <= -lo][:2]
        right = [j for j in np.argsort(k) if lo <= k[j] <= hi][:2]
        found = sorted((abs(k[a] + k[b]) / (k[b] - k[a]), int(a), int(b), float(k[b] - k[a]))
                       for a in left for b in right)
        if found:
            pairs[i] = found
        ks = np.sort(k[np.abs(k) <= k_far])
        same_side = ks[:-1] * ks[1:] > 0
        gaps[i] = np.diff(ks)[same_side]
    if not pairs:
        return {}
    widths = sorted({p[3] for found in pairs.values() for p in found})

    def support(c: float) -> int:
        near = lambda v: np.abs(np.asarray(v) / c - 1) <= 0.2  # noqa: E731
        return (sum(bool(near([p[3] for p in found]).any()) for found in pairs.values())
                + sum(bool(near(g).any()) for g in gaps.values() if len(g)))

    def centre(c: float) -> float:
        """The median of each frame's candidate width nearest ``c`` (within 20 % of it)."""
        near = [min((p[3] for p in found), key=lambda v: abs(v / c - 1)) for found in pairs.values()]
        return float(np.median([v for v in near if abs(v / c - 1) <= 0.2] or [c]))

    scored = {c: support(c) for c in widths}
    best = max(widths, key=lambda c: (scored[c], -c))
    r = centre(best)
    for n in (3, 2):       # a half or a third of it, seen often enough: the lanes' own width
        part = [c for c in widths if abs(c * n / r - 1) <= 0.1 and 3 * scored[c] >= scored[best]]
        if part:
            r = centre(max(part, key=lambda c: (scored[c], -c)))
            break
    chosen = {i: next((p for p in found if abs(p[3] / r - 1) <= 0.2), None) for i, found in pairs.items()}
    return {i: (c[1], c[2], c[3]) for i, c in chosen.items() if c is not None}


def _roll_from_spacing(frames: list[tuple[np.ndarray, tuple[int, int]]]) -> tuple[float, int] | None:
    """Return (roll deg, lines used) that makes the lines of every frame (their angles about the
    frame's vanishing point, and which two are the ego lane's) equally spaced along the horizon,
    whole multiples of the ego lane's width apart, or None when no frame shows a line beyond the
    ego lane's.

    The cost, summed over the frames' lines outside the ego lane, is each line's distance from a
    whole multiple (capped at 0.15, so that a line of another spacing, e.g. a shoulder, weighs
    little), on a grid of rolls within MAX_ROLL_DEG; its minimum is refined by least squares
    with the multiples fixed.
    """
    grid = np.arange(-MAX_ROLL_DEG, MAX_ROLL_DEG + 1e-9, 0.01)
    terms = []          # (angles, ego pair, other line indices)
    for ang, pair in frames:
        ang = np.asarray(ang, np.float64)
        lo, hi = sorted(ang[list(pair)])
        # lines beyond the ego lane's, not so flat that a hundredth of a degree moves them a lane
        others = [j for j in range(len(ang)) if (ang[j] < lo or ang[j] > hi)
                  and abs(ang[j]) <= ROLL_MAX_LINE_ANGLE_DEG]
        if others:
            terms.append((ang, pair, others))
    if not terms:
        return None

    def multiples(rolls: np.ndarray, ang, pair, others) -> np.ndarray:
        k = _k(ang[None, :], rolls[:, None])
        return (k[:, others] - k[:, [pair[0]]]) / (k[:, [pair[1]]] - k[:, [pair[0]]])

    cost = np.zeros(len(grid))
    for ang, pair, others in terms:
        n = multiples(grid, ang, pair, others)
        cost += np.minimum(np.abs(n - np.round(n)), 0.15).sum(1)
    b = int(np.argmin(cost + 1e-3 * np.abs(grid)))   # a tie goes to the smaller roll
    roll = float(grid[b])
    # least squares around it with the multiples fixed
    fixed = []
    for ang, pair, others in terms:
        n = multiples(np.array([roll]), ang, pair, others)[0]
        keep = [(j, round(v)) for j, v in zip(others, n) if abs(v - round(v)) < 0.1 and round(v) not in (0, 1)]
        if keep:
            fixed.append((ang, pair, [j for j, _ in keep], np.array([m for _, m in keep], np.float64)))
    if not fixed:
        return None
    fine = roll + np.arange(-0.05, 0.05 + 1e-9, 0.001)
    sq = np.zeros(len(fine))
    for ang, pair, idx, m in fixed:
        sq += ((multiples(fine, ang, pair, idx) - m) ** 2).sum(1)
    return float(fine[int(np.argmin(sq))]), sum(len(f[2]) for f in fixed)


# --------------------------------------------------------------------------- estimate

@dataclass(frozen=True)
class _Basis:
    vp: np.ndarray
    eh: np.ndarray   # along the horizon (to the right)
    ev: np.ndarray   # down, perpendicular to the horizon

    def to_uv(self, p: np.ndarray) -> np.ndarray:
        d = np.asarray(p, np.float64) - self.vp
        return np.stack([d @ self.eh, d @ self.ev], axis=-1)

    def to_xy(self, u, v) -> np.ndarray:
        return self.vp + np.multiply.outer(u, self.eh) + np.multiply.outer(v, self.ev)


def _basis(vp, roll_deg: float) -> _Basis:
    r = math.radians(roll_deg)
    return _Basis(np.asarray(vp, np.float64), np.array([math.cos(r), -math.sin(r)]),
                  np.array([math.sin(r), math.cos(r)]))


def estimate_geometry(frames: Iterable[np.ndarray], lens: Lens | Calibration | None = None,
                      focal_px: float | None = None, lane_width_m: float = DEFAULT_LANE_WIDTH_M,
                      look_ahead_m: float = DEFAULT_LOOK_AHEAD_M, dash_m: float = DEFAULT_DASH_M,
                      gap_m: float = DEFAULT_GAP_M, hood_row_px: float | None = None,
                      estimate_roll: bool = True, lens_from_road: bool = True) -> RoadGeometry:
    """Return the bird's-eye geometry of a camera estimated from RAW frames of the road.

    Parameters
    ----------
    frames : RGB uint8 frames of one camera (a few dozen, seconds apart, some on straight road).
    lens : the camera's ``camera.Lens`` or ``camera.Calibration``; frames are undistorted with it
        and its camera matrix gives the focal length and principal point. None: the frames are
        taken as undistorted, the principal point as the image centre.
    focal_px : the horizontal focal length (px) of the undistorted frames, if known without a
        calibration (it overrides the calibration's).
    lane_width_m : the width of the lanes (between line centres).
    look_ahead_m : how far ahead of the camera the bird's-eye view reaches.
    dash_m, gap_m : the painted and empty lengths of the dashed lines.
    hood_row_px : the top row of the car's hood; None: detected from the frames.
    estimate_roll : False assumes a roll of 0 (to measure what ignoring it costs).
    lens_from_road : with no ``lens``, measure the lens's radial distortion from the bend of the
        lines on straight road (``estimate_lens``); when it is clearly non-zero and well
        determined, the frames are undistorted with it and the estimate is made again; the
        result's ``lens`` holds it. The assumptions say what was found either way.

    Raises
    ------
    GeometryError
        If no frame gives a vanishing point on a straight road, or the look-ahead is nearer
        than the road the camera sees; the message names the reason of every frame.
    InputError
        If ``frames`` is empty or holds frames of different sizes or kinds.
    """
    frames = [_check_frame(f, f"frame {i}") for i, f in enumerate(frames)]
    if not frames:
        raise InputError("estimate_geometry: no frames given; pass frames of a road (a video's "
                         "first seconds, or a folder of images)")
    h, w = frames[0].shape[:2]
    for i, f in enumerate(frames):
        if f.shape[:2] != (h, w):
            raise InputError(f"frame {i}: is {f.shape[1]}x{f.shape[0]} but frame 0 is {w}x{h}; "
                             "estimate the geometry from frames of one camera")
    if lane_width_m <= 0 or look_ahead_m <= 0 or dash_m <= 0 or gap_m <= 0:
        raise InputError("estimate_geometry: lane_width_m, look_ahead_m, dash_m and gap_m must be positive")
    seen = _look(frames, lens, hood_row_px)
    notes: tuple[str, ...] = ()
    if seen.calibration is None and lens_from_road:
        found = estimate_lens([list(a.line_points) for a in seen.analyses if a.vp.ok], (w, h))
        if found is not None and found.applied:
            return _with_estimated_lens(found, frames, seen, focal_px, lane_width_m, look_ahead_m, dash_m, gap_m,
                                        hood_row_px, estimate_roll)
        notes = ("lens not given and taken as distortion-free: " + (
            "no lines long enough to measure it" if found is None else
            f"the lines cannot measure it ({found.reason}; kappa {found.kappa:+.3f})"),)
    return _solve(_analyse_road(seen, estimate_roll, notes), focal_px, lane_width_m, look_ahead_m, dash_m, gap_m)


def refined_geometry(geo: RoadGeometry, shift_px: float, why: str) -> RoadGeometry:
    """Return ``geo`` with its vanishing point moved ``shift_px`` along the horizon (positive to
    the right), as more frames of straight road place it (``runs.GeometryWatch``).

    The road's direction in the image is where the car heads on average: a window of frames on
    a gentle curve, or while the car drifts across its lane, puts it a few px aside. Moving the
    point along the horizon keeps the horizon, the roll, the pitch, the camera's height, the
    hood and the scale (the ego lane's ``lane_width_ratio`` and ``inverse_depth_scale_px_m``
    hold in the coordinates about the point, ``_solve``); the bird's-eye points keep their
    place about the point (``_Basis``), so the view keeps its rows, its look-ahead and its
    metres per pixel, and follows the point sideways. The yaw follows the point (its change in
    the camera's own line's slope, ``tan(yaw) sin(pitch)``, is left out: under 0.01 px at the
    view's bottom for a shift of 1 % of the focal length). ``why`` joins the assumptions.

    Raises
    ------
    GeometryError
        If the moved view leaves the frame (a corner beyond its left or right edge).
    """
    w, _ = geo.size_px
    old = _basis(geo.vanishing_point_px, geo.roll_deg)
    vp = old.to_xy(shift_px, 0.0)
    new = _basis(vp, geo.roll_deg)
    uv = old.to_uv(np.asarray(geo.src_px, np.float64))
    src = new.to_xy(uv[:, 0], uv[:, 1])
    if src[:, 0].min() < 0 or src[:, 0].max() > w - 1:
        raise GeometryError(f"the vanishing point moved {shift_px:+.1f} px along the horizon puts the "
                            "bird's-eye view's corners outside the frame")
    yaw = geo.yaw_deg
    if yaw is not None and geo.focal_px:
        pitch = math.radians(geo.pitch_deg or 0.0)
        yaw = math.degrees(math.atan(math.tan(math.radians(yaw)) - shift_px * math.cos(pitch) / geo.focal_px))
    return replace(geo, vanishing_point_px=(float(vp[0]), float(vp[1])), yaw_deg=yaw,
                   src_px=tuple((float(x), float(y)) for x, y in src),
                   assumptions=geo.assumptions + (why,))


# The estimate in three steps, so that the runs of ``_with_estimated_lens`` (the same frames with
# other focal lengths) analyse each set of frames once: ``_look`` (the image work of every
# frame: its mask, lines and vanishing point, and the hood), ``_analyse_road`` (what the frames
# tell together: the frames used, the vanishing point, the roll, the ego lane, the dashes' runs
# of paint) and ``_solve`` (what takes a focal length: the scale, the points, the confidence).

@dataclass(frozen=True)
class _Look:
    """Every frame's analysis and the hood (``_look``)."""

    size: tuple[int, int]
    calibration: Calibration | None
    analyses: tuple[_FrameAnalysis, ...]
    hood: np.ndarray | None
    hood_source: str


def _look(frames: list[np.ndarray], lens: Lens | Calibration | None, hood_row_px: float | None) -> _Look:
    """Return the analysis of every frame (undistorted with ``lens``) and the hood: given as
    ``hood_row_px``, else detected from at most HOOD_MAX_FRAMES frames, evenly spread."""
    h, w = frames[0].shape[:2]
    finder = RoadLineFinder((w, h), lens)
    if hood_row_px is not None:
        hood = np.full(w, float(hood_row_px))
        hood_source = "given"
    else:
        pick = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), HOOD_MAX_FRAMES)).round().astype(int))
        hood = detect_hood([finder.undistort(frames[i]) for i in pick])
        hood_source = "detected: still across frames, up to an edge that stays put"
        if hood is None or np.min(hood[int(0.1 * w):int(0.9 * w)]) >= h - 1:
            hood_source = "not detected"
    finder = RoadLineFinder((w, h), lens, hood)
    return _Look((w, h), finder.calibration, tuple(finder.analyse(f) for f in frames), hood, hood_source)


@dataclass(frozen=True)
class _Road:
    """What a set of frames tells by itself (``_analyse_road``), for ``_solve``."""

    look: _Look
    used: tuple[int, ...]
    rejected: tuple[tuple[int, str], ...]
    vp: np.ndarray
    vps: np.ndarray              # the used frames' own vanishing points
    scatter_y: float
    roll: float
    roll_source: str
    basis: _Basis
    horizon_slope: float
    horizon_row: float
    ego: dict[int, tuple[int, int, float]]
    r_k: float
    pp_uv: np.ndarray            # the principal point about the vanishing point (u, v)
    hood: np.ndarray
    hood_row: float
    hood_source: str
    dashes: _DashRuns | None
    assumptions: tuple[str, ...]


def _analyse_road(look: _Look, estimate_roll: bool, notes: tuple[str, ...] = ()) -> _Road:
    """Return what the frames of ``look`` tell together (``_Road``), their assumptions after ``notes``.

    Raises
    ------
    GeometryError
        If no frame gives a consistent vanishing point or shows the ego lane.
    """
    w, h = look.size
    analyses, calibration = look.analyses, look.calibration
    hood, hood_source = look.hood, look.hood_source
    assumptions = list(notes)

    # frames with a vanishing point on a straight road, consistent with the others
    rejected: list[tuple[int, str]] = []
    cand = []
    for i, a in enumerate(analyses):
        if a.vp.ok:
            cand.append(i)
        else:
            rejected.append((i, a.vp.reason))
    if not cand:
        raise GeometryError(_no_frame_message(rejected, len(analyses)))
    pts = np.array([analyses[i].vp.point_px for i in cand])
    tol_y, tol_x = max(3.0, 0.01 * h), VP_X_TOLERANCE * w
    med = np.median(pts, axis=0)
    # twice: the median of the frames that agree, then who agrees with it (a long gentle curve
    # can pull the first median aside)
    near = (np.abs(pts[:, 1] - med[1]) <= tol_y) & (np.abs(pts[:, 0] - med[0]) <= tol_x)
    if near.any():
        med = np.median(pts[near], axis=0)
    used = []
    for i, p in zip(cand, pts):
        if abs(p[1] - med[1]) > tol_y or abs(p[0] - med[0]) > tol_x:
            rejected.append((i, f"inconsistent: its vanishing point ({p[0]:.1f}, {p[1]:.1f}) px is off "
                                f"the median of the frames ({med[0]:.1f}, {med[1]:.1f}) px (a hill, a "
                                "bump or a lane change?)"))
        else:
            used.append(i)
    if not used:
        raise GeometryError(_no_frame_message(rejected, len(analyses)))
    rejected.sort()
    weights = np.array([analyses[i].vp.inlier_segments for i in used], np.float64)
    vps = np.array([analyses[i].vp.point_px for i in used])
    vp = (vps * weights[:, None]).sum(0) / weights.sum()
    scatter_y = float(np.std(vps[:, 1])) if len(used) > 1 else float("nan")

    # the ego lane: the nearest line left and right of the camera's; where a dashed line is not
    # seen, the nearest is the next lane's, so frames whose lane is much wider than most are left out
    angle_lists = {i: np.array([l.angle_deg for l in analyses[i].vp.lines]) for i in used}
    ego = _ego_frames(angle_lists, 0.0)

    # roll
    roll, roll_source = 0.0, "assumed 0"
    if estimate_roll:
        found = _roll_from_spacing([(angle_lists[i], ego[i][:2]) for i in ego])
        if found is not None:
            each = [r for r in (_roll_from_spacing([(angle_lists[i], ego[i][:2])]) for i in ego) if r is not None]
            spread = float(np.median([abs(r[0] - found[0]) for r in each]))
            if len(each) >= ROLL_MIN_FRAMES and spread <= ROLL_MAX_SPREAD_DEG:
                roll = found[0]
                roll_source = (f"lane spacing ({found[1]} lines beyond the ego lane's in {len(each)} frames, "
                               f"frame to frame within {spread:.2f} deg)")
            else:
                assumptions.append(
                    f"the lines beyond the ego lane's give a roll of {found[0]:+.2f} deg but "
                    + (f"in only {len(each)} frames" if len(each) < ROLL_MIN_FRAMES else
                       f"frame by frame {spread:.2f} deg apart (lanes of other widths?)") + ": not used")
    if roll_source == "assumed 0":
        dx = abs(w / 2 - vp[0])
        assumptions.append(
            "roll assumed 0 (it takes lines beyond the ego lane's, of equally wide lanes, to measure it): "
            "a roll of 1.5 deg would move the horizon at the image centre by "
            f"{dx * math.tan(math.radians(1.5)):.1f} px, the lane width by about 1.3 % and the scale along "
            "the road by about 7 %")
    else:
        assumptions.append("every lane is as wide as the ego lane (the roll is measured from their spacing)")
    basis = _basis(vp, roll)
    slope = -math.tan(math.radians(roll))
    horizon_row = float(vp[1] + slope * (w / 2 - vp[0]))

    # the ego lane's width in k = du/dv
    ego = _ego_frames(angle_lists, roll)
    if not ego:
        raise GeometryError(f"no frame shows both lines of the lane the car drives in, one on each side "
                            f"of the camera and {EGO_ANGLES_DEG[0]:g}-{EGO_ANGLES_DEG[1]:g} deg from straight "
                            "down below the vanishing point; give frames where the car drives between two "
                            "lane lines (is the video rotated?)")
    r_k = float(np.median([e[2] for e in ego.values()]))

    # the principal point
    if calibration is not None and calibration.estimated:
        assumptions.append(f"the lens was estimated ({calibration.estimated}): its focal length is not used")
    if calibration is not None and not calibration.estimated:
        K = calibration.camera_matrix
        pp = np.array([K[0, 2], K[1, 2]], np.float64)
    else:
        pp = np.array([w / 2, h / 2])
    if calibration is None or calibration.estimated:
        assumptions.append("principal point at the image centre")

    # hood row and the bottom of the road
    if hood_source == "not detected":
        lowest = [max(l.rows_px[1] for l in analyses[i].vp.lines) for i in used]
        hood_row = float(min(h, np.max(lowest) + 1))
        hood_source = "not detected: just below the lowest lane-line pixel"
        assumptions.append("hood not detected (it takes 3 frames of a moving car): the view starts "
                           "just below the lowest lane-line pixel found")
        hood = np.full(w, hood_row)
    else:
        lo, hi = int(0.1 * w), int(0.9 * w)
        hood_row = float(np.min(hood[lo:hi]))

    return _Road(look, tuple(used), tuple(rejected), vp, vps, scatter_y, roll, roll_source, basis, slope, horizon_row, ego,
                 r_k, basis.to_uv(pp), hood, hood_row, hood_source,
                 _dash_runs_of(analyses, used, ego, hood, roll, (w, h)), tuple(assumptions))


def _solve(road: _Road, focal_px: float | None, lane_width_m: float, look_ahead_m: float, dash_m: float,
           gap_m: float, focal_confidence: float = FOCAL_CONFIDENCE) -> RoadGeometry:
    """Return the geometry of ``road`` with these focal length (None: from the calibration, else
    the dashes, else assumed), lane width, look-ahead and dashes (``estimate_geometry``).
    ``focal_confidence`` multiplies the confidence when the scale along the road is the focal
    length's (no dash period in these frames): FOCAL_CONFIDENCE for a calibration's or a given
    one, 1 for one that other frames' dash period measured.

    Raises
    ------
    GeometryError
        If no road is seen above the hood, or the look-ahead is nearer than the road seen.
    """
    w, h = road.look.size
    calibration, analyses = road.look.calibration, road.look.analyses
    used, ego, roll, basis, r_k, hood = road.used, road.ego, road.roll, road.basis, road.r_k, road.hood
    assumptions = list(road.assumptions)
    # the focal length
    if calibration is not None and not calibration.estimated:
        K = calibration.camera_matrix
        fx, fy = float(K[0, 0]), float(K[1, 1])
        focal_source = "calibration"
    else:
        fx = fy = None
        focal_source = "unknown"
    if focal_px is not None:
        fy = float(focal_px) if fx is None else fy * float(focal_px) / fx
        fx = float(focal_px)
        focal_source = "given"
    pp_u, pp_v = road.pp_uv

    def angles(f_x: float, f_y: float) -> tuple[float, float]:
        """Return (pitch, yaw) in radians for focal lengths f_x, f_y."""
        theta = math.atan2(pp_v, f_y)
        psi = math.atan(pp_u * math.cos(theta) / f_x)
        return theta, psi

    def c_from_focal(f_x: float, f_y: float) -> float:
        theta, psi = angles(f_x, f_y)
        return f_x * lane_width_m / (r_k * math.cos(theta) * math.cos(psi) ** 2)

    # dash period -> C
    c_focal = c_from_focal(fx, fy) if fx is not None else None
    if c_focal is not None:
        c_range = (c_focal / DASH_FOCAL_RANGE, c_focal * DASH_FOCAL_RANGE)
    else:
        c_range = tuple(f * w * lane_width_m / r_k for f in FOCAL_RANGE_W)
    c_dash, dash_fit = _dash_scale(road.dashes, dash_m, gap_m, c_range)
    scale_conf = 1.0
    if c_dash is not None:
        f_dash = c_dash * r_k / lane_width_m
        for _ in range(4):  # the angles depend on the focal length
            theta, psi = angles(f_dash, f_dash)
            f_dash = c_dash * r_k * math.cos(theta) * math.cos(psi) ** 2 / lane_width_m
        if not 0.2 * w <= f_dash <= 6 * w:
            assumptions.append(f"a dash period was found but implies a focal length of {f_dash:.0f} px, "
                               "out of reach for a road camera: not used")
            c_dash = None
    if c_dash is not None:
        C = c_dash
        scale_source = f"dash period ({dash_m:g} m dash + {gap_m:g} m gap, dash pairs fit {dash_fit:.2f})"
        assumptions.append(f"dashed lines are {dash_m:g} m painted + {gap_m:g} m gap")
        if c_focal is not None:
            diff = c_dash / c_focal - 1
            if abs(diff) > DASH_DISAGREEMENT:
                # the calibrated focal length is measured, the dash pattern only assumed: trust it
                scale_conf = 0.75
                C, scale_source = c_focal, (f"focal length and lane width (the dash period "
                                            f"disagreed by {100 * diff:+.0f} %)")
                assumptions.append(f"the dash period and the focal length with the lane width disagree by "
                                   f"{100 * diff:+.0f} %: the dashes may not be {dash_m:g} m + {gap_m:g} m "
                                   "(or the lanes not as wide as assumed); the focal length is used")
        else:
            fx = fy = f_dash
            focal_source = "dash period and lane width"
    elif c_focal is not None:
        C, scale_source = c_focal, "focal length and lane width"
        scale_conf = focal_confidence
    else:
        fa = w / 2 / math.tan(math.radians(ASSUMED_HFOV_DEG / 2))
        C = c_from_focal(fa, fa)
        scale_source = f"assumed focal length {fa:.0f} px ({ASSUMED_HFOV_DEG:g} deg field of view)"
        assumptions.append(f"no dashed lines and no focal length: a focal length of {fa:.0f} px "
                           f"({ASSUMED_HFOV_DEG:g} deg horizontal field of view) is assumed; the scale "
                           "along the road may be off by tens of percent")
        scale_conf = 0.4
    assumptions.append(f"lanes {lane_width_m:g} m wide; a flat road")

    pitch = yaw = height = None
    implausible = ""
    k_c, s0 = 0.0, 0.0
    if fx is not None:
        theta, psi = angles(fx, fy)
        pitch, yaw = math.degrees(theta), math.degrees(psi)
        height = fx * lane_width_m * math.cos(theta) / (fy * r_k * math.cos(psi))
        k_c = (fx / fy) * math.tan(psi) * math.sin(theta)
        s0 = -height * math.tan(theta) / math.cos(psi)
        if not CAMERA_HEIGHT_RANGE_M[0] < height < CAMERA_HEIGHT_RANGE_M[1]:
            implausible = (f"implausible: the lane width and the focal length ({fx:.0f} px, {focal_source}) put "
                           f"the camera {height:.2f} m above the road, outside {CAMERA_HEIGHT_RANGE_M[0]:g}-"
                           f"{CAMERA_HEIGHT_RANGE_M[1]:g} m; the lane lines were probably paired wrongly (or "
                           f"the lanes are not {lane_width_m:g} m wide): the scale is not to be trusted")
            assumptions.append(implausible)
    else:
        assumptions.append("the camera sits on the car's centre line")

    # bird's-eye points
    half = r_k / 2
    margin = max(2.0, 0.01 * h)
    v_bottom = _bottom_v(basis, (k_c - half, k_c + half), hood, margin, (w, h))
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
    visible = C / v_top - C / v_bottom
    xm, ym = lane_width_m / (w / 2), visible / h
    widening = _view_widening([(analyses[i].mask, [analyses[i].line_fits[j] for j in ego[i][:2]]) for i in ego],
                              src, dst, (w, h))
    if widening is not None and abs(widening - 1) > LANE_PARALLEL_TOLERANCE:
        parallel_conf = IMPLAUSIBLE_CONFIDENCE
        assumptions.append(
            f"the ego lane {'widens' if widening > 1 else 'narrows'} by {100 * abs(widening - 1):.1f} % from the "
            "bottom third of the bird's-eye view to the top third (frames' median): "
            + ("a lens that distorts (give --calibration)" if calibration is None else "")
            + (" or " if calibration is None else "") + "a road that is not flat; the scale is not to be trusted")
    else:
        parallel_conf = 1.0

    # confidence
    n_used = len(used)
    conf = min(1.0, n_used / MIN_GOOD_FRAMES)
    # how well the frames pin the vanishing point: the standard error of their mean row (a car
    # that pitches over bumps scatters each frame's point by a few px; many frames still pin it)
    std_err_y = road.scatter_y / math.sqrt(n_used) if n_used > 1 else float("nan")
    if n_used > 1 and std_err_y > 1.0:
        conf *= math.exp(-((std_err_y - 1.0) / 3.0) ** 2)
    conf *= scale_conf
    conf *= min(1.0, len(ego) / MIN_GOOD_FRAMES)
    if road.hood_source.startswith("not detected"):
        conf *= 0.9
    if implausible:
        conf *= IMPLAUSIBLE_CONFIDENCE
    conf *= parallel_conf
    return RoadGeometry(
        size_px=(w, h), vanishing_point_px=(float(road.vp[0]), float(road.vp[1])),
        horizon_row_px=road.horizon_row,
        horizon_slope=road.horizon_slope, roll_deg=roll, roll_source=road.roll_source, pitch_deg=pitch, yaw_deg=yaw,
        camera_height_m=height, focal_px=fx, focal_source=focal_source if fx is not None else "unknown",
        hood_row_px=road.hood_row, hood_source=road.hood_source, src_px=src, dst_px=dst,
        lane_width_m=float(lane_width_m), look_ahead_m=float(look_ahead_m), near_m=float(near_m),
        visible_length_m=float(visible), xm_per_px=xm, ym_per_px=ym, scale_source=scale_source,
        inverse_depth_scale_px_m=float(C), lane_width_ratio=r_k, dash_fit=float(dash_fit),
        confidence=float(round(conf, 4)),
        assumptions=tuple(assumptions), frames_used=used, frames_rejected=road.rejected,
        frame_vanishing_points=tuple((i, float(p[0]), float(p[1])) for i, p in zip(used, road.vps)))


def _with_estimated_lens(found: LensEstimate, frames: list[np.ndarray], raw_look: _Look, focal_px, lane_width_m,
                         look_ahead_m, dash_m, gap_m, hood_row_px, estimate_roll) -> RoadGeometry:
    """Return the geometry of ``frames`` undistorted with the lens ``found`` from their lines.

    Undistorting with the frame's own camera matrix pushes the periphery out of the frame, and
    with it the near dashes, the longest: so the dash period is also measured in the raw frames
    (where the far dashes, near the centre, are barely distorted), and the focal length it gives
    is the one used when the undistorted frames show too few dashes to give one themselves.
    Each set of frames (undistorted, on the canvas, raw: ``raw_look``, the frames' analysis
    without a lens) is analysed once and solved with each focal length.
    """
    h, w = frames[0].shape[:2]
    fa = w / 2 / math.tan(math.radians(ASSUMED_HFOV_DEG / 2))
    scale = dict(lane_width_m=lane_width_m, look_ahead_m=look_ahead_m, dash_m=dash_m, gap_m=gap_m)
    cal = found.calibration((w, h), fa)
    road = _analyse_road(_look(frames, cal, hood_row_px), estimate_roll)
    geo = _solve(road, focal_px, **scale)
    raw_note = ""
    if focal_px is None and not geo.scale_source.startswith("dash period"):
        # the dashes on a larger canvas: the frames undistorted with what they push out kept
        pad = (int(round(LENS_CANVAS_PAD * w)), int(round(LENS_CANVAS_PAD * h)))
        grid, _ = Lens(cal, (w, h)).undistort_maps(pad=pad, m1type=cv2.CV_32FC2)
        if found.lam < 0:   # past the model's fold the map turns back: nothing there
            cw, ch = w + 2 * pad[0], h + 2 * pad[1]
            yy, xx = np.mgrid[0:ch, 0:cw]
            grid[np.hypot(xx - cw / 2, yy - ch / 2) > 1 / math.sqrt(-3 * found.lam)] = -1
        wide = [cv2.remap(f, grid, None, cv2.INTER_LINEAR) for f in frames]
        try:
            canvas = _solve(_analyse_road(_look(wide, None, None), estimate_roll), None, **scale)
        except GeometryError:
            canvas = None
        if canvas is not None and canvas.focal_source == "dash period and lane width":
            # the focal length is the canvas's dash period's, measured: no FOCAL_CONFIDENCE
            again = _solve(road, canvas.focal_px, **scale, focal_confidence=1.0)
            geo = replace(again, focal_source="dash period and lane width",
                           scale_source=f"dash period of the undistorted frames on a canvas {100 * LENS_CANVAS_PAD:g} % "
                                        f"larger each side ({canvas.scale_source[len('dash period '):].strip('()')}; "
                                        f"focal {canvas.focal_px:.0f} px)")
            raw_note = (f"undistortion pushes the near dashes out of the frame: the dash period was measured on "
                        f"the undistorted frames on a canvas {100 * LENS_CANVAS_PAD:g} % larger each side "
                        f"(focal length {canvas.focal_px:.0f} px)")
    if focal_px is None and not geo.scale_source.startswith("dash period"):
        try:
            raw = _solve(_analyse_road(raw_look, estimate_roll), None, **scale)
        except GeometryError:
            raw = None
        if raw is not None and raw.focal_source == "dash period and lane width":
            again = _solve(road, raw.focal_px, **scale)
            # the raw frames' dashes are measured through the lens (4 % short on the synthetic
            # 90 deg camera with k1 = -0.25): a scale not to be trusted
            geo = replace(again, focal_source="dash period of the raw frames and lane width",
                           confidence=round(again.confidence * RAW_DASH_CONFIDENCE, 4),
                           scale_source=f"dash period of the raw frames (focal {raw.focal_px:.0f} px) and lane "
                                        "width: the undistorted frames show too few dashes")
            raw_note = (f"the undistorted frames show too few dashes: the focal length, {raw.focal_px:.0f} px, "
                        "is the one the dash period gives in the raw frames, through the lens: the scale "
                        "along the road may be a few % off and is not to be trusted")
    f = geo.focal_px or fa
    lens = found.calibration((w, h), f)
    note = (f"lens not given: its radial distortion was estimated from the bend of {found.lines} lines in "
            f"{found.frames} frames (r_d = r_u (1 + lam r_u^2), lam {found.lam:.3g} px^-2: "
            f"{100 * found.kappa:+.1f} % at the half-diagonal; k1 {lens.dist_coeffs[0]:+.3f} at focal {f:.0f} px), "
            f"their bow {found.bend_px:.2f} px -> {found.residual_bend_px:.2f} px; the frames are undistorted with it")
    return replace(geo, lens=lens, assumptions=(note,) + ((raw_note,) if raw_note else ()) + tuple(
        a for a in geo.assumptions if not a.startswith("the lens was estimated")))

def _no_frame_message(rejected: list[tuple[int, str]], n: int) -> str:
    """Return the error of a run where no frame gave a consistent vanishing point."""
    reasons: dict[str, list[int]] = {}
    for i, why in sorted(rejected):
        reasons.setdefault(why.split(":")[0], []).append(i)
    parts = [f"{why} ({len(ix)} frame{'s' if len(ix) > 1 else ''})" for why, ix in reasons.items()]
    first = sorted(rejected)[0][1] if rejected else ""
    return (f"no consistent vanishing point in {n} frame{'s' if n > 1 else ''}: {'; '.join(parts)}. "
            f"First: {first}")


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


def _dash_runs(on: np.ndarray, q0: float, dq: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the (centres, lengths) in q of the runs of paint in an on/off signal sampled at
    q0 + dq * i (0 at both ends), joined across gaps under 3 px, at least 2 px long and wholly
    inside the signal (``_dash_scale`` keeps those that may be dashes)."""
    edges = np.diff(on.astype(np.int8))
    starts, ends = np.flatnonzero(edges == 1) + 1, np.flatnonzero(edges == -1) + 1   # [start, end)
    if len(starts) == 0:
        return np.zeros(0), np.zeros(0)
    qs, qe = q0 + dq * starts, q0 + dq * ends
    # join runs whose gap is under 3 px (v = 1/q, so a step dq is v^2 dq px)
    gap_px = (qs[1:] - qe[:-1]) / (qs[1:] * qe[:-1])
    first = np.flatnonzero(np.r_[True, gap_px >= 3.0])
    qs, qe = np.minimum.reduceat(qs, first), np.maximum.reduceat(qe, first)
    inner = np.ones(len(qs), bool)
    inner[0] = starts[0] > 1
    inner[-1] &= ends[-1] < len(on) - 1
    length_px = (qe - qs) / (qs * qe)
    centre = (qs + qe) / 2
    keep = inner & (length_px >= 2.0)
    return centre[keep], (qe - qs)[keep]


def _dash_lines(analyses, used, ego: dict[int, tuple[int, int, float]], roll: float) -> list[tuple[int, int]]:
    """Return the (frame, line) of the lines whose dashes measure the dash period: in the frames
    that show the ego lane, the lines a whole lane width (within DASH_LANE_TOLERANCE of one) from
    its left line, from one lane left of the ego lane to one lane right of it. A barrier, a kerb
    or a shoulder's edge is no lane line (its flecks and joints are no dashes), and lines farther
    out are seen at a grazing angle that merges their dashes."""
    out = []
    for i in used:
        if i not in ego:
            continue
        left, _, r = ego[i]
        lines = analyses[i].vp.lines
        k = _k(np.array([l.angle_deg for l in lines]), roll)
        n = (k - k[left]) / r
        for j in np.flatnonzero((np.abs(n - np.round(n)) <= DASH_LANE_TOLERANCE)
                                & (np.round(n) >= -1) & (np.round(n) <= 2)):
            out.append((i, int(j)))
    return out


def _dash_length_model(centre: np.ndarray, length: np.ndarray) -> tuple[float, float] | None:
    """Return (a, b): a run of a dash at q = 1/v is a + b q^2 long in q (a = dash_m / C, b the px
    the blur and the mask add to its ends), fitted to the long runs (10 px or more) that are
    single dashes (at most twice their median: merged dashes are three times as long), robustly
    (Theil-Sen: the median of the pairwise slopes); None with fewer than two such runs."""
    long = length * centre ** -2 >= 10.0
    if long.sum() < 2:
        return None
    single = long & (length <= 2 * np.median(length[long]))
    q2, y = centre[single] ** 2, length[single]
    b = 0.0
    if len(y) >= DASH_BLUR_MIN_RUNS:
        jj, kk = np.triu_indices(len(y), 1)
        dq2 = q2[kk] - q2[jj]
        ok = dq2 > 1e-3 * q2.max()
        if ok.any():
            b = max(0.0, float(np.median((y[kk] - y[jj])[ok] / dq2[ok])))
    a = float(np.median(y - b * q2))
    return (a, b) if a > 0 else None


def _dash_pairs(runs: list[np.ndarray]) -> np.ndarray:
    """Return the pairs of dashes of one line, 3 x N: their distance in q, weight (the inverse
    variance of their centres: a centre's error in q is its error in px times q^2) and the index
    of their line in ``runs``."""
    out = [np.zeros((3, 0))]
    for n, centre in enumerate(runs):
        if len(centre) >= 2:
            jj, kk = np.triu_indices(len(centre), 1)
            out.append(np.stack([centre[kk] - centre[jj], 1.0 / (centre[kk] ** 4 + centre[jj] ** 4),
                                 np.full(len(jj), float(n))]))
    return np.concatenate(out, axis=1)


def _dash_fit_curve(pairs: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Return the fit of each frequency ``nu`` (1 / period in q) to the pairs (``_dash_pairs``):
    their weighted mean of cos(2 pi nu distance)."""
    d, weight = pairs[0], pairs[1]
    return np.cos(2 * np.pi * np.multiply.outer(nu, d)) @ (weight / weight.sum())


@dataclass(frozen=True)
class _DashRuns:
    """The runs of paint along the lane lines whose dashes may measure the dash period
    (``_dash_runs_of``): per line its (frame, line) and its runs' centres and lengths in q = 1/v
    (``_dash_runs``); ``span`` the stretch of q the lines were sampled over."""

    span: float
    runs: tuple[tuple[tuple[int, int], np.ndarray, np.ndarray], ...]


def _dash_runs_of(analyses, used, ego: dict[int, tuple[int, int, float]], hood: np.ndarray, roll: float,
                  size: tuple[int, int]) -> _DashRuns | None:
    """Return the runs of paint along the lane lines of the frames that show the ego lane
    (``_dash_lines``), sampled along their length at even steps of q = 1/v (v: px below the
    frame's horizon) above the hood (``_dash_runs``), or None when no line reaches far enough
    below the horizon; ``_dash_scale`` finds the dash period in them."""
    w, h = size
    v_min = max(6.0, DASH_V_MIN_FRACTION * h)
    signals_meta = []
    v_max = 0.0
    for i, j in _dash_lines(analyses, used, ego, roll):
        a = analyses[i]
        fb = _basis(a.vp.point_px, roll)
        c, d, _, bottom = a.line_fits[j]
        v_line = float(fb.to_uv(c + d * (bottom - c[1]) / d[1])[1])
        if v_line <= 2 * v_min:
            continue
        v_max = max(v_max, v_line)
        signals_meta.append((i, j, fb, c, d, v_line))
    if not signals_meta:
        return None
    q_lo, q_hi = 1.0 / v_max, 1.0 / v_min
    dq = 0.5 / v_max ** 2
    n = int((q_hi - q_lo) / dq) + 1
    if n > 40000:
        n = 40000
        dq = (q_hi - q_lo) / (n - 1)
    q = q_lo + dq * np.arange(n)
    v = 1.0 / q
    kernel = np.ones((1, 5), np.uint8)
    dilated = {}
    runs = []
    for i, j, fb, c, d, v_line in signals_meta:
        if i not in dilated:
            dilated[i] = cv2.dilate(analyses[i].mask, kernel)
        m = dilated[i]
        # points of the line at distance v below the frame's horizon
        c_v = float((c - fb.vp) @ fb.ev)
        tau = (v - c_v) / float(d @ fb.ev)
        xi = np.round(c[0] + tau * d[0]).astype(int)
        yi = np.round(c[1] + tau * d[1]).astype(int)
        inside = (xi >= 0) & (xi < w) & (yi >= 0) & (v <= v_line + 1)
        inside[inside] &= yi[inside] < hood[xi[inside]] - 1
        idx = np.flatnonzero(inside)
        if len(idx) < 0.2 * n:
            continue
        stretch = slice(idx[0], idx[-1] + 1)
        on = np.zeros(idx[-1] - idx[0] + 3, np.int8)
        on[1:-1] = (m[np.clip(yi[stretch], 0, h - 1), np.clip(xi[stretch], 0, w - 1)] > 0) & inside[stretch]
        runs.append(((i, j),) + _dash_runs(on, q[idx[0]] - dq, dq))
    return _DashRuns(q_hi - q_lo, tuple(runs))


def _dash_scale(dashes: _DashRuns | None, dash_m: float, gap_m: float,
                c_range: tuple[float, float]) -> tuple[float | None, float]:
    """Return (C from the dash period, how well the dashes fit it), or (None, fit) without a
    clear dash period; C is searched within ``c_range``.

    ``dashes`` are the runs of paint along the lane lines (``_dash_runs_of``), sampled at even
    steps of q = 1/v, where s = C q + s0 makes a dash pattern periodic; those no longer than a
    dash of the shortest period searched and far enough below the horizon for a gap to show
    (3 px at the smallest C searched) may be dashes. Their lengths give a + b q^2 (``_dash_length_model``): a first
    C = dash_m / a, and b, what blur adds to a run. A run is a dash when its length less b q^2
    is within DASH_LENGTH_WINDOW of a: far away a raised marker in a gap or a fleck blurs to
    half a dash's length in q, and a marker beside a dash merges with it; either would put a
    "dash" half a period off. For a period P in q, the fit is the weighted mean over all pairs
    of dashes of one line of cos(2 pi (q_j - q_k) / P): 1 when every pair lies a whole number of
    periods apart (``_dash_fit_curve``); the period is the best fit within a factor
    DASH_LENGTH_RANGE below and DASH_LENGTH_UP above what the lengths say (which rules out the
    harmonic at twice C), used from a fit of DASH_MIN_FIT and only when it holds without any one
    frame (or, from one frame, any one line): each such sub-sample's best period within
    DASH_CONSISTENCY of it and fitting it from DASH_MIN_FIT; C = (dash_m + gap_m) / P.
    """
    if dashes is None:
        return None, 0.0
    period_m = dash_m + gap_m
    span = dashes.span
    lo = max(DASH_MIN_PERIODS / span, c_range[0] / period_m)
    hi = c_range[1] / period_m
    if hi <= lo:
        return None, 0.0
    # nearer the horizon than this, a gap spans under 3 px for the smallest C searched
    v_resolved = math.sqrt(3.0 * c_range[0] / gap_m)
    runs = []
    for key, centre, length in dashes.runs:
        keep = (length <= 0.6 / lo) & (1.0 / centre >= v_resolved)
        runs.append((key, centre[keep], length[keep]))
    if not runs:
        return None, 0.0
    model = _dash_length_model(np.concatenate([r[1] for r in runs]), np.concatenate([r[2] for r in runs]))
    if model is None:
        return None, 0.0
    a_q, b_q = model
    c_len = dash_m / a_q
    lo = max(lo, c_len / DASH_LENGTH_RANGE / period_m)
    hi = min(hi, c_len * DASH_LENGTH_UP / period_m)
    if hi <= lo:
        return None, 0.0
    dashes = []
    for key, centre, length in runs:
        # runs much shorter or longer than a dash there, less its blur, are not dashes; and,
        # with C known roughly, runs nearer the horizon than where a gap spans 6 px
        own = length - b_q * centre ** 2
        ok = ((own >= DASH_LENGTH_WINDOW[0] * a_q) & (own <= DASH_LENGTH_WINDOW[1] * a_q)
              & (centre <= 1.0 / math.sqrt(6.0 * c_len / gap_m)))
        if ok.sum() >= 2:
            dashes.append((key, centre[ok]))
    step = 1.0 / (40 * span)
    nu = np.arange(lo, hi + step, step)
    if len(nu) < 3:
        return None, 0.0
    pairs = _dash_pairs([c for _, c in dashes])
    if pairs.shape[1] < DASH_MIN_PAIRS:
        return None, 0.0
    fit = _dash_fit_curve(pairs, nu)
    b = int(np.argmax(fit))
    if fit[b] < DASH_MIN_FIT or b in (0, len(nu) - 1):
        return None, float(fit[b])
    c0, c1, c2 = fit[b - 1], fit[b], fit[b + 1]
    den = c0 - 2 * c1 + c2
    f = nu[b] + (0.5 * (c0 - c2) / den * step if den < 0 else 0.0)
    # consistency: the period holds without any one frame (from one frame: without any one line)
    line = pairs[2].astype(int)
    frames = np.array([key[0] for key, _ in dashes])[line]
    group = frames if len(np.unique(frames)) > 1 else line
    if len(np.unique(group)) < 2:
        return None, float(c1)
    worst = float(c1)
    for g in np.unique(group):
        keep = group != g
        sub = _dash_fit_curve(pairs[:, keep], nu)
        sb = int(np.argmax(sub))
        worst = min(worst, float(sub[b]))
        if sub[b] < DASH_MIN_FIT or abs(nu[sb] / f - 1) > DASH_CONSISTENCY:
            return None, worst
    return float(f * period_m), float(c1)
