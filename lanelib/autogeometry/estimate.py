"""``estimate_geometry``: the bird's-eye geometry of a camera from frames of the road.

All in the undistorted image (frames are undistorted first when a ``camera.Lens`` or
``camera.Calibration`` is given, or a lens measured from the road's lines, ``lens``):

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
  (2.5 %; frames' median; ``_view_widening``): a lens that distorts and was not given (a
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
from dataclasses import replace
from typing import Iterable

import cv2
import numpy as np

from ..camera import Calibration, Lens
from ..errors import GeometryError, InputError
from ..perspective import DEFAULT_LANE_WIDTH_M
from .dashes import DASH_DISAGREEMENT, _dash_scale
from .horizon import _Basis
from .lens import LensEstimate, estimate_lens
from .road import _analyse_road, _look, _Look, _Road
from .roadgeometry import RoadGeometry
from .vanishing import _check_frame

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
# the ego lane may widen or narrow by this fraction from the bottom third of the bird's-eye view to
# its top third (frames' median) before the view is taken as wrong: a lens not given, a road not flat
LANE_PARALLEL_TOLERANCE = 0.025
IMPLAUSIBLE_CONFIDENCE = 0.4   # the confidence is multiplied by this then (below LOW_CONFIDENCE)
FOCAL_CONFIDENCE = 0.9         # ... by this when the scale along the road is a focal length's, not dashes'
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
