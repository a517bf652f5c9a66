"""The hard-road checks of a tracked frame: a line seen short of the car on a bend, a grade read
from a double line's stripes, and a restart from one line.

``tracking.judge.TrackChecks`` calls them; each changes nothing unless its switch is on (the
``hard-roads`` preset's parts, in ``TrackerConfig``):

- near gap (``near_gap_m``): on a bend, a line whose paint stops short of the car is joined
  there to the line inferred from the other instead of extrapolated (``gap_limits_m``);
- grade pair check (``grade_pair_check``): a pair not parallel against the track is a lane when
  it is parallel on the grade a double line's stripes show (``graded_pair``);
- stripe spread (``stripe_spread``): a line inferred from the other follows the lane's width
  ahead that the other's double stripes show (``inferred_spread``);
- restart from one line (``restart_frames``): soon after a reset, one line where the lost track's
  was restarts the lane (``restart``).

``tracking.update.accept`` keeps what these parts and the proposers of ``roads.proposers``
remember of an accepted frame through ``remember_accepted``. The tracker is passed in
(duck-typed): this package sits below it in the layers.
"""
from __future__ import annotations

import numpy as np

from ..checks import line_problem, pair_problem
from ..proposers import SIDES, Candidate
from ..records import LaneSearch, LineFit
from .stripes import stripe_spread


# ---- a line seen short of the car on a bend (near gap) -------------------------------------

def gap_limits_m(t, left: LineFit, right: LineFit, bands: tuple[float, float], track) -> tuple[float, float]:
    """Return the largest gap (m) each line may stop short of the car by and count as seen
    there: ``near_gap_m`` (``gap_limit_m``) for a line seen short of the car by more than
    that where its tracked line bends over the gap (``bent_gap``) while the other line
    reaches within ``near_gap_m`` and passes its line checks, so that it is joined to the
    line inferred from the other; else ``max_gap_m``, where an extrapolation on a straight
    road does not rest on the curvature."""
    cfg = t.config
    if not cfg.near_gap_m or track is None:
        return cfg.max_gap_m, cfg.max_gap_m
    fits = (left, right)
    bent = [fit.found and bent_gap(t, fit, track, i) for i, fit in enumerate(fits)]
    if not any(bent):  # the usual frame: both lines reach the car, or the road is straight
        return cfg.max_gap_m, cfg.max_gap_m
    near = [fit.found and fit.gap_px * t.ym <= cfg.near_gap_m
            and not line_problem(fit, bands[i], t.checks, t.xm, SIDES[i])
            for i, fit in enumerate(fits)]
    return tuple(gap_limit_m(t, i) if bent[i] and near[1 - i] else cfg.max_gap_m
                 for i in range(2))


def bent_gap(t, fit: LineFit | None, track, side: int) -> bool:
    """Return whether a line reaches the car only by an extrapolation that rests on the
    curvature: its pixels stop more than ``near_gap_m`` short of the bottom row where its
    tracked line bends by more than ``near_gap_bend_m`` over the gap. The width seen at the car
    is not measured on such a line (``tracking.update.accept``)."""
    cfg = t.config
    return bool(cfg.near_gap_m and track is not None and fit.gap_px * t.ym > cfg.near_gap_m
                and abs(track[side][0]) * fit.gap_px ** 2 * t.xm > cfg.near_gap_bend_m)


def gap_limit_m(t, side: int) -> float:
    """Return ``near_gap_m`` when line ``side``'s paint reached the car in the newest accepted
    frames (not inferred, not faded: the track there is a measurement), else ``max_gap_m``."""
    cfg, s = t.config, t.state
    if (cfg.near_gap_m and s.history and not s.history[-1].inferred[side]
            and not s.inferred_run[side] and not s.faded_run[side]):
        return min(cfg.near_gap_m, cfg.max_gap_m)
    return cfg.max_gap_m


def paint_at_car(t, fit: LineFit | None, faded_run: int) -> bool:
    """Return whether ``fit`` is paint seen at the car; on a side whose paint has been missing
    at the car for ``faded_run`` accepted frames, only when its pixels reach within
    ``return_gap_m`` of the bottom row (returning paint seen farther ahead is joined nearer the
    car to the line placed inside the asphalt edge, ``roads.proposers.Shoulder``)."""
    if not t.reach_car(fit):
        return False
    return not faded_run or fit.gap_px * t.ym <= t.config.return_gap_m


def remember_accepted(t, best, track, seen: list, coeffs: dict) -> None:
    """Keep what the hard-road parts remember of an accepted frame (``tracking.update.accept``;
    ``seen``: its lines seen as paint, ``coeffs``: the pixel coefficients of both, one maybe
    inferred): the width at the car a restart from one line goes on with, how many accepted frames
    each side's paint has been missing at the car (``paint_at_car``: a faded line), the lines'
    bases (``base_history_frames``) and which side's line is the asphalt edge (an inferred line
    keeps its side's kind)."""
    s, search = t.state, best.search
    if track is None and (best.left is None or best.right is None):  # restarted from one line
        s.restart_width = s.lost_track.width_m
    at_car = [paint_at_car(t, fit, run) for fit, run in zip(seen, s.faded_run)]
    s.faded_run = [0 if near else run + 1 for run, near in zip(s.faded_run, at_car)]
    if s.base_history.maxlen:
        s.base_history.append(t.bases((coeffs["left"], coeffs["right"])))
    for i, fit in enumerate((best.left, best.right)):
        if fit is not None:
            s.edge[i] = bool(search.edge[i])


