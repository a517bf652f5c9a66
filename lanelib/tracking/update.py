"""The end of a tracked frame: infer a missing line and smooth, or hold, or lose the lane.

``accept`` takes a frame that kept a line: a missing one is inferred from it
(``LaneTracker.inferred_line``, half its confidence) and the reported lane is the remembered
frames' smoothed average. ``hold_or_lose`` takes a frame that kept none: the predicted lane is
held up to ``hold_frames`` frames with a confidence falling to zero (blind frames, no line seen
at all, as under an overpass, up to ``blind_hold_frames`` more); then the track is forgotten
until a pair passes the checks.
"""
from __future__ import annotations

import numpy as np

from ..fit import normal_width_m
from ..records import LineFit, line_source
from ..result import FrameResult
from ..proposers import SIDES, Candidate
from ..roads.checks import bent_gap, remember_accepted
from .state import Accepted



def accept(t: "LaneTracker", best: Candidate, track, images: dict,
           spread: np.ndarray | None = None) -> FrameResult:
    """Remember a frame that kept at least one line and return its result: the smoothed lane
    (``spread``: the view's scale across the road ahead for an inferred line, from a double
    line's stripes)."""
    s, search = t.state, best.search
    left, right = best.left, best.right
    notes = list(best.why)
    coeffs, confs = {}, {}
    for side, fit in (("left", left), ("right", right)):
        if fit is not None:
            coeffs[side] = np.array(fit.coeffs_px, float)
            confs[side] = t.pipeline.line_confidence(fit)
    for side, other, i in (("left", "right", 0), ("right", "left", 1)):
        if side not in coeffs:  # infer from the other line and the tracked lane width
            coeffs[side] = t.inferred_line(coeffs[other], track, i, search.top_px, spread)
            confs[side] = round(0.5 * confs[other], 3)
            widened = " at the car, widened ahead as its double stripes" if spread is not None else ""
            width = "the tracked width" if track is not None else "the width seen before the loss"
            notes.append(f"{side} line inferred from the {other} line and {width}{widened}")
    accepted = Accepted(coeffs["left"], coeffs["right"], confs["left"], confs["right"],
                        search.top_px, s.frame, (left is None, right is None))
    s.history.append(accepted)
    s.trend.append(accepted)
    s.inferred_run = [0 if t.reach_car(fit) else run + 1 for run, fit in zip(s.inferred_run, (left, right))]
    # a line placed the shoulder inside the asphalt edge is no paint seen: its paint is still
    # missing, and the width at the car is not measured on it
    seen = [None if search.shoulder[i] else fit for i, fit in enumerate((left, right))]
    if (t.reach_car(seen[0]) and t.reach_car(seen[1])  # both seen at the car: measured there
            and not any(bent_gap(t, fit, track, i) for i, fit in enumerate(seen))):
        s.seen_widths.append(normal_width_m(coeffs["left"], coeffs["right"], t.bottom, t.xm, t.ym))
    s.lost = s.blind = 0
    s.conf = (confs["left"], confs["right"])
    remember_accepted(t, best, track, seen, coeffs)  # what the hard-road parts remember of the frame
    kinds = tuple("inferred" if fit is None else line_source(search, i) for i, fit in enumerate((left, right)))
    return _result(t, t.lane, s.conf, search.method, {"left": left, "right": right}, best, notes, images, kinds)


def hold_or_lose(t: "LaneTracker", best: Candidate, track, images: dict, blind: bool) -> FrameResult:
    """Count a frame that kept no line (``blind``: no search saw any line) and return its
    result: the predicted lane held, or no lane once the hold is over (the track forgotten)."""
    s, cfg = t.state, t.config
    notes = list(best.why)
    if track is not None and (note := _hold(t, blind)):
        counted = s.lost - s.blind
        share = (1.0 - counted / (cfg.hold_frames + 1)) * (1.0 - s.blind / (cfg.blind_hold_frames + 1))
        notes.append(note)
        confs = tuple(round(c * share, 3) for c in s.conf)
        return _result(t, track, confs, "hold", {}, best, notes, images, ("held", "held"))
    if track is not None:
        blinds = f" beside {s.blind} frames with nothing seen" if s.blind else ""
        notes.append(f"lane lost for more than {cfg.hold_frames} frames{blinds}; tracker reset")
        t.forget_track()
    else:
        s.lost += 1
    reason = "; ".join(notes) or "no lane"
    left, right = LineFit(None, reason=reason), LineFit(None, reason=reason)
    return FrameResult(left, right, t.pipeline.measure(left, right), best.search.method,
                       0.0, 0.0, reason, best.search, images)


def _hold(t: "LaneTracker", blind: bool) -> str:
    """Count one more frame without a lane and return its hold's note, or "" when the hold is over; a
    blind frame uses up ``blind_hold_frames`` first, any other counts toward ``hold_frames``.
    """
    s, cfg = t.state, t.config
    if blind and s.blind < cfg.blind_hold_frames:
        s.lost += 1
        s.blind += 1
        return f"holding the last good lane (nothing seen: {s.blind} of {cfg.blind_hold_frames} blind frames)"
    counted = s.lost - s.blind
    if counted >= cfg.hold_frames:
        return ""
    s.lost += 1
    return f"holding the last good lane ({counted + 1} of {cfg.hold_frames} frames)"


def _result(t: "LaneTracker", coeffs, confs, method: str, sources: dict, best: Candidate,
            notes: list[str], images: dict, kinds: tuple[str, str]) -> FrameResult:
    fits = []
    for side, c in zip(SIDES, coeffs):
        src = sources.get(side)
        fits.append(LineFit(tuple(float(v) for v in c), src.n_pixels if src else 0,
                            src.span_px if src else 0.0, "" if src else _note_for(side, notes)))
    left, right = fits
    return FrameResult(left, right, t.pipeline.measure(left, right), method,
                       float(confs[0]), float(confs[1]), "; ".join(notes), best.search, images,
                       sources=kinds)


def _note_for(side: str, notes: list[str]) -> str:
    """Return the notes about one line (why it was inferred or held)."""
    mine = [n for n in notes if n.startswith(side) or n.startswith("holding")]
    return "; ".join(mine) or "not detected in this frame"
