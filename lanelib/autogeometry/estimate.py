"""``estimate_geometry``: the bird's-eye geometry of a camera from frames of the road.

All in the undistorted image (frames are undistorted first when a ``camera.Lens`` or
``camera.Calibration`` is given, or a lens measured from the road's lines, ``lens``):

- **Bird's-eye points** (``view``): the ego lane's width about the camera's own line, from just
  above the hood to ``look_ahead_m`` ahead, edges parallel to the horizon.
- **Metric scale.** Across the road: the src sides are one lane width apart (``lane_width_m``,
  3.7 m by default), so xm_per_px = lane_width_m / (w/2). Along the road: the distance ahead
  of a point v px below the horizon is s = C / v + s0 (a pinhole over a flat road; s0 =
  -H tan(pitch)/cos(yaw), a few cm, 0 when the focal length is unknown). C is measured, in this
  order: from the dash period where dashed lines are seen (``dashes``), else from the focal
  length (a calibration's K or ``focal_px``) and the lane width
  (C = f lane_width_m / (r cos(pitch) cos^2(yaw))), else from an assumed focal length (a 60 deg
  horizontal field of view), which the result states. With the dash period, the focal length
  follows from the same formula, so the pitch, yaw and camera height are given too (with the
  principal point at the image centre unless a calibration gives it).
- **Confidence** (0-1): the product of min(1, frames used / 5), how well the frames pin the
  vanishing point (1 up to 1 px of standard error of their mean row, falling off beyond: a car
  pitching over bumps scatters single frames by a few px, and many frames still pin it),
  min(1, frames showing the ego lane / 5), the source of the scale (dashes 1, focal length 0.9
  (FOCAL_CONFIDENCE), dashes and focal length disagreeing by more than 8 % 0.75, and then the
  focal length is used, assumed focal length 0.4), 0.9 when the hood was not found, and 0.4
  when the focal length and the lane width put the camera at an implausible height
  (``CAMERA_HEIGHT_RANGE_M``, 0.7-4 m: the lines were paired wrongly; the assumptions say so),
  and 0.4 again when the ego lane's lines, carried into the bird's-eye view, are not parallel:
  its width at the top differs from that at the bottom by more than LANE_PARALLEL_TOLERANCE
  (2.5 %; frames' median; ``view._view_widening``): a lens that distorts and was not given (a
  straight line's image bends), or a road that is not flat. Below ``LOW_CONFIDENCE`` a pipeline
  should refuse the result unless told to use it.
- **An estimated lens** (``_with_estimated_lens``). Undistortion with the frame's own camera
  matrix pushes the near dashes out of the frame: when too few are left for a period, it is
  measured on the frames undistorted onto a canvas LENS_CANVAS_PAD (10 %) larger each side, and
  its focal length sets the scale; failing that, the raw frames' dash period does, with the
  confidence multiplied by RAW_DASH_CONFIDENCE (0.6): measured through the lens, it is a few %
  off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Iterable

import cv2
import numpy as np

from ..camera import Calibration, Lens
from ..errors import GeometryError, InputError
from ..perspective import DEFAULT_LANE_WIDTH_M
from .dashes import DASH_DISAGREEMENT, _dash_scale
from .lens import LensEstimate, estimate_lens
from .road import _analyse_road, _look, _Look, _Road
from .roadgeometry import RoadGeometry
from .vanishing import _check_frame
from .view import IMPLAUSIBLE_CONFIDENCE, _parallel_confidence, _view

DEFAULT_LOOK_AHEAD_M = 25.0
DEFAULT_DASH_M = 3.0
DEFAULT_GAP_M = 9.0
ASSUMED_HFOV_DEG = 60.0
MIN_GOOD_FRAMES = 5     # frames on straight road for full confidence
DASH_FOCAL_RANGE = 1.35        # with a known focal length, C is searched within this factor of its C
FOCAL_RANGE_W = (0.3, 3.5)     # else focal lengths from 0.3 to 3.5 image widths (hfov 16-118 deg)
# A camera this high above the road or more, or this low or less, is no road camera (a car's
# dashcam sits 1.0-1.6 m up, a truck's 2-3 m): the lane width was measured between the wrong lines
CAMERA_HEIGHT_RANGE_M = (0.7, 4.0)
FOCAL_CONFIDENCE = 0.9         # the confidence is multiplied by this when the scale along the road is a
                               # focal length's, not dashes'
LENS_CANVAS_PAD = 0.1           # undistorted frames on a canvas this much of the frame larger each side, for dashes
RAW_DASH_CONFIDENCE = 0.6       # the confidence is multiplied by this when the scale is the raw frames' dashes'


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
    used, roll, r_k = road.used, road.roll, road.r_k
    assumptions = list(road.assumptions)
    fx, fy, focal_source = _focal(road.look.calibration, focal_px)
    scale = _scale(road, fx, fy, focal_source, lane_width_m, dash_m, gap_m, focal_confidence, assumptions)
    fx, focal_source, C = scale.fx, scale.focal_source, scale.c
    assumptions.append(f"lanes {lane_width_m:g} m wide; a flat road")
    pose = _pose(road.pp_uv, fx, scale.fy, focal_source, r_k, lane_width_m, assumptions)
    view = _view(road, C, pose.k_c, pose.s0, look_ahead_m, assumptions)
    xm, ym = lane_width_m / (w / 2), view.visible_m / h
    parallel_conf = _parallel_confidence(road, view, assumptions)
    conf = _confidence(road, scale.confidence, bool(pose.implausible), parallel_conf)
    return RoadGeometry(
        size_px=(w, h), vanishing_point_px=(float(road.vp[0]), float(road.vp[1])),
        horizon_row_px=road.horizon_row,
        horizon_slope=road.horizon_slope, roll_deg=roll, roll_source=road.roll_source, pitch_deg=pose.pitch_deg,
        yaw_deg=pose.yaw_deg, camera_height_m=pose.height_m, focal_px=fx,
        focal_source=focal_source if fx is not None else "unknown",
        hood_row_px=road.hood_row, hood_source=road.hood_source, src_px=view.src, dst_px=view.dst,
        lane_width_m=float(lane_width_m), look_ahead_m=float(view.look_ahead_m), near_m=float(view.near_m),
        visible_length_m=float(view.visible_m), xm_per_px=xm, ym_per_px=ym, scale_source=scale.source,
        inverse_depth_scale_px_m=float(C), lane_width_ratio=r_k, dash_fit=float(scale.dash_fit),
        confidence=float(round(conf, 4)),
        assumptions=tuple(assumptions), frames_used=used, frames_rejected=road.rejected,
        frame_vanishing_points=tuple((i, float(p[0]), float(p[1])) for i, p in zip(used, road.vps)))


def _focal(calibration: Calibration | None, focal_px: float | None) -> tuple[float | None, float | None, str]:
    """Return (fx, fy, their source): ``focal_px`` when given (fy scaled with it), else a measured
    calibration's, else (None, None, "unknown")."""
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
    return fx, fy, focal_source