# ---- the grade a double line's stripes show (grade pair check, stripe spread) ---------------

def graded_pair(t, left: LineFit, right: LineFit, rows: np.ndarray, top_px: int, mask,
                problem: str) -> str:
    """Return the note that keeps a pair refused as not parallel against the track, "" when it
    is not kept: with ``grade_pair_check``, the pair passes against the width the road ahead's
    grade gives it in the flat view (``graded_reference``). ``mask``: a function returning the
    frame's whole-view mask (None: no such check)."""
    if not t.config.grade_pair_check or not problem.startswith("lines not parallel"):
        return ""
    graded = graded_reference(t, left, right, rows, top_px, mask)
    h = t.pipeline.size[1]
    if graded is None or pair_problem(left, right, h, t.xm, t.ym, t.checks, top_px, width_reference_px=graded):
        return ""
    return f"{problem} against the track, but parallel on the road ahead's grade (the double stripes' spread)"


def graded_reference(t, left: LineFit, right: LineFit, rows: np.ndarray, top_px: int,
                     mask) -> np.ndarray | None:
    """Return the lane's width (px) on ``rows`` as the road ahead's grade makes it in the flat
    view: the pair's width at the car times the scale across the road read from a double
    line's stripes along either line (``lane_spread``), or None when no stripes tell it."""
    if mask is None:
        return None
    for fit in (left, right):
        spread = lane_spread(t, mask(), fit.coeffs_px, top_px)
        if spread is not None:
            at_car = float(np.polyval(right.coeffs_px, t.bottom) - np.polyval(left.coeffs_px, t.bottom))
            return at_car * np.polyval(spread, t.bottom - rows)
    return None


def inferred_spread(t, best: Candidate, mask) -> np.ndarray | None:
    """Return the view's scale across the road ahead for the line a frame infers, read from the
    seen line's double stripes (``lane_spread``), or None: ``stripe_spread`` off, not exactly one
    line kept, or no stripes. ``mask``: a function returning the frame's whole-view mask."""
    if not t.config.stripe_spread or (best.left is None) == (best.right is None):
        return None
    seen = best.left if best.left is not None else best.right
    return lane_spread(t, mask(), seen.coeffs_px, best.search.top_px)


def lane_spread(t, binary: np.ndarray, coeffs_px, top_px: int) -> np.ndarray | None:
    """Return the view's scale across the road ahead from a double line's stripes along
    ``coeffs_px`` (``roads.stripes.stripe_spread``), or None."""
    return stripe_spread(binary, coeffs_px, t.pipeline.config.search.double_line_px, top_px,
                         t.pipeline.size)


# ---- a restart from one line ---------------------------------------------------------------

def restart(t, search: LaneSearch, kept: dict, why: list[str], failed: bool,
            candidates: list | None = None) -> Candidate:
    """Return the candidate of a frame without a track where not both lines make a lane.

    One line alone restarts the lane only within ``restart_frames`` frames after a reset
    of a track that saw both lines at the car: a line that reaches the car within
    ``restart_distance_m`` of the lost track's seen line on its side, confirmed by such a
    line in the previous frame (a lone line's fit has no pair to check its shape). When both
    lines so lie, neither restarts it: one of them is not a line of the lane.
    """
    cfg = t.config
    none = Candidate(search, None, None, why, failed)
    lines = {s: f for s, f in kept.items() if f is not None}
    if not lines:
        return none
    lost = t.state.lost_track
    if lost is None or t.state.lost >= cfg.restart_frames:
        why.append("one line alone cannot start a track")
        return none
    near = {}
    for side, fit in lines.items():
        i = SIDES.index(side)
        dist = abs(float(np.polyval(fit.coeffs_px, t.bottom)) - lost.bases[i]) * t.xm
        if lost.seen[i] and t.reach_car(fit) and dist <= cfg.restart_distance_m:
            near[side] = dist
    if len(near) != 1:
        why.append("one line alone cannot start a track" if len(lines) == 1 and not near else
                   "no single line lies where the lost track's line was" if not near else
                   "both lines lie where the lost track's lines were but are no lane together")
        return none
    (side, dist), = near.items()
    fit = lines[side]
    if candidates is not None:  # the next frame confirms a restart against it
        candidates.append((side, np.array(fit.coeffs_px, float)))
    agree = confirmed_restart(t, side, fit)
    if agree is None:
        why.append(f"{side} line lies where the lost track's {side} line was ({dist:.2f} m at the "
                   "car); it restarts the lane if the next frame's agrees with it")
        return none
    why.append(f"{side} line alone restarts the lane: {dist:.2f} m at the car from the lost "
               f"track's {side} line (limit {cfg.restart_distance_m} m), {t.state.lost + 1} "
               f"frames after the reset (limit {cfg.restart_frames}), the previous frame's within "
               f"{agree}")
    return Candidate(search, fit if side == "left" else None, fit if side == "right" else None,
                     why, failed)


def confirmed_restart(t, side: str, fit: LineFit) -> str | None:
    """Return how a line that could restart the lane agrees with one the previous frame could
    have restarted it from on the same side (``LaneTracker.agree``), or None when none agrees."""
    for previous_side, coeffs in t.state.restart_candidates[0]:
        if previous_side == side and (how := t.agree(fit.coeffs_px, coeffs)):
            return how
    return None
