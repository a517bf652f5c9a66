"""The bird's-eye points of a camera mounted a little otherwise, refined from the lines it sees.

A benchmark preset holds one camera's bird's-eye points. Another car's camera, pitched or turned
a little differently, sees the road's vanishing point elsewhere: a pitch moves it up or down, a
yaw sideways, and for small angles the whole image moves with it. Through the preset's points the
lines of such a camera fan apart (pitch) or turn (yaw) in the bird's-eye view, and the vote, which
looks for parallel lines, finds fewer of them.

``refine_points`` runs the lines search (``LanePipeline.detect_lines``) on frames of one camera,
fits a straight line to the near half of each line found, and takes the point where those lines
meet (``meeting_point``): the vanishing point as this camera sees it. Where it lies further from
the points' own vanishing point (where the sides of their trapezoid meet, ``points_vanishing``)
than ``LinesConfig.refine_points_px`` vertically, or twice that sideways (a turned view only tilts
the lines, which the vote's headings partly take up; a pitched one fans them), the four points
move by the difference, and the search runs again through the moved points, up to ``ROUNDS``
times: lines found through points that are off lean towards those points, so one round sees
about half of the way. For the same reason a first round that sees the lines meet within half
the threshold is the last: the points are right. The threshold is the estimate's own error on
frames whose points are right: the near halves of real lines, through the lens and over grades,
meet a few pixels from where the road's lines meet.

The road's own shape moves the point too: a sequence driven mostly on one long bend or grade
sees its lines meet aside or above where a straight, flat road's would, and the points follow.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import io
from ..camera import Calibration, Lens
from ..config import PipelineConfig
from ..errors import ConfigError, InputError, LaneLibError
from ..lines.result import ImageLine
from ..perspective import as_points
from ..pipeline import LanePipeline

FRAMES = 20          # frames of a sequence the estimate reads, evenly spread
ROUNDS = 3           # searches at most: the first through the config's points, then through the moved ones
MIN_LINES = 10       # lines (each of at least MIN_RISE_PX rows) the estimate needs
MIN_RISE_PX = 40.0   # the near half of a line must rise this many rows to give a direction
SIDEWAYS = 2.0       # the sideways threshold is this many times the vertical one
SETTLED_PX = 1.0     # a round that moves the point less than this ends the rounds


@dataclass(frozen=True)
class PointsRefinement:
    """What ``refine_points`` made of one sequence's frames.

    ``meeting_px`` is where the lines found meet, relative to the points' own vanishing point
    ((x, y) px in the config's image size; None when there are too few lines to tell);
    ``shift_px`` the shift of the config's four bird's-eye points ((0, 0) when they are kept);
    ``lines`` the lines the last estimate rests on; ``reason`` why the points were kept or moved.
    """

    sequence: str
    meeting_px: tuple[float, float] | None
    shift_px: tuple[float, float]
    lines: int
    reason: str

    @property
    def moved(self) -> bool:
        return self.shift_px != (0.0, 0.0)

    def note(self) -> str:
        """Return the one-line note of this refinement.

        Examples
        --------
        >>> PointsRefinement("d/0001.MP4", (0.2, 12.4), (0.2, 12.4), 40, "its lines meet 12 px below").note()
        "d/0001.MP4: bird's-eye points moved by (+0, +12) px (its lines meet 12 px below)"
        >>> PointsRefinement("d/0002.MP4", None, (0.0, 0.0), 3, "too few lines").note()
        "d/0002.MP4: bird's-eye points kept (too few lines)"
        """
        if not self.moved:
            return f"{self.sequence}: bird's-eye points kept ({self.reason})"
        dx, dy = self.shift_px
        return f"{self.sequence}: bird's-eye points moved by ({dx:+.0f}, {dy:+.0f}) px ({self.reason})"


def points_vanishing(src_px) -> tuple[float, float]:
    """Return the (x, y) px where the left and right sides of a src trapezoid (tl, bl, br, tr) meet.

    Examples
    --------
    >>> points_vanishing(((600, 450), (200, 700), (1100, 700), (700, 450)))
    (650.0, 418.75)
    """
    (x0, y0), (x1, y1), (x2, y2), (x3, y3) = as_points(src_px)
    left, right = (x1 - x0) / (y1 - y0), (x2 - x3) / (y2 - y3)
    y = (x3 - x0 + left * y0 - right * y3) / (left - right)
    return float(x0 + left * (y - y0)), float(y)


def shifted_points(config: PipelineConfig, shift_px: tuple[float, float]) -> PipelineConfig:
    """Return ``config`` with its four bird's-eye source points moved by ``shift_px`` (x, y)."""
    dx, dy = shift_px
    src = tuple((x + dx, y + dy) for x, y in config.perspective.src_px)
    return replace(config, perspective=replace(config.perspective, src_px=src))


def near_directions(lines: Sequence[ImageLine], lens: Lens) -> np.ndarray:
    """Return (a, b, rise) of ``x = a y + b`` fitted to the near half (the lower half of its rows)
    of each line, in the undistorted image (``lens.inverse``), for the lines whose near half rises
    at least ``MIN_RISE_PX`` rows; ``rise`` is that height, the fit's weight."""
    out = []
    for line in lines:
        p = line.points_px if lens.is_identity else lens.inverse(line.points_px)
        if len(p) < 3:
            continue
        y = p[:, 1]
        near = y >= y.max() - 0.5 * (y.max() - y.min())
        rise = float(np.ptp(y[near]))
        if rise >= MIN_RISE_PX:
            a, b = np.polyfit(y[near], p[near, 0], 1)
            out.append((a, b, rise))
    return np.asarray(out, np.float64).reshape(-1, 3)


def meeting_point(directions: np.ndarray, rounds: int = 10) -> tuple[float, float]:
    """Return the (x, y) px nearest, in x, to every line ``x = a y + b`` of ``directions`` (rows
    (a, b, weight)): least squares, reweighted so that lines more than twice the median distance
    away (another road's lines, a kerb at a junction) count less.

    Examples
    --------
    >>> lines = np.array([[-1.0, 1000.0, 1], [1.0, 200.0, 1], [0.5, 400.0, 1], [-0.5, 800.0, 1]])
    >>> [round(v, 6) for v in meeting_point(lines)]
    [600.0, 400.0]
    """
    a, b, weight = directions[:, 0], directions[:, 1], directions[:, 2]
    design = np.column_stack([np.ones_like(a), -a])  # x_v - a y_v = b
    w = weight.copy()
    for _ in range(rounds):
        root = np.sqrt(w)
        point = np.linalg.lstsq(design * root[:, None], b * root, rcond=None)[0]
        dist = np.abs(design @ point - b)
        scale = 2.0 * 1.4826 * np.median(dist) + 1e-9
        w = weight / np.maximum(1.0, dist / scale)
    return float(point[0]), float(point[1])


def refine_points(frames: Sequence[np.ndarray], config: PipelineConfig, calibration: Calibration | None,
                  sequence: str = "") -> PointsRefinement:
    """Return how far to move ``config``'s bird's-eye points for the camera of ``frames`` (see the
    module's docstring): (0, 0) when its lines meet within ``config.lines.refine_points_px``
    (vertically; twice that sideways) of the points' own vanishing point, or when the frames give
    fewer than ``MIN_LINES`` lines to tell."""
    limit = config.lines.refine_points_px
    h, w = frames[0].shape[:2]
    sx, sy = config.perspective.size_px[0] / w, config.perspective.size_px[1] / h
    home = points_vanishing(config.perspective.src_px)
    lens = Lens(calibration, (w, h))
    shift, n = (0.0, 0.0), 0
    for round_ in range(ROUNDS):
        pipe = LanePipeline(shifted_points(config, shift), calibration, size=(w, h))
        found = [line for f in frames for line in pipe.detect_lines(f, ego=False).lines]
        directions = near_directions(found, lens)
        n = len(directions)
        if n < MIN_LINES:
            return PointsRefinement(sequence, None, (0.0, 0.0), n, f"{n} lines to tell from, fewer than {MIN_LINES}")
        x, y = meeting_point(directions)
        new = (x * sx - home[0], y * sy - home[1])
        settled = math.dist(new, shift) < SETTLED_PX or (round_ == 0 and _within(new, limit / 2))
        shift = new
        if settled:
            break
    meeting = (round(shift[0], 1), round(shift[1], 1))
    if _within(shift, limit):
        return PointsRefinement(sequence, meeting, (0.0, 0.0), n, _where(shift) + f", within {limit:g} px")
    return PointsRefinement(sequence, meeting, meeting, n, _where(shift))


def _within(shift: tuple[float, float], limit: float) -> bool:
    """Return whether ``shift`` lies within ``limit`` px vertically and ``SIDEWAYS`` times it sideways."""
    return abs(shift[1]) <= limit and abs(shift[0]) <= SIDEWAYS * limit


def _where(shift: tuple[float, float]) -> str:
    """Return e.g. "its lines meet 3 px right of and 12 px below the points' vanishing point"."""
    dx, dy = shift
    return (f"its lines meet {abs(dx):.0f} px {'right' if dx >= 0 else 'left'} of and {abs(dy):.0f} px "
            f"{'below' if dy >= 0 else 'above'} the points' vanishing point")


def sequence_refinement(images: Sequence[Path], config: PipelineConfig, calibration: Calibration | None,
                        sequence: str, read: Callable[[Path], np.ndarray] = io.read_image) -> PointsRefinement:
    """Return ``refine_points`` on up to ``FRAMES`` of a sequence's ``images``, evenly spread, each
    read by ``read`` (RGB; e.g. a reader that also resizes, as ``why`` reads TuSimple frames); an
    image that cannot be read, or of another size than the first, is left out (``predict_frame``
    reports it), and frames the pipeline refuses (a lanelib error other than a bad config) keep
    the points with the reason. A value, not an exception, so that a Dask task returns it alike."""
    step = max(1, math.ceil(len(images) / FRAMES))
    frames = []
    for image in images[::step]:
        try:
            frame = read(image)
        except InputError:
            continue
        if not frames or frame.shape == frames[0].shape:
            frames.append(frame)
    if not frames:
        return PointsRefinement(sequence, None, (0.0, 0.0), 0, "none of its images could be read")
    try:
        return refine_points(frames, config, calibration, sequence)
    except ConfigError:
        raise
    except LaneLibError as e:  # e.g. frames the calibration does not fit: each frame reports it
        return PointsRefinement(sequence, None, (0.0, 0.0), 0, str(e))
