"""What ``LanePipeline.detect_lines`` reports: every lane line seen, in the RAW image (``ImageLine``,
made from a lines-view fit by ``image_line``), and the frame's lines with its ego lane (``LinesResult``)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..result import FrameResult
from .trace import ViewLine


@dataclass(frozen=True)
class ImageLine:
    """One lane line of ``LanePipeline.detect_lines``: where it is seen, in the RAW image.

    ``points_px`` is an (N, 2) array of (x, y) px of the line over the span where it has pixels,
    sorted by y; ``view`` is its fit in the lines view (``lines.trace.ViewLine``); ``offset_m`` is its
    distance (m) right (+) or left (-) of the car's centre line at the ego view's bottom row.
    """

    points_px: np.ndarray = field(repr=False)
    view: ViewLine
    offset_m: float

    def x_at_rows(self, rows_px) -> np.ndarray:
        """Return the line's x (px) at raw-image rows ``rows_px``; NaN where it is not seen."""
        p = self.points_px
        rows = np.asarray(rows_px, np.float64)
        if len(p) < 2:
            return np.full(len(rows), np.nan)
        return np.interp(rows, p[:, 1], p[:, 0], left=np.nan, right=np.nan)

    def joined(self, ahead: "ImageLine") -> "ImageLine":
        """Return this line going on as ``ahead`` where ``ahead`` is seen further from the car (its
        rows above this line's first row), with this line's view fit and offset."""
        p = self.points_px
        beyond = ahead.points_px[ahead.points_px[:, 1] < (p[0, 1] if len(p) else np.inf)]
        return replace(self, points_px=np.concatenate([beyond, p]))


def image_line(line: ViewLine, view_to_raw, car_x_px: float, bottom_px: float,
               xm_per_px: float, step_px: float = 1.0) -> ImageLine:
    """Return a view line as an ``ImageLine``: its fit sampled every ``step_px`` view rows over
    its span and mapped by ``view_to_raw`` (a transform with ``checked``: the lines view's
    inverse, then the lens), where that map is valid."""
    n = max(2, int(math.ceil((line.y_bottom_px - line.y_top_px) / step_px)) + 1)
    yv = np.linspace(line.y_top_px, line.y_bottom_px, n)
    pts, ok = view_to_raw.checked(np.column_stack([line.x_at(yv), yv]))
    pts = pts[ok]
    pts = pts[np.argsort(pts[:, 1], kind="stable")]
    return ImageLine(pts, line, float((line.x_at(bottom_px) - car_x_px) * xm_per_px))


@dataclass(frozen=True)
class LinesResult:
    """Every lane line ``LanePipeline.detect_lines`` saw, left to right, and the ego lane.

    ``ego`` is the frame's ``FrameResult`` (``detect``): what the overlay, curvature and offset
    use (None when not asked for: ``predict`` needs only the lines); ``lines`` holds every line
    seen, the ego pair's lines among them; ``refused`` the lines the search weighed and did not
    report, each with why (``LinesConfig.method = "vote"``: ``lines.vote.vote_candidates``).
    """

    lines: tuple[ImageLine, ...]
    ego: FrameResult | None
    images: dict = field(default_factory=dict, repr=False)
    refused: tuple[tuple[ImageLine, str], ...] = ()
