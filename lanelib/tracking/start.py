"""How a track starts without one: a pitched pair, or one line soon after a reset.

Without a track a pair refused only as not parallel may be a lane in a pitched flat view: it
starts the track when such pairs agree ``pitched_start_frames`` frames in a row
(``pitched_start``). One line alone restarts a track lost moments ago, where the lost track's
line was, confirmed by the previous frame (``restart``).
"""
from __future__ import annotations

import numpy as np

from ..checks import pitched_pair_problem
from ..records import LaneSearch, LineFit
from ..proposers import SIDES, Candidate


def restart(t: "LaneTracker", search: LaneSearch, kept: dict, why: list[str], failed: bool,
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

def confirmed_restart(t: "LaneTracker", side: str, fit: LineFit) -> str | None:
    """Return how a line that could restart the lane agrees with one the previous frame could
    have restarted it from on the same side (``agree``), or None when none agrees."""
    for previous_side, coeffs in t.state.restart_candidates[0]:
        if previous_side == side and (how := agree(t, fit.coeffs_px, coeffs)):
            return how
    return None

def agree(t: "LaneTracker", now, before) -> str:
    """Return how a line lies within ``max_jump_m`` at the car and ``max_bend_m`` in shape of
    another (pixel coefficients of both), "" when it does not."""
    dx = (np.polyval(now, t.rows) - np.polyval(before, t.rows)) * t.xm
    if abs(dx[-1]) > t.config.max_jump_m or dx.max() - dx.min() > t.config.max_bend_m:
        return ""
    return f"{abs(dx[-1]):.2f} m at the car and {dx.max() - dx.min():.2f} m in shape"

def pitched_start(t: "LaneTracker", kept: dict, problem: str, top_px: int, why: list[str]) -> bool:
    """Return whether a pair refused without a track as not parallel starts the track as a
    lane in a pitched flat view, ``pitched_start_frames`` frames in a row each agreeing with
    the previous one's (``agree``); remembers it for the next frame when it is such a lane."""
    cfg = t.config
    if not cfg.pitched_start_frames or not problem.startswith("lines not parallel"):
        return False
    left, right = kept["left"], kept["right"]
    if pitched_pair_problem(left, right, t.pipeline.size[1], t.xm, t.ym, t.checks, top_px,
                            cfg.max_pitch_change):
        return False
    pair = (np.array(left.coeffs_px, float), np.array(right.coeffs_px, float))
    pitched = t.state.pitched
    run = 1 + max((n for n, *previous in pitched[0]
                   if all(agree(t, a, b) for a, b in zip(pair, previous))), default=0)
    pitched[1].append((run, *pair))
    if run < cfg.pitched_start_frames:
        return False
    why[-1] = (f"{problem}, but a lane in a pitched flat view (its width changes linearly, within "
               f"{cfg.max_pitch_change:.0%} of its width at the car) {run} frames in a row: the "
               "track starts")
    return True