def _angles(pp_uv: np.ndarray, f_x: float, f_y: float) -> tuple[float, float]:
    """Return (pitch, yaw) in radians of a camera whose principal point lies at ``pp_uv`` about
    the vanishing point, for focal lengths f_x, f_y."""
    pp_u, pp_v = pp_uv
    theta = math.atan2(pp_v, f_y)
    psi = math.atan(pp_u * math.cos(theta) / f_x)
    return theta, psi


def _c_from_focal(road: _Road, lane_width_m: float, f_x: float, f_y: float) -> float:
    """Return C (s = C / v + s0) from focal lengths and the lane width: f w / (r cos(pitch) cos^2(yaw))."""
    theta, psi = _angles(road.pp_uv, f_x, f_y)
    return f_x * lane_width_m / (road.r_k * math.cos(theta) * math.cos(psi) ** 2)


@dataclass(frozen=True)
class _Scale:
    """The scale along the road (``_scale``): C in s = C / v + s0, where it comes from and how
    far to trust it (a factor of the confidence), how well the dashes fit, and the focal lengths
    it leaves (None: unknown) with their source."""

    c: float
    source: str
    confidence: float
    dash_fit: float
    fx: float | None
    fy: float | None
    focal_source: str


def _scale(road: _Road, fx: float | None, fy: float | None, focal_source: str, lane_width_m: float,
           dash_m: float, gap_m: float, focal_confidence: float, assumptions: list[str]) -> _Scale:
    """Return the scale along the road, from the dash period where dashed lines are seen, else the
    focal length and the lane width, else an assumed focal length (ASSUMED_HFOV_DEG). A dash
    period that disagrees with a known focal length by more than DASH_DISAGREEMENT yields to it;
    one with no known focal length gives the focal length. What it assumed joins ``assumptions``."""
    w = road.look.size[0]
    c_focal = _c_from_focal(road, lane_width_m, fx, fy) if fx is not None else None
    c_dash, dash_fit, f_dash = _dash_c(road, c_focal, lane_width_m, dash_m, gap_m, assumptions)
    scale_conf = 1.0
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
        C = _c_from_focal(road, lane_width_m, fa, fa)
        scale_source = f"assumed focal length {fa:.0f} px ({ASSUMED_HFOV_DEG:g} deg field of view)"
        assumptions.append(f"no dashed lines and no focal length: a focal length of {fa:.0f} px "
                           f"({ASSUMED_HFOV_DEG:g} deg horizontal field of view) is assumed; the scale "
                           "along the road may be off by tens of percent")
        scale_conf = 0.4
    return _Scale(C, scale_source, scale_conf, dash_fit, fx, fy, focal_source)


