"""What the pipeline (or the tracker) reports for one frame: ``FrameResult``, ``Rejected``,
confidences; the vocabulary ``LanePipeline`` and ``LaneTracker`` share.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from .params import SearchConfig
from .records import LaneMeasurement, LaneSearch, LineFit


def line_confidence(fit: LineFit, height_px: int, config: SearchConfig = SearchConfig()) -> float:
    """Return a 0-1 confidence of a fitted line: vertical span covered times pixel support."""
    if not fit.found:
        return 0.0
    span = min(1.0, fit.span_px / (0.75 * height_px))
    support = min(1.0, fit.n_pixels / (4.0 * config.min_line_pixels))
    return round(span * support, 3)


def _round(v: float, nd: int) -> float:
    return v if math.isnan(v) else round(float(v), nd)


def _json_number(v: float, nd: int) -> float | None:
    """Return ``v`` rounded to ``nd`` digits, or None where it is not finite (for JSON)."""
    return round(float(v), nd) if math.isfinite(v) else None


@dataclass(frozen=True)
class Rejected:
    """A lane that failed the plausibility checks: its fits as the search made them, what they measured
    (NaN where a line is missing), and why.
    """

    left: LineFit
    right: LineFit
    measurement: LaneMeasurement
    reason: str

    def summary(self) -> dict:
        """Return radius, offset and width of the rejected lane (None where not measured) and why."""
        m = self.measurement
        return {"radius_m": _json_number(m.radius_m, 1), "offset_m": _json_number(m.offset_m, 3),
                "lane_width_m": _json_number(m.lane_width_m, 3), "reason": self.reason}


@dataclass(frozen=True)
class FrameResult:
    """What the pipeline (or the tracker) found in one frame.

    ``found`` is true when both lines were found and passed the checks (``LaneChecks``); otherwise
    ``reason`` says why and the measurements are NaN, a detection that failed being kept in
    ``rejected``, never reported as the lane. ``left_conf``/``right_conf``: 0-1 confidences (0 when
    not found or rejected). ``sources`` says where each line comes from: "seen" (paint found in this
    frame), "edge" (the unpainted asphalt edge, ``roads.edge.road_edge``), "shoulder" (a faded line
    placed its shoulder inside the edge, ``roads.proposers.Shoulder``), "inferred" (from the other
    line and the tracked width), "held" (earlier frames), "" (none). ``images`` holds the stage
    images (undistorted, birdseye, binary, search, result) when asked to keep them.
    """

    left: LineFit
    right: LineFit
    measurement: LaneMeasurement
    method: str
    left_conf: float
    right_conf: float
    reason: str = ""
    search: LaneSearch | None = field(default=None, repr=False)
    images: dict = field(default_factory=dict, repr=False)
    rejected: Rejected | None = None
    sources: tuple[str, str] = ("", "")

    @property
    def left_found(self) -> bool:
        return self.left.found

    @property
    def right_found(self) -> bool:
        return self.right.found

    @property
    def found(self) -> bool:
        return self.left.found and self.right.found

    @property
    def radius_m(self) -> float:
        return self.measurement.radius_m

    @property
    def curvature_per_m(self) -> float:
        return self.measurement.curvature_per_m

    @property
    def offset_m(self) -> float:
        return self.measurement.offset_m

    @property
    def lane_width_m(self) -> float:
        return self.measurement.lane_width_m

    def summary(self) -> dict:
        """Return the per-image record written to results.json (NaN where not found); ``rejected`` is None,
        or a failed detection's radius, offset, width and why (``Rejected.summary``).
        """
        return {"found": self.found, "left_found": self.left_found, "right_found": self.right_found,
                "radius_m": _round(self.radius_m, 1), "offset_m": _round(self.offset_m, 3),
                "lane_width_m": _round(self.lane_width_m, 3), "reason": self.reason,
                "rejected": self.rejected.summary() if self.rejected is not None else None}
