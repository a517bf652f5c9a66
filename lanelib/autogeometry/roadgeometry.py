"""``RoadGeometry``: the bird's-eye geometry of a camera estimated from the road, and its refinement.

``RoadGeometry.perspective_config()`` is the ``perspective.PerspectiveConfig`` to run with;
``refined_geometry`` moves the vanishing point (and the bird's-eye view with it) along the
horizon to where the straight frames through a video place it (``watch.GeometryWatch``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..camera import Calibration
from ..errors import GeometryError
from ..perspective import Perspective, PerspectiveConfig
from .horizon import _basis
from .vanishing import Point

LOW_CONFIDENCE = 0.5
DRIFT_PX = 3.0          # a vanishing point this far off the horizon has drifted (see horizon_shift_px)


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
    the ego lane's r (``estimate``, ``horizon``); ``dash_fit`` how well the dashes fit the dash
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


def refined_geometry(geo: RoadGeometry, shift_px: float, why: str) -> RoadGeometry:
    """Return ``geo`` with its vanishing point moved ``shift_px`` along the horizon (positive to
    the right), as more frames of straight road place it (``watch.GeometryWatch``).

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
