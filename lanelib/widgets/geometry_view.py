"""The road-geometry estimate of ``PerspectiveTuner``: the points set from the road itself, its
lines in the readout and its horizon and vanishing point on the preview.

``GeometryEstimate`` is a base class of ``perspective.PerspectiveTuner`` that holds
``estimate``, ``set_geometry`` and the estimate button's handler apart from the tuner's point
controls; the tuner's ``_build`` makes the state they use (``geometry_options``, ``geometry``,
``_geometry``, ``estimate_button``), and ``set_geometry`` sets the tuner's ``_pending`` clicks and
``_focal_px`` as its own point setters do. The functions below it take the estimate as an argument:
``geometry_lines`` and ``low_confidence_line`` for the readout, ``draw_horizon`` for the preview.
"""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from .. import autogeometry, batch
from ..autogeometry import LOW_CONFIDENCE, RoadGeometry
from ..config import PipelineConfig
from ..errors import GeometryError, InputError, LaneLibError
from ..perspective import Perspective, PerspectiveConfig, implied_focal_px, scaled


class GeometryEstimate:
    """Set ``PerspectiveTuner``'s points from a road geometry: estimated from the picked item
    (``estimate``, the ``estimate`` button) or given (``set_geometry``)."""

    def estimate(self, start_s: float | None = None, **options) -> RoadGeometry:
        """Estimate the road geometry from the picked item, set the points to it and return it.

        A video: ``batch.estimate_road_geometry`` of the picked clip, ``seconds`` of it from
        ``start_s`` (default: its start), ``max_frames`` frames evenly spread, what
        ``python -m lanelib geometry CLIP`` gives. An image: ``geometry.estimate_geometry`` of
        this frame alone (one frame measures neither the hood nor the roll and gives a low
        confidence). Both with the tuner's calibration for the item. The result goes into the
        controls through ``set_geometry``.

        Parameters
        ----------
        start_s : where in the clip the frames start (s); videos only.
        **options : fields of ``autogeometry.GeometryOptions`` that replace those of
            ``self.geometry_options`` for this estimate: ``lane_width_m``, ``look_ahead_m``,
            ``dash_m``, ``gap_m``, ``focal_px``, ``seconds``, ``max_frames``,
            ``accept_low_confidence`` (on by default here: a low-confidence estimate is
            applied and flagged in the readout; off refuses it with a ``GeometryError``).

        Raises
        ------
        GeometryError
            If the frames give no consistent vanishing point (the reason: no road, too few
            segments, inconsistent, road not straight), or a low confidence is refused; the
            points are left as they are.
        InputError
            For an unknown option, or ``start_s`` with an image.
        """
        names = set(autogeometry.GeometryOptions.__dataclass_fields__)
        unknown = sorted(set(options) - names)
        if unknown:
            raise InputError(f"estimate: unknown options {unknown}; use fields of "
                             f"autogeometry.GeometryOptions ({', '.join(sorted(names))})")
        opts = replace(self.geometry_options, **options)
        label, path = self.image, self.images[self.image]
        calibration = self.calibration_for(label)
        # a low confidence is judged below; the tuner's frames go through its own calibration
        # (or none), so no lens is estimated from the road for points it could not undistort by
        trial = replace(opts, accept_low_confidence=True)
        if self.is_video:
            start = 0.0 if start_s is None else float(start_s)
            geo = batch.estimate_road_geometry(path, calibration, trial, start_s, lens_from_road=False)
            source = f"the clip {label}, {opts.seconds:g} s from {start:g} s"
        else:
            if start_s is not None:
                raise InputError(f"{label}: start_s is for a video; an image is estimated from "
                                 "this frame alone")
            try:
                geo = trial.estimate([self._raw], calibration, lens_from_road=False)
            except GeometryError as e:
                raise GeometryError(f"{label}: {e}") from None
            source = f"this frame alone ({label})"
        if geo.low_confidence and not opts.accept_low_confidence:
            raise GeometryError(
                f"{label}: the road geometry estimated from {source} has confidence "
                f"{geo.confidence:.2f}, below {LOW_CONFIDENCE} ({'; '.join(geo.assumptions)}); "
                "the points are unchanged: estimate from a clip with a longer straight stretch, "
                "or pass accept_low_confidence=True to apply it, flagged")
        self.set_geometry(geo, source)
        return geo

    def set_geometry(self, geo: RoadGeometry, source: str = "") -> PipelineConfig:
        """Set the points of a road geometry (``geo.perspective_config()``); return the new config.

        The src and dst points, the lane width, the visible length and the car's centre line
        (``car_x_px``) become exactly those of ``geo`` (scaled to the picked item when ``geo``
        was estimated on frames of another size). The readout shows ``geo``'s summary, what it
        assumed and, below ``geometry.LOW_CONFIDENCE``, a "low confidence" flag; the preview
        draws its horizon and vanishing point. ``source`` says in the readout where ``geo``
        came from (e.g. "out/geometry.json").
        """
        pc = geo.perspective_config()
        size = (self._raw.shape[1], self._raw.shape[0])
        if tuple(pc.size_px) != size:
            pc = scaled(pc, size)
        Perspective(pc)  # refuses collinear points with a ConfigError
        self.error = ""
        self._pending = []
        self.geometry = geo
        self._geometry = (self.image, pc, source)
        self._show(replace(self.config, perspective=pc))
        self._focal_px = implied_focal_px(pc)
        self._update(None)
        self._refresh()
        return self.config

    def _on_estimate(self, button=None) -> None:
        """Estimate from the picked item (``estimate``), or show why it failed in red."""
        what = "clip" if self.is_video else "frame"
        self.message.value = (f'<pre style="margin:0">estimating the road geometry from this {what} '
                              "...</pre>")
        self.estimate_button.disabled = True
        try:
            self.estimate()
        except LaneLibError as e:
            self._show_error(str(e))
        finally:
            self.estimate_button.disabled = False