def _dash_c(road: _Road, c_focal: float | None, lane_width_m: float, dash_m: float, gap_m: float,
            assumptions: list[str]) -> tuple[float | None, float, float | None]:
    """Return (C from the dash period, how well the dashes fit it, the focal length it implies),
    C None without a period or when its focal length is out of reach for a road camera (0.2-6
    image widths; said in ``assumptions``). C is searched within DASH_FOCAL_RANGE of ``c_focal``,
    or, with no focal length known, over the focal lengths of FOCAL_RANGE_W."""
    w = road.look.size[0]
    r_k = road.r_k
    if c_focal is not None:
        c_range = (c_focal / DASH_FOCAL_RANGE, c_focal * DASH_FOCAL_RANGE)
    else:
        c_range = tuple(f * w * lane_width_m / r_k for f in FOCAL_RANGE_W)
    c_dash, dash_fit = _dash_scale(road.dashes, dash_m, gap_m, c_range)
    f_dash = None
    if c_dash is not None:
        f_dash = c_dash * r_k / lane_width_m
        for _ in range(4):  # the angles depend on the focal length
            theta, psi = _angles(road.pp_uv, f_dash, f_dash)
            f_dash = c_dash * r_k * math.cos(theta) * math.cos(psi) ** 2 / lane_width_m
        if not 0.2 * w <= f_dash <= 6 * w:
            assumptions.append(f"a dash period was found but implies a focal length of {f_dash:.0f} px, "
                               "out of reach for a road camera: not used")
            c_dash = None
    return c_dash, dash_fit, f_dash


@dataclass(frozen=True)
class _Pose:
    """The camera's pitch, yaw and height (None without a focal length), its own line's slope
    ``k_c`` and the offset ``s0`` in s = C / v + s0 (0 without one), and why its height is
    implausible ('' when it is not)."""

    pitch_deg: float | None
    yaw_deg: float | None
    height_m: float | None
    k_c: float
    s0: float
    implausible: str


def _pose(pp_uv: np.ndarray, fx: float | None, fy: float | None, focal_source: str, r_k: float,
          lane_width_m: float, assumptions: list[str]) -> _Pose:
    """Return the camera's pose from its focal lengths and the ego lane's width r; a height outside
    CAMERA_HEIGHT_RANGE_M, or no focal length (the camera on the car's centre line), joins
    ``assumptions``."""
    pitch = yaw = height = None
    implausible = ""
    k_c, s0 = 0.0, 0.0
    if fx is not None:
        theta, psi = _angles(pp_uv, fx, fy)
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
    return _Pose(pitch, yaw, height, k_c, s0, implausible)


def _confidence(road: _Road, scale_conf: float, implausible: bool, parallel_conf: float) -> float:
    """Return the estimate's confidence (0-1): the product of the factors the module docstring lists."""
    n_used = len(road.used)
    conf = min(1.0, n_used / MIN_GOOD_FRAMES)
    # how well the frames pin the vanishing point: the standard error of their mean row (a car
    # that pitches over bumps scatters each frame's point by a few px; many frames still pin it)
    std_err_y = road.scatter_y / math.sqrt(n_used) if n_used > 1 else float("nan")
    if n_used > 1 and std_err_y > 1.0:
        conf *= math.exp(-((std_err_y - 1.0) / 3.0) ** 2)
    conf *= scale_conf
    conf *= min(1.0, len(road.ego) / MIN_GOOD_FRAMES)
    if road.hood_source.startswith("not detected"):
        conf *= 0.9
    if implausible:
        conf *= IMPLAUSIBLE_CONFIDENCE
    conf *= parallel_conf
    return conf


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
            # the raw frames' dashes are measured through the lens, whose distortion shortens
            # them: a scale not to be trusted
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
