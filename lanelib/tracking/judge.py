"""The checks of a tracked frame: which lines of a candidate search the track keeps, and why.

``TrackChecks.judge`` checks each line as in a single image (``checks.line_problem``) and
against the track: a line seen only far ahead (``checks.gap_problem``) is joined near the car to
a reference (``fit.joined_fit``); one that jumped at the car or bent away from its track is
refused, unless both bent alike and are a lane on their own (the road changed, the track lags).
The pair is then checked against the tracked width, except a pitched flat view's lane and a
grade read from a double line's stripes (``roads.checks.graded_pair``). Without a track, a pair
refused as not parallel may start one as a pitched lane (``start.pitched_start``), and one line
may restart a track lost moments ago (``roads.checks.restart``). The hard-road checks
(``roads.checks``) change nothing unless switched on.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..checks import gap_problem, line_problem, pair_problem, pitched_pair_problem
from ..fit import joined_fit
from ..records import LaneSearch, LineFit
from ..proposers import SIDES, Candidate
from ..roads.checks import gap_limits_m, graded_pair, restart
from .start import pitched_start


class TrackChecks:
    """The checks of one tracker (its geometry, ``TrackerConfig`` and ``LaneChecks``)."""

    def __init__(self, tracker: "LaneTracker"):
        self.t = tracker

    def judge(self, search: LaneSearch, track, top_px: int = 0, mask=None,
              candidates: list | None = None, bands: tuple[float, float] | None = None) -> Candidate:
        """Return what the checks keep of ``search`` against ``track`` (pixel coefficients, or None),
        over the look-ahead from ``top_px`` down. ``mask``: returns the frame's whole-view mask, for the
        grade pair check (None skips it). ``candidates``: collects the lines this frame could restart
        the lane from (None: the state is left as it is). ``bands``: each line's search band width (px;
        default ``checks.search_bands_px``).
        """
        t = self.t
        rows = t.rows if not top_px else np.linspace(float(top_px), t.bottom, len(t.rows))
        bands = t.pipeline.search_bands_px(search) if bands is None else bands
        failed = False
        why: list[str] = []
        kept: dict[str, LineFit | None] = {"left": None, "right": None}
        bent: dict[str, LineFit] = {}  # lines refused only for bending away from the track
        distant: dict[str, LineFit] = {}  # lines seen only far ahead that lie along their track
        limits = gap_limits_m(t, search.left, search.right, bands, track)
        for i, (side, fit) in enumerate((("left", search.left), ("right", search.right))):
            if not fit.found:
                why.append(f"{side} line not found ({fit.reason})")
                continue
            problem = line_problem(fit, bands[i], t.checks, t.xm, side)
            if problem:
                why.append(problem)
                failed = True
                continue
            far = gap_problem(fit, t.ym, limits[i], side) if track is not None else ""
            if far:
                if not self.confirms_track(fit, track[i], top_px, i):
                    why.append(far)
                    failed = True
                    continue
                kept[side] = distant[side] = fit
                continue
            if track is not None:
                problem, bends = self.track_problem(fit, track[i], rows, i)
                if problem:
                    why.append(problem)
                    failed = True
                    if bends:
                        bent[side] = fit
                    continue
            kept[side] = fit
        for i, side in enumerate(SIDES):
            if side in distant:  # joined to the other line's inference, or else to its track
                other = SIDES[1 - i]
                near = kept[other] is not None and other not in distant
                ref = t.inferred_line(np.array(kept[other].coeffs_px), track, i, top_px) if near else track[i]
                kept[side] = replace(distant[side], coeffs_px=self.joined(distant[side], ref, top_px))
                why.append(f"{gap_problem(distant[side], t.ym, limits[i], side)}; it lies "
                           f"along its track there, and nearer the car "
                           + ("the line inferred from the other line is taken" if near else "its track is taken"))
        if len(bent) == 2 and self.pair_outvotes_track(bent, track, rows, top_px):
            kept, failed = dict(bent), False
            why.append("both lines bent away from the track together and pass the pair checks: "
                       "the road changed, the track lags")
        if kept["left"] is not None and kept["right"] is not None:
            problem = self.pair_problem(kept, track, rows, top_px, mask, bool(distant), why)
            if problem:
                why.append(problem)
                failed = True
                if track is None:
                    if candidates is not None and pitched_start(t, kept, problem, top_px, why):
                        return Candidate(search, kept["left"], kept["right"], why, False)
                    return restart(t, search, kept, why, failed, candidates)
                lc, rc = (t.pipeline.line_confidence(kept[s]) for s in SIDES)
                drop = "right" if lc >= rc else "left"
                why.append(f"{drop} line dropped (lower confidence)")
                kept[drop] = None
        if track is None and (kept["left"] is None or kept["right"] is None):
            return restart(t, search, kept, why, failed, candidates)
        return Candidate(search, kept["left"], kept["right"], why, failed)

    # ---- a line against its track ---------------------------------------------------------

    def track_problem(self, fit: LineFit, tracked: np.ndarray, rows: np.ndarray, side: int) -> tuple[str, bool]:
        """Return why a line is no continuation of its tracked line ("" when it is), and whether only for
        its shape (a bend the other line may share): it jumped more than ``jump_limit_m`` at the car, or
        bent more than ``max_bend_m`` from the track where both are in view (not against an inferred
        line: a seen line is not checked against one never seen).
        """
        t = self.t
        name = SIDES[side]
        dx = (np.polyval(fit.coeffs_px, rows) - np.polyval(tracked, rows)) * t.xm
        dx = dx[self.bend_rows(fit, tracked, rows)]
        jump_m = t.jump_limit_m(side)
        if abs(dx[-1]) > jump_m:
            return f"{name} line jumped {abs(dx[-1]):.2f} m at the car (limit {round(jump_m, 2)} m)", False
        if dx.max() - dx.min() > t.config.max_bend_m and not t.state.newest_inferred(side):
            return (f"{name} line bent {dx.max() - dx.min():.2f} m away from its track "
                    f"(limit {t.config.max_bend_m} m)"), True
        return "", False

    def bend_rows(self, fit: LineFit, tracked: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Return the ``rows`` a line's bend against its track is read on: where both lie in the view, and
        the bottom row. Beyond, on a tight bend, both are extrapolations of fits to different pixels
        and part by metres though both lay on the line where seen.
        """
        w = self.t.pipeline.size[0]
        x_fit, x_track = np.polyval(fit.coeffs_px, rows), np.polyval(tracked, rows)
        inside = (x_fit >= 0) & (x_fit < w) & (x_track >= 0) & (x_track < w)
        inside[-1] = True
        return inside

    def confirms_track(self, fit: LineFit, tracked: np.ndarray, top_px: int, side: int) -> bool:
        """Return whether a line seen only far ahead lies within the jump limit of its tracked
        line on the rows where its pixels are, inside the look-ahead."""
        t = self.t
        near = t.bottom - fit.gap_px
        rows = np.linspace(max(float(top_px), near - fit.span_px), near, 5)
        dx = (np.polyval(fit.coeffs_px, rows) - np.polyval(tracked, rows)) * t.xm
        return bool(np.abs(dx).max() <= t.jump_limit_m(side))

    def joined(self, fit: LineFit, reference: np.ndarray, top_px: int) -> tuple[float, float, float]:
        """Return a line seen only far ahead joined to ``reference`` nearer the car
        (``fit.joined_fit``: the fit where its pixels are, the reference below them)."""
        t = self.t
        near = t.bottom - fit.gap_px
        seen = np.arange(max(float(top_px), near - fit.span_px), near)
        return joined_fit(seen, np.polyval(fit.coeffs_px, seen), reference,
                          np.arange(near, t.bottom + 1.0), t.pipeline.size[1])

    # ---- the pair -------------------------------------------------------------------------

    def pair_problem(self, kept: dict, track, rows: np.ndarray, top_px: int, mask, distant: bool,
                     why: list[str]) -> str:
        """Return why two kept lines are no lane ("" when they are), noting an exception in ``why``:
        compared row by row with the tracked width (``width_reference``); on their own when the track
        inferred a line (a pitched flat view's lane is a lane); with ``grade_pair_check``, a lane when
        parallel on the grade a double line's stripes show.
        """
        t = self.t
        h = t.pipeline.size[1]
        left, right = kept["left"], kept["right"]
        reference = self.width_reference(track, rows)
        problem = pair_problem(left, right, h, t.xm, t.ym, t.checks, top_px, width_reference_px=reference)
        if track is not None and reference is None and problem and not distant and not self.pair_alone(
                left, right, top_px):
            # checked on its own (a line inferred), both lines seen at the car
            why.append(f"{problem}, but a lane in a pitched flat view (its width changes linearly)")
            return ""
        if track is not None and (graded := graded_pair(t, left, right, rows, top_px, mask, problem)):
            why.append(graded)
            return ""
        return problem

    def pair_alone(self, left: LineFit, right: LineFit, top_px: int) -> str:
        """Return why two lines checked on their own, not against the tracked width, are no lane;
        with ``pitched_start_frames`` on, a lane in a pitched flat view is a lane."""
        t = self.t
        h = t.pipeline.size[1]
        problem = pair_problem(left, right, h, t.xm, t.ym, t.checks, top_px)
        if problem.startswith("lines not parallel") and t.config.pitched_start_frames:
            return pitched_pair_problem(left, right, h, t.xm, t.ym, t.checks, top_px,
                                        t.config.max_pitch_change)
        return problem

    def pair_outvotes_track(self, bent: dict, track, rows: np.ndarray, top_px: int) -> bool:
        """Return whether two lines that both bent away from the track are the lane anyway: they
        bend alike (within ``max_bend_m`` of each other) and are a lane on their own."""
        t = self.t
        dl = np.polyval(bent["left"].coeffs_px, rows) - np.polyval(track[0], rows)
        dr = np.polyval(bent["right"].coeffs_px, rows) - np.polyval(track[1], rows)
        if float(np.abs(dl - dr).max()) * t.xm > t.config.max_bend_m:
            return False
        return not self.pair_alone(bent["left"], bent["right"], top_px)

    def width_reference(self, track, rows: np.ndarray) -> np.ndarray | None:
        """Return the tracked lane's width (px) on ``rows``, or None without a track or when the newest
        accepted frame inferred a line: that width was carried over, not measured, and would refuse a
        pair seen now.
        """
        s = self.t.state
        if track is None or s.newest_inferred(0) or s.newest_inferred(1):
            return None
        return np.polyval(track[1], rows) - np.polyval(track[0], rows)