def low_confidence_line(geo: RoadGeometry | None) -> str:
    """Return the readout's flag of a low-confidence estimate ("" for none or a confident one)."""
    if geo is None or not geo.low_confidence:
        return ""
    n = len(geo.frames_used)
    return (f"low confidence: {geo.confidence:.2f}, below {LOW_CONFIDENCE} ({n} frame"
            f"{'' if n == 1 else 's'} on straight road) - check the points before saving")


def geometry_lines(geo: RoadGeometry, applied: PerspectiveConfig, source: str,
                   shown: PerspectiveConfig) -> list[str]:
    """Return the readout's lines about the estimate ``geo``: where it came from (``source``),
    its flag, summary and assumptions, and a note when the points ``shown`` are no longer the
    ones it set (``applied``)."""
    lines = [f"road geometry estimated from {source}:" if source else "road geometry estimated:"]
    flag = low_confidence_line(geo)
    if flag:
        lines.append(flag)
    lines += ["  " + line for line in geo.summary().splitlines()]
    lines.append("  assumed: " + "; ".join(geo.assumptions))
    if shown != applied:
        lines.append("  (the points have been changed since this estimate)")
    return lines


def draw_horizon(tile: np.ndarray, geo: RoadGeometry) -> None:
    """Draw the horizon and vanishing point of ``geo`` on the undistorted tile, in place."""
    th, tw = tile.shape[:2]
    gw, gh = geo.size_px
    sx, sy = tw / gw, th / gh
    ends = [(x, geo.horizon_row_px + geo.horizon_slope * (x - gw / 2)) for x in (0.0, float(gw))]
    (x0, y0), (x1, y1) = ((round(x * sx), round(y * sy)) for x, y in ends)
    cv2.line(tile, (x0, y0), (x1, y1), (0, 255, 255), 1, cv2.LINE_AA)
    vx, vy = geo.vanishing_point_px
    cv2.drawMarker(tile, (round(vx * sx), round(vy * sy)), (0, 255, 255), cv2.MARKER_CROSS, 14, 2,
                   cv2.LINE_AA)
