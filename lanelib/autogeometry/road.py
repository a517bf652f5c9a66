"""What the frames of a road tell together, before any focal length (``_look``, ``_analyse_road``).

The estimate runs in three steps, so that the runs of ``estimate._with_estimated_lens`` (the same
frames with other focal lengths) analyse each set of frames once: ``_look`` (the image work of
every frame: its mask, lines and vanishing point, and the hood), ``_analyse_road`` (what the
frames tell together: the frames used, the vanishing point, the roll, the ego lane, the dashes'
runs of paint) and ``estimate._solve`` (what takes a focal length: the scale, the points, the
confidence).

Across frames, a frame whose vanishing point lies more than 1 % of the image height (at least
3 px) from the median row, or ``VP_X_TOLERANCE`` of the width from the median column, is left
out as inconsistent (a hill, a bump, a lane change).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Calibration, Lens
from ..errors import GeometryError
from .dashes import _dash_runs_of, _DashRuns
from .hood import HOOD_MAX_FRAMES, detect_hood
from .horizon import EGO_ANGLES_DEG, _basis, _Basis, _ego_frames, _roll_from_spacing
from .vanishing import RoadLineFinder, _FrameAnalysis

# A frame's vanishing point more than this share of the width from the others' is left out: the
# car's heading moves it by about f tan(heading) (1 deg: 1.6 % of the width at a 60 deg field of
# view); more is a bend whose lines still pass as straight (a 900 m curve: 3.5 %).
VP_X_TOLERANCE = 0.025
ROLL_MIN_FRAMES = 3
ROLL_MAX_SPREAD_DEG = 0.3


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
    analyses = look.analyses
    assumptions = list(notes)
    used, rejected = _consistent_frames(analyses, look.size)
    weights = np.array([analyses[i].vp.inlier_segments for i in used], np.float64)
    vps = np.array([analyses[i].vp.point_px for i in used])
    vp = (vps * weights[:, None]).sum(0) / weights.sum()
    scatter_y = float(np.std(vps[:, 1])) if len(used) > 1 else float("nan")

    # the ego lane: the nearest line left and right of the camera's; where a dashed line is not
    # seen, the nearest is the next lane's, so frames whose lane is much wider than most are left out
    angle_lists = {i: np.array([l.angle_deg for l in analyses[i].vp.lines]) for i in used}
    roll, roll_source = _roll(angle_lists, _ego_frames(angle_lists, 0.0), estimate_roll, vp, w, assumptions)
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
    pp = _principal_point(look.calibration, look.size, assumptions)
    hood, hood_row, hood_source = _hood_row(look, used, assumptions)
    return _Road(look, tuple(used), tuple(rejected), vp, vps, scatter_y, roll, roll_source, basis, slope, horizon_row, ego,
                 r_k, basis.to_uv(pp), hood, hood_row, hood_source,
                 _dash_runs_of(analyses, used, ego, hood, roll, (w, h)), tuple(assumptions))


def _consistent_frames(analyses: tuple[_FrameAnalysis, ...], size: tuple[int, int]
                       ) -> tuple[list[int], list[tuple[int, str]]]:
    """Return (the frames with a vanishing point on a straight road, consistent with the others;
    (frame, reason) of the others, sorted).

    Raises
    ------
    GeometryError
        If no frame is left; the message names every frame's reason.
    """
    w, h = size
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
    return used, rejected


def _roll(angle_lists: dict[int, np.ndarray], ego: dict[int, tuple[int, int, float]], estimate_roll: bool,
          vp: np.ndarray, w: int, assumptions: list[str]) -> tuple[float, str]:
    """Return (roll deg, its source): from the lanes' spacing (``_roll_from_spacing``) when at
    least ROLL_MIN_FRAMES frames give it one by one within ROLL_MAX_SPREAD_DEG, else 0; what it
    assumed joins ``assumptions``."""
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
    return roll, roll_source


def _principal_point(calibration: Calibration | None, size: tuple[int, int], assumptions: list[str]) -> np.ndarray:
    """Return the principal point (x, y px): a measured calibration's, else the image centre
    (which joins ``assumptions``, as does an estimated lens's focal length left unused)."""
    w, h = size
    if calibration is not None and calibration.estimated:
        assumptions.append(f"the lens was estimated ({calibration.estimated}): its focal length is not used")
    if calibration is not None and not calibration.estimated:
        K = calibration.camera_matrix
        pp = np.array([K[0, 2], K[1, 2]], np.float64)
    else:
        pp = np.array([w / 2, h / 2])
    if calibration is None or calibration.estimated:
        assumptions.append("principal point at the image centre")
    return pp


def _hood_row(look: _Look, used: list[int], assumptions: list[str]) -> tuple[np.ndarray, float, str]:
    """Return (the hood's top row per column, the hood row, its source): the detected hood's
    highest row over the middle 80 % of the columns, or, with no hood detected, just below the
    lowest lane-line pixel of the frames used (which joins ``assumptions``)."""
    w, h = look.size
    hood, hood_source = look.hood, look.hood_source
    if hood_source == "not detected":
        lowest = [max(l.rows_px[1] for l in look.analyses[i].vp.lines) for i in used]
        hood_row = float(min(h, np.max(lowest) + 1))
        hood_source = "not detected: just below the lowest lane-line pixel"
        assumptions.append("hood not detected (it takes 3 frames of a moving car): the view starts "
                           "just below the lowest lane-line pixel found")
        hood = np.full(w, hood_row)
    else:
        lo, hi = int(0.1 * w), int(0.9 * w)
        hood_row = float(np.min(hood[lo:hi]))
    return hood, hood_row, hood_source


def _no_frame_message(rejected: list[tuple[int, str]], n: int) -> str:
    """Return the error of a run where no frame gave a consistent vanishing point."""
    reasons: dict[str, list[int]] = {}
    for i, why in sorted(rejected):
        reasons.setdefault(why.split(":")[0], []).append(i)
    parts = [f"{why} ({len(ix)} frame{'s' if len(ix) > 1 else ''})" for why, ix in reasons.items()]
    first = sorted(rejected)[0][1] if rejected else ""
    return (f"no consistent vanishing point in {n} frame{'s' if n > 1 else ''}: {'; '.join(parts)}. "
            f"First: {first}")
