"""How a track starts from a pitched pair: without a track, a pair refused only as not parallel
may be a lane in a pitched flat view, and starts the track when such pairs agree
``pitched_start_frames`` frames in a row. (A restart from one line is ``roads.checks.restart``.)
"""
from __future__ import annotations

import numpy as np

from ..checks import pitched_pair_problem


def pitched_start(t, kept: dict, problem: str, top_px: int, why: list[str]) -> bool:
    """Return whether a pair refused without a track as not parallel starts the track as a pitched
    lane, agreeing with the previous frame's (``LaneTracker.agree``) ``pitched_start_frames`` in a
    row; remembers such a pair for the next frame.
    """
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
                   if all(t.agree(a, b) for a, b in zip(pair, previous))), default=0)
    pitched[1].append((run, *pair))
    if run < cfg.pitched_start_frames:
        return False
    why[-1] = (f"{problem}, but a lane in a pitched flat view (its width changes linearly, within "
               f"{cfg.max_pitch_change:.0%} of its width at the car) {run} frames in a row: the "
               "track starts")
    return True
