"""Lane tracking across video frames: search near the track, check, infer, smooth, hold, reset.

``LaneTracker.update(frame)`` runs one frame through a ``LanePipeline`` and returns a
``FrameResult`` whose fits are the tracked (smoothed) lane, so ``LanePipeline.annotate`` and the
debug composite work on it unchanged. Per frame:

1. **Search.** Around the predicted lane when the previous frame was accepted ("prior"), with
   sliding windows from the track's lines otherwise ("windows"); a prior search that fails its
   checks is retried with windows on the same mask. With a track the look-ahead keeps the
   tracked lines in view (``search.lookahead_top_px``: shorter on a tight bend), growing by at
   most ``lookahead_growth_m`` a frame beyond the rows the track was measured on. Without a track
   a whole view that gives no lane is searched again in shorter views
   (``LanePipeline.short_view_search``). **Re-acquisition**: a line inferred for
   ``reacquire_after_frames`` frames is looked for in a band around its inference that widens
   with the frames it has been inferred (up to ``reacquire_band_m``), since an inference drifts
   while nothing shows the line; the line found there passes every check, with a jump limit as
   wide as the band. **The road seen from the car** (``road_view_run_m``): when a line is
   refused, the look-ahead is also cut where the lane's interior stops looking like the road
   near the car (beyond a crest, a vehicle on the road) and the lane is searched again there.
2. **Checks.** Every found lane passes the checks ``LanePipeline.detect`` uses
   (``params.LaneChecks``): each line alone (``checks.line_problem``: not a bright patch that fills
   its band, not texture), each line against the track (``max_jump_m`` at the car,
   ``max_bend_m`` in shape over the rows where both lie in view), and the pair
   (``checks.pair_problem``: width at the car, parallel, equal curvatures; with a track the width
   is compared row by row with the tracked width, which carries a grade's change of the flat
   view). A pair whose lines both bend from the track alike and pass the pair's checks outvotes
   the track. A pair refused as not parallel is kept when its width changes as a seen double
   line's stripe spacing does (``grade_pair_check``). A line whose pixels stop more than
   ``max_gap_m`` short of the car is an extrapolation there: with a track it is kept where
   seen and joined near the car to the inferred or tracked line (on a bend, within
   ``near_gap_m``), otherwise refused. When the pair fails, the line with the higher confidence
   is kept. A detection that lost a line to the checks is kept in the result's ``rejected``.
3. **One line lost.** The other line is inferred from the kept one: moved along its normal by
   the lane's width (``fit.offset_line``), so it has the kept line's shape. The width at the
   car is the median of the widths seen at the car in the last ``smooth_frames`` frames that saw
   both lines (``seen_width_m``), since a width read back from inferred lines drifts; ahead it
   follows the tracked width, or a seen double line's stripe spacing (``stripe_spread``). Its
   confidence is half the kept line's.
4. **Smoothing.** The reported fit is a weighted average of the fits accepted in the last
   ``smooth_frames`` frames, weight ``recency_decay ** age`` times the line's confidence. A
   weighted window and not a Kalman filter: the tracker does not observe the steering or the
   road that move the lane between frames, so a Kalman filter's motion model would be "constant
   coefficients plus tuned noise", an exponential filter with a gain to tune; the window has two
   plain parameters, a bounded memory (a reset is clean) and a lag of about a frame, and the
   confidence weights let a poor detection move the lane less. Averaging coefficients averages
   the curves row by row, since x(y) is linear in them.
5. **Hold and reset.** With no acceptable line the predicted lane is reported for up to
   ``hold_frames`` frames with a confidence falling to zero; then the tracker resets and reports
   no lane until a pair passes the checks. Frames in which no search saw any line at all (under
   an overpass) are held for up to ``blind_hold_frames`` beside them, since nothing contradicts
   the track. **Restart from one line**: in the ``restart_frames`` frames after a reset, a line
   that passes every line check, reaches the car, lies within ``restart_distance_m`` of the lost
   track's line on its side and agrees with such a line of the previous frame restarts the lane,
   the other line inferred (restarts do not chain). **Pitched start**: without a track, a pair
   refused only as not parallel that is a lane in a pitched flat view
   (``checks.pitched_pair_problem``) and agrees with the previous frame's starts the track
   (``pitched_start_frames``).
6. **History of bases** (``base_history_frames``, off by default): when the windows start from a
   weak histogram peak (``min_base_peak``), they are run again from the median of the recent
   accepted bases, and the search that passes more lines is kept.
7. **Trend.** The lane searched around, checked against and held (``predicted_lane``) is the
   smoothed lane moved along the trend of its centre line over the last ``trend_frames`` accepted
   frames, since the smoothed lane lags the road by about a frame; the reported lane of an
   accepted frame stays the smoothed one, which does not carry the trend's noise.
8. **The asphalt edge.** When a lane has one line and no paint at all on the other side, the
   unpainted asphalt edge there is taken as the line if the pair passes every check
   (``LanePipeline.edge_search``); ``sources`` says "edge". **A painted line that fades out** is
   placed its measured shoulder inside the asphalt edge: while both lines are seen, each painted
   line's distance out to the asphalt edge is measured near the car (on one frame in
   ``shoulder_every``) and remembered (``shoulder_frames``, agreeing within
   ``shoulder_spread_m``); when the paint then fades, the line is placed that far inside the
   edge where the edge is seen, joined beyond to the inference or nearer the car to returning
   paint (``return_gap_m``), and kept when the pair passes its checks; ``sources`` says
   "shoulder".

Confidence per line (0-1): ``result.line_confidence`` of the accepted detection (span of rows
covered times pixel support), half the other line's for an inferred line, the last value times
the share of the hold that is left for a held line, 0 when no lane is reported.
"""
from __future__ import annotations

import hashlib
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from .checks import gap_problem, line_problem, pair_problem, pitched_pair_problem
from .fit import least_squares_poly, normal_width_m, offset_line, offset_rows_px, parallel_fits, row_medians
from .params import LaneChecks
from .params.roads import TrackerConfig
from .pipeline import LanePipeline
from .records import NEAR_SHARE, LaneSearch, LineFit, Window, line_source
from .result import FrameResult, Rejected
from .roads.edge import VergeGrid, grid_rows_px, road_edge, road_view_interior, road_view_top_px, verge_grid
from .roads.stripes import stripe_spacing_px
from .search import lane_pixels, lookahead_top_px, search_around


@dataclass(frozen=True)
class _LostTrack:
    """What a reset remembers of the track it forgot, for a restart from one line (step 5): the
    tracked lines' x (px) on the bottom row, whether each was seen (not inferred) in the last
    accepted frame, and the width seen at the car (``seen_width_m``)."""

    bases: tuple[float, float]
    seen: tuple[bool, bool]
    width_m: float


@dataclass(frozen=True)
class _Accepted:
    """One frame's accepted lane: pixel coefficients and confidence of each line, and the
    first row of the look-ahead it was measured in, and the frame's number."""

    left: np.ndarray
    right: np.ndarray
    left_conf: float
    right_conf: float
    top_px: int = 0
    frame: int = 0
    inferred: tuple[bool, bool] = (False, False)  # (left, right) inferred, not seen


class LaneTracker:
    """Track the lane through consecutive frames of one video with one ``LanePipeline``.

    Parameters
    ----------
    pipeline : the pipeline that searches each frame (its size, perspective and search config).
    config : tracking parameters; defaults to ``pipeline.config.tracking``.
    checks : the plausibility checks; defaults to ``pipeline.config.checks``, those of
        ``pipeline.detect``.

    Call ``update`` once per frame, in order; ``reset`` before a new video. After each
    ``update``, ``retries`` names the fallback searches that frame needed, in the order they
    ran (none when the cheap search passed): "road view", "windows from the track", "re-acquire",
    "remembered bases", "fallback masks", "shorter views", "other peaks", "asphalt edge",
    "shoulder". Every fallback search reads the whole
    view under ``ThresholdConfig.fallback_rule`` (the cheap search, its rule). ``python -m lanelib bench`` counts them and times them.
    """

    def __init__(self, pipeline: "LanePipeline", config: TrackerConfig | None = None,
                 checks: LaneChecks | None = None):
        self.pipeline = pipeline
        self.config = config if config is not None else pipeline.config.tracking
        self.checks = checks if checks is not None else pipeline.config.checks
        h = pipeline.size[1]
        self._bottom = float(h - 1)
        self._rows = np.linspace(0.0, h - 1.0, self.checks.check_rows)
        self._xm = pipeline.perspective.xm_per_px
        self._ym = pipeline.perspective.ym_per_px
        self.reset()

    # ---- state ----------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget the track and the remembered bases (a new video): the next frame is searched
        with sliding windows from the histogram."""
        self._forget_track()
        self._lost_track: _LostTrack | None = None  # a new video: no lost track to restart from
        # (side, pixel coefficients) of the lines that could restart the lane in the previous
        # frame and in this one, each waiting for the next frame to confirm it (step 5)
        self._restart_candidates: tuple[list, list] = ([], [])
        # (frames in a row, left and right pixel coefficients) of the pitched pairs of the previous
        # frame and of this one (``TrackerConfig.pitched_start_frames``)
        self._pitched: tuple[list, list] = ([], [])
        self._frame = 0  # the number of the frame being tracked (1 for the first)
        self.retries: tuple[str, ...] = ()
        self._base_history: deque[tuple[float, float]] = deque(maxlen=self.config.base_history_frames)

    def _forget_track(self) -> None:
        """Forget the track (the lane was lost too long); the remembered bases stay, and so does
        ``_lost_track`` (what a restart from one line needs, step 5: set by the reset)."""
        self._history: deque[_Accepted] = deque(maxlen=self.config.smooth_frames)
        self._trend: deque[_Accepted] = deque(maxlen=max(self.config.trend_frames, 1))
        self._lost = 0
        self._blind = 0  # frames since the last accepted one in which nothing was seen (step 5)
        # the lane's normal width at the car (m) in the last frames that saw both lines (step 3)
        self._seen_widths: deque[float] = deque(maxlen=self.config.smooth_frames)
        self._conf = (0.0, 0.0)
        self._edge = [False, False]  # (left, right): the track's line is the asphalt edge (step 8)
        # (left, right): the newest shoulders (m) measured from the paint out to the asphalt edge (step 8)
        self._shoulders: tuple[deque, deque] = (deque(maxlen=self.config.shoulder_frames),
                                                deque(maxlen=self.config.shoulder_frames))
        # (left, right): accepted frames in a row that inferred the line, or saw it only short of
        # the car (the re-acquisition band, step 1)
        self._inferred_run = [0, 0]
        # (left, right): accepted frames in a row without the line's paint seen at the car
        # (inferred, or placed inside the asphalt edge: step 8)
        self._faded_run = [0, 0]
        self._restart_width = float("nan")  # the width (m) a track restarted from one line infers at

    def _remember_lost(self) -> _LostTrack | None:
        """Return what a restart from one line needs of the track being reset (step 5): its
        lines' bases, which were seen in the newest accepted frame, and the width seen at the
        car; None for a track that never saw both lines at the car (one restarted from one line
        that saw no second line: restarts do not chain)."""
        lane = self.lane
        if lane is None or not self._seen_widths:
            return None
        newest = self._history[-1].inferred
        return _LostTrack(self._bases(lane), (not newest[0], not newest[1]), self.seen_width_m)

    @property
    def remembered_bases(self) -> tuple[float, float] | None:
        """The median x (px, bottom row) of each line over the remembered frames, or None."""
        if not self._base_history:
            return None
        left, right = np.median(np.array(self._base_history), axis=0)
        return float(left), float(right)

    @property
    def lane(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the tracked (smoothed) pixel coefficients (left, right), or None when reset."""
        if not self._history:
            return None
        w = self._smoothing_weights()
        left = np.array([a.left for a in self._history])
        right = np.array([a.right for a in self._history])
        return (w[:, 0] @ left / w[:, 0].sum(), w[:, 1] @ right / w[:, 1].sum())

    def _smoothing_weights(self) -> np.ndarray:
        """Return the (left, right) weight of each remembered frame in ``lane``, oldest first."""
        weights = []
        for age, acc in enumerate(reversed(self._history)):
            decay = self.config.recency_decay ** age
            weights.append((decay * max(acc.left_conf, 0.05), decay * max(acc.right_conf, 0.05)))
        return np.array(weights[::-1])

    def predicted_lane(self, frame: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the tracked lane moved along the trend of its centre line to ``frame`` (step 7).

        ``lane`` averages past frames, so it shows the lane as it was a frame or so ago (the
        weighted mean of its frames' numbers); on a bend that tightens, opens or turns the other
        way it lags the road. From the third accepted frame on, each pixel coefficient of the
        lane's centre line ((left + right) / 2) over the last ``trend_frames`` accepted frames is
        fitted by a straight line in the frame number, and both lines are moved by that rate
        times the frames from the average's time to ``frame`` (the width is kept). While the lane
        is not seen the trend is followed no further than the frame after the last accepted
        one: nothing is known about the road beyond it, and a held lane that followed the trend
        through a whole hold would drift from the lines that come back.

        Parameters
        ----------
        frame : number of the frame to predict the lane in (``frame_number``); default: the
            frame being tracked.
        """
        lane = self.lane
        if lane is None or self.config.trend_frames < 3 or len(self._trend) < 3:
            return lane
        frames = np.array([acc.frame for acc in self._trend], float)
        centres = np.array([(acc.left + acc.right) / 2.0 for acc in self._trend])
        rate = np.polyfit(frames - frames[-1], centres, 1)[0]  # per frame, for a, b and c
        # frame numbers counted from the last accepted frame: the same floats wherever the
        # tracker started (a Dask segment warms up from a later frame than one process)
        last = frames[-1]
        w = self._smoothing_weights()
        times = w.T @ (np.array([acc.frame for acc in self._history], float) - last) / w.sum(axis=0)
        target = min(float(self._frame if frame is None else frame) - last, 1.0)
        return lane[0] + rate * (target - times[0]), lane[1] + rate * (target - times[1])

    @property
    def seen_width_m(self) -> float:
        """Return the lane's width at the car (m, along the normal on the view's bottom row) that a
        missing line is inferred at (step 3): the median over the last ``smooth_frames`` frames
        that saw both lines at the car (neither extrapolated there on a bend, ``_bent_gap``),
        NaN before any."""
        return float(np.median(self._seen_widths)) if self._seen_widths else float("nan")

    @property
    def frame_number(self) -> int:
        """Return the number of the last frame tracked (1 for the first after ``reset``)."""
        return self._frame

    @property
    def lost_frames(self) -> int:
        """Return the number of frames since the last accepted detection."""
        return self._lost

    def state_key(self) -> bytes:
        """Return a fingerprint of the state the next frames' results depend on.

        Two trackers of one pipeline with the same key give the same results, to the last bit,
        on the same next frames, whichever frame each started from: the remembered fits (their
        coefficients' bytes), confidences, look-ahead rows and seen/inferred flags of the smoothing
        and the trend, each frame's number counted back from the last frame tracked, the
        remembered bases, the hold's counters, the held confidences, the widths seen at the car
        (``seen_width_m``), which sides' tracked lines are asphalt edges and the shoulders measured
        beyond the painted ones (step 8) and for how many
        frames each line has been inferred (the re-acquisition band, step 1), and what a restart
        from one line needs (step 5): the reset track's bases and seen width, the width a
        restarted track infers at, and the lines the last frame could have restarted from. A
        Dask segment's warm-up compares it with the previous segment's (``cluster.settle_joints``).
        """
        def accepted(acc: _Accepted) -> tuple:
            return (acc.left.tobytes(), acc.right.tobytes(), acc.left_conf, acc.right_conf,
                    acc.top_px, self._frame - acc.frame, acc.inferred)

        state = ([accepted(a) for a in self._history], [accepted(a) for a in self._trend],
                 list(self._base_history), self._lost, self._blind, self._conf, list(self._seen_widths),
                 self._edge, [list(d) for d in self._shoulders], self._faded_run, self._inferred_run,
                 self._lost_track,
                 self._restart_width,
                 [(side, c.tobytes()) for side, c in self._restart_candidates[1]],
                 [(run, l.tobytes(), r.tobytes()) for run, l, r in self._pitched[1]])
        return hashlib.sha256(repr(state).encode()).digest()

    # ---- one frame ------------------------------------------------------------------------

    def update(self, raw: np.ndarray, keep_images: bool = False, index: int | None = None) -> FrameResult:
        """Return the tracked lane in the next RAW frame of the video (see the module docstring).

        ``index``: the frame's number in the video (0 for the first), which picks the frames the
        shoulder is measured on (``TrackerConfig.shoulder_every``); default: the frames tracked
        since ``reset`` before this one. The lane itself does not depend on it otherwise.
        """
        pipe = self.pipeline
        index = self._frame if index is None else index
        self._frame += 1
        self._restart_candidates = (self._restart_candidates[1], [])
        self._pitched = (self._pitched[1], [])
        track = self.predicted_lane()
        prior = None
        top = 0 if track is None else self.lookahead_top_px(track)
        if track is not None and self._lost == 0:
            prior = (LineFit(tuple(track[0])), LineFit(tuple(track[1])))
        search, det_images = pipe.search_frame(raw, prior=prior, keep_images=keep_images or prior is None,
                                               top_px=top)

        def mask() -> np.ndarray:
            """The whole view under the fallback masks' rule, thresholded once."""
            if "fallback binary" not in det_images:
                if pipe.has_fallback_masks or "binary" not in det_images:
                    bird = det_images.get("birdseye")
                    det_images["fallback binary"] = pipe.binary(
                        bird if bird is not None else pipe.birdseye(raw), fallback=True)
                else:
                    det_images["fallback binary"] = det_images["binary"]
            return det_images["fallback binary"]

        ran: list[str] = []  # the fallback searches this frame needed (``retries``)
        seen = self._restart_candidates[1]  # the lines this frame could restart the lane from
        best = (search, *self._check(search.left, search.right, track, self._band_px(search), top, mask,
                                     seen))
        first = search
        looked = [search]  # every search this frame ran: did any see a line at all (step 5)?

        def better(retry: LaneSearch | None, name: str, note: str = "") -> None:
            """Keep ``retry`` when more of its lines pass the checks than of the best so far."""
            nonlocal best
            ran.append(name)
            if retry is None:
                return
            looked.append(retry)
            checked = (retry, *self._check(retry.left, retry.right, track, self._band_px(retry),
                                           retry.top_px, mask, seen))
            if sum(c is not None for c in checked[1:3]) > sum(c is not None for c in best[1:3]):
                best = checked
                if note:
                    best[3].append(note)

        if track is not None and best[4] and self.config.road_view_run_m > 0:
            # a line refused: is the far view still the road seen from the car (a crest, a car)?
            cap = self.road_view_top_px(raw, track)
            if cap > top:
                before = best
                better(pipe.search(mask(), prior, bases=self._bases(track), top_px=cap), "road view")
                if best is not before and (best[1] is None or best[2] is None):
                    best = before  # only a pair in the shorter view: one line is no better evidence
                if best is not before:
                    top = cap
        if track is not None and (best[1] is None or best[2] is None):
            # the search missed: look again with windows started from the tracked lines
            better(pipe.search(mask(), bases=self._bases(track), top_px=top), "windows from the track")
        elif track is None and self._no_pair(best) and (bases := self._weak_bases(search)) is not None:
            # no track and a weak histogram peak: start that side from the remembered base
            better(pipe.search(mask(), bases=bases), "remembered bases",
                   "windows started from the remembered bases (weak histogram peak)")
        if track is not None and (side := self._reacquire_side(best)) is not None:
            # a line inferred for several frames: look for it further out from its inference
            better(self._reacquire(best[0], mask(), track, side, top), "re-acquire")
        if track is None and self._no_pair(best) and pipe.has_fallback_masks:
            # no track and the cheap masks gave no lane: the whole view on the fallback masks
            better(pipe.search(mask()), "fallback masks")
        if track is None and self._no_pair(best) and pipe.config.search.short_views:
            # no track and the whole view gave no lane: shorter views (a tight bend)
            better(pipe.short_view_search(mask()), "shorter views")
        if track is None and self._no_pair(best) and pipe.config.search.candidates > 1:
            # no track and the strongest peaks gave no lane: the robust path (other peaks)
            better(pipe.robust_search(mask(), best[0]), "other peaks")
        if pipe.config.edge.enabled and (edgeless := self._edge_candidate(best, track)) is not None:
            # one line, and no paint on the other side: its asphalt edge (step 8)
            bird = det_images.get("birdseye")
            if bird is None:
                bird = det_images["birdseye"] = pipe.birdseye(raw)
            better(pipe.edge_search(bird, edgeless), "asphalt edge")
        if (pipe.config.edge.enabled and track is not None and self.config.shoulder_frames
                and (faded := self._faded_side(raw, det_images.get("birdseye"), best)) is not None):
            # a painted line faded out: placed the remembered shoulder inside its asphalt edge
            side, why_faded = faded
            bird = det_images.get("birdseye")
            if bird is None:
                bird = det_images["birdseye"] = pipe.birdseye(raw)
            ran.append("shoulder")
            for placed, joined in self._shoulder_search(bird, side, best, track):
                looked.append(placed)
                checked = (placed, *self._check(placed.left, placed.right, track, self._band_px(placed),
                                                placed.top_px, mask, seen))
                if checked[1] is not None and checked[2] is not None:
                    best = checked
                    best[3].append(f"{('left', 'right')[side]} line {why_faded}: placed the shoulder "
                                   f"({self.shoulder_m(side):.2f} m) inside the asphalt edge"
                                   + (", joined ahead to its returning paint" if joined else ""))
                    break
        self.retries = tuple(ran)
        search, left, right, why, failed = best
        if pipe.config.edge.enabled and self.config.shoulder_frames and index % self.config.shoulder_every == 0:
            self._measure_shoulders(raw, det_images.get("birdseye"), search, left, right)
        images = det_images if keep_images else {}
        if keep_images and search is not first and "fallback binary" in images:
            images["binary"] = images["fallback binary"]  # the views show the mask the lane came from
        images.pop("fallback binary", None)
        blind = not any(s.left.found or s.right.found for s in looked)
        spread = None  # one line to infer: the view's scale ahead from the other's double stripes
        if self.config.stripe_spread and (left is None) != (right is None):  # a track, or a restart
            seen = left if left is not None else right
            spread = self._stripe_spread(mask(), seen.coeffs_px, search.top_px)
        result = self._advance(search, left, right, why, track, images, blind, spread)
        if not failed:
            return result
        rejected = Rejected(search.left, search.right, pipe.measure(search.left, search.right),
                            "; ".join(why))
        return replace(result, rejected=rejected)

    @staticmethod
    def _no_pair(best: tuple) -> bool:
        """Return whether a search without a track kept no pair: no line, or one line alone
        restarting the lane (step 5), which a fallback search finding a pair outdoes."""
        return best[1] is None or best[2] is None

    def _edge_candidate(self, best: tuple, track) -> LaneSearch | None:
        """Return the search whose missing line the asphalt edge may stand for (step 8), or None.

        Without a track: a best search that found one line and nothing on the other side (a line
        alone cannot start a track, or only restarts one, step 5). With a track: a frame that
        kept one line, where the other side's tracked line was the asphalt edge (no paint was
        tracked there); what the search found on that side failed the checks, so it is dropped
        for the edge.
        """
        search, left, right = best[:3]
        if track is None:
            return search if search.left.found != search.right.found else None
        if (left is None) == (right is None):
            return None
        side = "left" if left is None else "right"
        if not self._edge[0 if side == "left" else 1]:
            return None
        return replace(search, **{side: LineFit(None, reason="refused by the checks")})

    def shoulder_m(self, side: int) -> float:
        """Return the shoulder (m) of line ``side`` (0 left, 1 right): how far beyond its paint
        the asphalt edge runs (step 8), the median of the remembered measurements once at least
        half of ``shoulder_frames`` are in and their robust spread is within
        ``shoulder_spread_m``; NaN otherwise."""
        found = np.array(self._shoulders[side], float)
        if not self.config.shoulder_frames or 2 * len(found) < self.config.shoulder_frames:
            return float("nan")
        median = float(np.median(found))
        if 1.4826 * float(np.median(np.abs(found - median))) > self.config.shoulder_spread_m:
            return float("nan")
        return median

    def _measure_shoulders(self, raw: np.ndarray, bird: np.ndarray | None, search: LaneSearch,
                           left: LineFit | None, right: LineFit | None) -> None:
        """Remember the shoulder of each painted line of a frame that kept both lines at the car
        (``_shoulder_beside``, when clearly found)."""
        if not (self._reach_car(left) and self._reach_car(right)):
            return
        grid = None
        for i, (fit, other) in enumerate(((left, right), (right, left))):
            if search.edge[i] or search.shoulder[i]:
                continue  # not paint
            grid = grid or self._near_grid(raw, bird)
            shoulder = self._shoulder_beside(grid, fit, other, i, (search.left_pixels, search.right_pixels)[i])
            if not np.isnan(shoulder):
                self._shoulders[i].append(round(shoulder, 4))

    def _near_grid(self, raw: np.ndarray, bird: np.ndarray | None) -> VergeGrid:
        """Return the verge features (``roads.edge.verge_grid``) of the bird's-eye view's rows within
        ``shoulder_near_m`` of its bottom row, what ``_shoulder_beside`` reads: one row of each
        ``EdgeConfig.scale`` (``roads.edge.grid_rows_px``; measured on every frame with both lines, so a
        quarter of the rows), from ``bird`` or those rows of RAW alone remapped."""
        w, h = self.pipeline.size
        k = self.pipeline.config.edge.scale
        top = max(0, int(round(self._bottom - self.config.shoulder_near_m / self._ym))) // k * k
        sample = grid_rows_px(top, h, k)  # one row of each k: read on every frame, so cheap
        rows = bird[sample] if bird is not None else self.pipeline.birdseye_rows(raw, sample)
        return verge_grid(rows, k, top, h, sampled=True)

    def _shoulder_beside(self, grid: VergeGrid, fit: LineFit, other: LineFit, side: int,
                         pixels: tuple[np.ndarray, np.ndarray] | None = None) -> float:
        """Return the shoulder (m) beyond line ``fit`` on ``side`` (0 left, 1 right), NaN where not
        clearly found: the median distance (along the line's normal) from the line out to the
        asphalt edge beyond it in ``grid`` (``_near_grid``) (``roads.edge.road_edge`` from 0 to
        ``EdgeConfig.max_shoulder_m`` beyond the line, the road surface read between ``fit`` and
        ``other``), on the rows within ``shoulder_near_m`` of the view's bottom row; clearly found:
        edge points on at least half of those rows (of the shrunk grid), their distances' robust
        spread (1.4826 x the median distance from their median) within ``shoulder_spread_m``. With
        the line's ``pixels`` ((ys, xs) of the search) the distance on a row is from the median of
        its pixels on that row of the shrunk grid, where it has some: the paint where it is, not a
        fit of the whole look-ahead (on a tight bend a fit can lie centimetres outside its paint at
        the car)."""
        cfg = replace(self.pipeline.config.edge, trace_margin_m=0.0)
        k = cfg.scale
        top = max(0, int(round(self._bottom - self.config.shoulder_near_m / self._ym)))
        _, points = road_edge(None, other, ("left", "right")[side], self._xm, self._ym, self.checks,
                              cfg, top, guide_px=fit.coeffs_px, range_m=(0.0, cfg.max_shoulder_m),
                              grid=grid)
        if len(points) < 0.5 * (self._bottom + 1 - top) / k:
            return float("nan")
        ys = points[:, 1]
        x_line = np.polyval(fit.coeffs_px, ys)
        if pixels is not None and len(pixels[0]):
            bins = (np.asarray(pixels[0]) // k).astype(int)
            near = bins >= top // k
            rows, paint = row_medians(bins[near], np.asarray(pixels[1], float)[near])
            if len(rows):  # the paint's x on each grid row it holds
                grid_rows = (ys // k).astype(int)
                at = np.minimum(np.searchsorted(rows, grid_rows), len(rows) - 1)
                hit = rows[at] == grid_rows
                x_line[hit] = paint[at[hit]]
        slope = np.polyval(np.polyder(np.asarray(fit.coeffs_px, float)), ys) * self._xm / self._ym
        dist = np.abs(points[:, 0] - x_line) * self._xm / np.sqrt(1.0 + slope ** 2)
        median = float(np.median(dist))
        if 1.4826 * float(np.median(np.abs(dist - median))) > self.config.shoulder_spread_m:
            return float("nan")
        return median

    def _faded_side(self, raw: np.ndarray, bird: np.ndarray | None, best: tuple) -> tuple[int, str] | None:
        """Return the side (0 left, 1 right) whose painted line has faded out and is to be placed
        the remembered shoulder inside the asphalt edge (step 8), with what was seen of it, or None.

        The side's shoulder is known (``shoulder_m``), its tracked line is no asphalt edge, the
        other line is kept, the side's paint was not seen at the car in the last accepted frame
        (``_faded_run``), and: this frame kept no line there, the paint missing for
        ``reacquire_after_frames`` frames or more (at least one; a line missing for a frame or
        two, a dash's gap or a shadow, is still near its track and is inferred as before); or the
        line kept there is seen only far ahead (``max_gap_m``: the paint returning ahead, which
        would be joined nearer the car to the line inferred from the other line); or it is the
        asphalt edge itself, not paint: the edge lies less than half the shoulder beyond it
        (``_shoulder_beside``; the grass beside the edge can pass for a line in the search's
        mask)."""
        search, left, right = best[:3]
        for i, (fit, other) in enumerate(((left, right), (right, left))):
            if other is None or self._edge[i] or not self._faded_run[i] or search.edge[i] or search.shoulder[i]:
                continue
            shoulder = self.shoulder_m(i)
            if np.isnan(shoulder):
                continue
            if fit is None:
                if self._faded_run[i] >= max(1, self.config.reacquire_after_frames):
                    return i, "not found where its paint faded out"
                continue
            if not self._reach_car((search.left, search.right)[i]):
                return i, "seen only far ahead where its paint faded out"
            gap_m = (search.left, search.right)[i].gap_px * self._ym
            if gap_m > self.config.return_gap_m:
                return i, f"seen only from {gap_m:.1f} m ahead where its paint faded out"
            if self._shoulder_beside(self._near_grid(raw, bird), fit, other, i) < 0.5 * shoulder:
                return i, "seen at the asphalt edge, where its paint runs the shoulder inside it"
        return None

    def _shoulder_search(self, bird: np.ndarray, side: int, best: tuple, track
                         ) -> list[tuple[LaneSearch, bool]]:
        """Return the best search with its line ``side`` placed the remembered shoulder inside the
        asphalt edge on that side (``LanePipeline.edge_search``), each with whether it is joined
        to the line's returning paint: first so joined (``_joined_paint``) where the search has
        pixels on that side, then joined beyond the edge to the line inferred from the kept one
        (the first that passes the checks is kept); none where no edge is found.

        The edge is looked for from the line inferred from the kept one (step 3), within the
        shoulder plus or minus the line's jump limit (``_jump_limit_m``: how far the inference
        may lie from the line at the car) beyond it, and followed from the car over the view
        where it is seen (``EdgeConfig.trace_margin_m``)."""
        search, left, right = best[:3]
        kept = right if side == 0 else left
        name = ("left", "right")[side]
        guide = self._inferred(np.array(kept.coeffs_px, float), track, side, search.top_px)
        shoulder, tol = self.shoulder_m(side), self._jump_limit_m(side)
        faded = replace(search, **{name: LineFit(None, reason="paint faded out"),
                                   ("right", "left")[side]: kept})
        placed = self.pipeline.edge_search(bird, faded, guide, (max(0.0, shoulder - tol), shoulder + tol),
                                           shoulder)
        if placed is None:
            return []
        line = getattr(placed, name)
        joined = self._joined_paint((search.left_pixels, search.right_pixels)[side], line, search.top_px)
        if joined is None:
            return [(placed, False)]
        return [(replace(placed, **{name: joined}), True), (placed, False)]

    def _joined_paint(self, pixels, placed: LineFit, top_px: int) -> LineFit | None:
        """Return a faded line's returning paint ahead joined nearer the car to ``placed`` (the
        line placed the shoulder inside the asphalt edge, step 8), or None with fewer than half
        ``min_line_pixels`` paint pixels (``pixels``: (ys, xs) of the search on that side) in
        the look-ahead (from ``top_px``).

        One second-order fit to the paint's median x on each row it holds and to the placed line
        on each row between the paint's nearest (all but ``records.NEAR_SHARE`` of its pixels lie
        above it) and the view's bottom row: the paint where it is seen, the edge near the car,
        where the paint is missing. Extrapolated to the car, or joined to the line inferred from
        the other line, paint seen only a few metres ahead in a sag beyond a crest lies inside
        the line at the car (the flat view widens the lane ahead there, and the inference does
        not follow). Its pixel count and rows are the edge's and the
        paint's together (its confidence, ``result.line_confidence``)."""
        ys, xs = np.asarray(pixels[0]), np.asarray(pixels[1], float)
        keep = ys >= top_px
        ys, xs = ys[keep], xs[keep]
        if len(ys) < self.pipeline.config.search.min_line_pixels // 2:
            return None
        near = float(np.quantile(ys, 1.0 - NEAR_SHARE))
        keep = ys <= near
        rows, med = row_medians(ys[keep], xs[keep])
        unseen = np.arange(np.floor(near) + 1.0, self._bottom + 1.0)
        coeffs = least_squares_poly(np.concatenate([rows.astype(float), unseen]),
                                    np.concatenate([med, np.polyval(placed.coeffs_px, unseen)]), 2,
                                    float(self.pipeline.size[1]))
        top = min(float(rows[0]), self._bottom - placed.gap_px - placed.span_px)
        return replace(placed, coeffs_px=coeffs, n_pixels=placed.n_pixels + int(keep.sum()),
                       span_px=float(self._bottom - placed.gap_px - top))

    def _reacquire_half_px(self, side: int) -> float:
        """Return the half width (px) of the band a line inferred for ``reacquire_after_frames``
        frames or more is looked for in (step 1), 0 when it is not re-acquired."""
        cfg = self.config
        run = self._inferred_run[side]
        if not cfg.reacquire_after_frames or run < cfg.reacquire_after_frames:
            return 0.0
        margin = self.pipeline.config.search.prior_margin_px
        return min(margin * (2 + run - cfg.reacquire_after_frames), cfg.reacquire_band_m / self._xm)

    def _jump_limit_m(self, side: int) -> float:
        """Return how far (m) a line ``side`` may lie from its tracked line at the car (or, seen
        only far ahead, where it was seen): ``max_jump_m``, or the re-acquisition band's half width
        when the tracked line was inferred long enough to be looked for in it (step 1)."""
        return max(self.config.max_jump_m, self._reacquire_half_px(side) * self._xm)

    def _reacquire_side(self, best: tuple) -> int | None:
        """Return the side (0 left, 1 right) whose line this frame did not keep and the track has
        inferred long enough to be looked for more widely (step 1), or None."""
        for i in (0, 1):
            if best[1 + i] is None and best[2 - i] is not None and self._reacquire_half_px(i) > 0:
                return i
        return None

    def _reacquire(self, search: LaneSearch, binary: np.ndarray, track, side: int,
                   top_px: int) -> LaneSearch | None:
        """Return ``search`` with line ``side`` looked for again in ``binary``, the whole view
        (step 1), or None when no line could lie within ``_reacquire_half_px`` of its inference.

        The inference is moved across to the median distance of the lane pixels in the bin
        nearest it (bins ``prior_margin_px`` wide, every half margin, out to the band's half
        width) that holds ``min_line_pixels``, and the line is searched within ``prior_margin_px``
        of it (``search.search_around``), its curvature shared with the other line when it is
        short (``fit.parallel_fits``). The band goes into the search's windows, so the line's
        band checks (``checks.line_problem``) compare it with the band it was searched in."""
        cfg = self.pipeline.config.search
        half = self._reacquire_half_px(side)
        margin = cfg.prior_margin_px
        ys, xs = lane_pixels(binary)
        keep = ys >= top_px
        dx = xs[keep] - np.polyval(track[side], ys[keep])
        dx = dx[np.abs(dx) <= half]
        if len(dx) < cfg.min_line_pixels:
            return None
        steps = np.arange(margin / 2, half - margin / 2 + 1.0, margin / 2)
        for centre in [0.0] + [c for step in steps for c in (-step, step)]:  # nearest first
            near = dx[np.abs(dx - centre) <= margin / 2]
            if len(near) >= cfg.min_line_pixels:
                break
        else:
            return None
        moved = np.array(track[side], float)
        moved[2] += float(np.median(near))
        name = ("left", "right")[side]
        priors = [LineFit(None), LineFit(None)]
        priors[side] = LineFit(tuple(moved))
        found = search_around(binary, priors[0], priors[1], cfg, top_px)
        h = self.pipeline.size[1]
        slabs = np.linspace(float(h), float(top_px), cfg.n_windows + 1).round().astype(int)
        band = tuple(Window(name, int(x - margin), int(x + margin), int(lo), int(hi))
                     for hi, lo in zip(slabs[:-1], slabs[1:])
                     for x in [float(np.polyval(moved, (lo + hi) / 2))])
        merged = replace(search, **{name: getattr(found, name), f"{name}_pixels": getattr(found, f"{name}_pixels")},
                         windows=tuple(w for w in search.windows if w.side != name) + band)
        left, right = parallel_fits(merged.left, merged.right, merged.left_pixels,
                                    merged.right_pixels, h, cfg)
        return replace(merged, left=left, right=right)

    def lookahead_top_px(self, track: tuple[np.ndarray, np.ndarray]) -> int:
        """Return the first row (px) of this frame's look-ahead for the tracked lane ``track``.

        Where the tracked lines stay in the view (``search.lookahead_top_px``), but no more than
        ``lookahead_growth_m`` beyond the rows the tracked fits were measured on.
        """
        measured = max(acc.top_px for acc in self._history)
        grow = int(round(self.config.lookahead_growth_m / self._ym))
        top = lookahead_top_px(track, self.pipeline.size, self.pipeline.config.search)
        return max(top, measured - grow, 0)

    def road_view_top_px(self, raw: np.ndarray, track: tuple[np.ndarray, np.ndarray]) -> int:
        """Return the first row (px) of the road seen continuously from the car in a RAW frame,
        between the tracked lines ``track`` (``roads.edge.road_view_top_px``), 0 for the whole view.

        Only every ``road_view_step_px``-th row of the bird's-eye view, and only the columns the
        lane's interior covers on them, are remapped (``LanePipeline.birdseye_rows``); the
        saturation that is unlike the road is ``EdgeConfig.min_saturation_step``, the asphalt
        edge's road-vs-verge step (one measure of what is not asphalt).
        """
        pipe = self.pipeline
        w, h = pipe.size
        rows = np.arange(h - 1, -1, -self.config.road_view_step_px)
        lo, hi = road_view_interior(rows, track, w)
        c0, c1 = int(lo.min()), int(max(hi.max(), lo.min() + 1))  # the columns an interior covers
        if c0 >= w:
            return 0
        return road_view_top_px(pipe.birdseye_rows(raw, rows, (c0, c1)), rows, track, self._ym,
                                pipe.config.edge.min_saturation_step, self.config.road_view_run_m,
                                w, c0)

    def check(self, left: LineFit, right: LineFit, track: tuple[np.ndarray, np.ndarray] | None,
              band_px: float | tuple[float, float] | None = None
              ) -> tuple[LineFit | None, LineFit | None, list[str]]:
        """Return the lines that pass the sanity checks (None where rejected) and why others failed.

        Parameters
        ----------
        left, right : this frame's fits (bird's-eye pixels).
        track : the tracked pixel coefficients (left, right), or None without a track.
        band_px : width (px) of the band the lines' pixels were searched in, one for both or
            (left, right) (``checks.search_bands_px``); None: the band checks are skipped.
        """
        return self._check(left, right, track, band_px)[:3]

    def _check(self, left: LineFit, right: LineFit, track, band_px, top_px: int = 0, mask=None,
               candidates: list | None = None
               ) -> tuple[LineFit | None, LineFit | None, list[str], bool]:
        """Return ``check``'s answer and whether a check rejected a found line.

        The track checks and the pair's compare the lines over the look-ahead's rows, from
        ``top_px`` down (``search.lookahead_top_px``). ``mask``: the frame's whole view under the
        fallback masks' rule, made when first called (``update``), for the grade pair check;
        None skips that check. ``candidates``: where ``update`` collects the lines this frame
        could restart the lane from (``_restart``); None (``check``) keeps the tracker as it is.
        """
        cfg = self.config
        rows = self._rows if not top_px else np.linspace(float(top_px), self._bottom, len(self._rows))
        bands = band_px if isinstance(band_px, tuple) else (band_px or 0.0, band_px or 0.0)
        failed = False
        why: list[str] = []
        kept: dict[str, LineFit | None] = {"left": None, "right": None}
        bent: dict[str, LineFit] = {}  # lines refused only for bending away from the track
        distant: dict[str, LineFit] = {}  # lines seen only far ahead that lie along their track
        limits = self._gap_limits_m(left, right, bands, track)
        for i, (side, fit) in enumerate((("left", left), ("right", right))):
            if not fit.found:
                why.append(f"{side} line not found ({fit.reason})")
                continue
            problem = line_problem(fit, bands[i], self.checks, self._xm, side)
            if problem:
                why.append(problem)
                failed = True
                continue
            far = gap_problem(fit, self._ym, limits[i], side) if track is not None else ""
            if far:
                if not self._confirms_track(fit, track[i], top_px, i):
                    why.append(far)
                    failed = True
                    continue
                kept[side] = fit
                distant[side] = fit
                continue
            if track is not None:
                dx = (np.polyval(fit.coeffs_px, rows) - np.polyval(track[i], rows)) * self._xm
                dx = dx[self._bend_rows(fit, track[i], rows)]
                jump_m = self._jump_limit_m(i)
                if abs(dx[-1]) > jump_m:
                    why.append(f"{side} line jumped {abs(dx[-1]):.2f} m at the car "
                               f"(limit {round(jump_m, 2)} m)")
                    failed = True
                    continue
                if dx.max() - dx.min() > cfg.max_bend_m and not self._track_inferred(i):
                    why.append(f"{side} line bent {dx.max() - dx.min():.2f} m away from its track "
                               f"(limit {cfg.max_bend_m} m)")
                    failed = True
                    bent[side] = fit
                    continue
            kept[side] = fit
        for i, side in enumerate(("left", "right")):
            if side in distant:  # joined to the other line's inference, or else to its track
                other = "right" if i == 0 else "left"
                near = kept[other] is not None and other not in distant
                ref = self._inferred(np.array(kept[other].coeffs_px), track, i, top_px) if near else track[i]
                kept[side] = replace(distant[side], coeffs_px=self._joined(distant[side], ref, top_px))
                why.append(f"{gap_problem(distant[side], self._ym, limits[i], side)}; it lies "
                           f"along its track there, and nearer the car "
                           + ("the line inferred from the other line is taken" if near else "its track is taken"))
        if len(bent) == 2 and self._pair_outvotes_track(bent, track, rows, top_px):
            kept, failed = dict(bent), False
            why.append("both lines bent away from the track together and pass the pair checks: "
                       "the road changed, the track lags")
        if kept["left"] is not None and kept["right"] is not None:
            reference = self._width_reference(track, rows)
            problem = pair_problem(kept["left"], kept["right"], self.pipeline.size[1],
                                   self._xm, self._ym, self.checks, top_px,
                                   width_reference_px=reference)
            if track is not None and reference is None and problem and not distant and not self._pair_alone(
                    kept["left"], kept["right"], top_px):
                # checked on its own (a line inferred), both lines seen at the car: a pitched flat
                # view's lane is a lane (a line joined to an inference is not seen at the car)
                why.append(f"{problem}, but a lane in a pitched flat view (its width changes linearly)")
                problem = ""
            graded_check = self.config.grade_pair_check and track is not None
            if graded_check and problem.startswith("lines not parallel"):
                graded = self._graded_reference(kept["left"], kept["right"], rows, top_px, mask)
                if graded is not None and not pair_problem(
                        kept["left"], kept["right"], self.pipeline.size[1], self._xm, self._ym,
                        self.checks, top_px, width_reference_px=graded):
                    why.append(f"{problem} against the track, but parallel on the road ahead's grade "
                               "(the double stripes' spread)")
                    problem = ""
            if problem:
                why.append(problem)
                failed = True
                if track is None:
                    if candidates is not None and self._pitched_start(kept, problem, top_px, why):
                        return kept["left"], kept["right"], why, False
                    return self._restart(kept, why, failed, candidates)
                lc, rc = (self._conf_of(kept[s]) for s in ("left", "right"))
                drop = "right" if lc >= rc else "left"
                why.append(f"{drop} line dropped (lower confidence)")
                kept[drop] = None
        if track is None and (kept["left"] is None or kept["right"] is None):
            return self._restart(kept, why, failed, candidates)
        return kept["left"], kept["right"], why, failed

    def _bend_rows(self, fit: LineFit, tracked: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Return which of the check's ``rows`` a line's bend against its tracked line is read on:
        those where both lie in the view, and always the bottom row (the car).

        The look-ahead keeps at least ``SearchConfig.min_view_fraction`` of the view (9.4 m), but
        on a tight bend the lines leave the view sideways sooner (on a 35 m bend after a few
        metres). Above that
        the fit and the track are extrapolations of 2nd-order fits made from different pixels; a
        line that bows with the bend (``SearchConfig.short_bend_resolution``) parts from a
        straighter track there by metres, and was refused as bent although both lay on the
        line where it was seen, until the hold ran out and the lane was lost.
        """
        w = self.pipeline.size[0]
        x_fit, x_track = np.polyval(fit.coeffs_px, rows), np.polyval(tracked, rows)
        inside = (x_fit >= 0) & (x_fit < w) & (x_track >= 0) & (x_track < w)
        inside[-1] = True
        return inside

    def _restart(self, kept: dict, why: list[str], failed: bool, candidates: list | None = None
                 ) -> tuple[LineFit | None, LineFit | None, list[str], bool]:
        """Return ``_check``'s answer without a track when not both lines of ``kept`` (each
        passed the line checks) make a lane: one line alone restarts the lane only soon after a
        reset, where the lost track's line on its side was (step 5); otherwise none.

        Within ``restart_frames`` frames after a reset of a track that saw both lines at the car
        (``_LostTrack``), a line that reaches the car (``max_gap_m``) and lies within
        ``restart_distance_m`` of the lost track's line on its side at the car, that line seen
        (not inferred) in the track's newest accepted frame, restarts the lane, the other line
        inferred at the width seen at the car before the loss (``_inferred``). When both lines so
        lie (the pair failed its checks), neither restarts it: one of them is not a line of the
        lane, and the tracker does not guess which.
        """
        lines = {s: f for s, f in kept.items() if f is not None}
        if not lines:
            return None, None, why, failed
        lost, cfg = self._lost_track, self.config
        if lost is None or self._lost >= cfg.restart_frames:
            why.append("one line alone cannot start a track")
            return None, None, why, failed
        near = {}
        for side, fit in lines.items():
            i = 0 if side == "left" else 1
            dist = abs(float(np.polyval(fit.coeffs_px, self._bottom)) - lost.bases[i]) * self._xm
            if lost.seen[i] and self._reach_car(fit) and dist <= cfg.restart_distance_m:
                near[side] = dist
        if len(near) != 1:
            why.append("one line alone cannot start a track" if len(lines) == 1 and not near else
                       "no single line lies where the lost track's line was" if not near else
                       "both lines lie where the lost track's lines were but are no lane together")
            return None, None, why, failed
        (side, dist), = near.items()
        fit = lines[side]
        if candidates is not None:  # the next frame confirms a restart against it
            candidates.append((side, np.array(fit.coeffs_px, float)))
        agree = self._confirmed_restart(side, fit)
        if agree is None:
            why.append(f"{side} line lies where the lost track's {side} line was ({dist:.2f} m at the "
                       "car); it restarts the lane if the next frame's agrees with it")
            return None, None, why, failed
        why.append(f"{side} line alone restarts the lane: {dist:.2f} m at the car from the lost "
                   f"track's {side} line (limit {cfg.restart_distance_m} m), {self._lost + 1} "
                   f"frames after the reset (limit {cfg.restart_frames}), the previous frame's within "
                   f"{agree}")
        return (fit if side == "left" else None, fit if side == "right" else None, why, failed)

    def _pitched_start(self, kept: dict, problem: str, top_px: int, why: list[str]) -> bool:
        """Return whether a pair refused without a track as not parallel starts the track as a
        lane in a pitched flat view (``TrackerConfig.pitched_start_frames``), noting why in
        ``why``; remembers it for the next frame when it is such a lane."""
        cfg = self.config
        if not cfg.pitched_start_frames or not problem.startswith("lines not parallel"):
            return False
        left, right = kept["left"], kept["right"]
        if pitched_pair_problem(left, right, self.pipeline.size[1], self._xm, self._ym, self.checks,
                                top_px, cfg.max_pitch_change):
            return False
        pair = (np.array(left.coeffs_px, float), np.array(right.coeffs_px, float))
        run = 1 + max((n for n, *previous in self._pitched[0] if self._agree(pair, previous)), default=0)
        self._pitched[1].append((run, *pair))
        if run < cfg.pitched_start_frames:
            return False
        why[-1] = (f"{problem}, but a lane in a pitched flat view (its width changes linearly, within "
                   f"{cfg.max_pitch_change:.0%} of its width at the car) {run} frames in a row: the "
                   "track starts")
        return True

    def _agree(self, pair, previous) -> bool:
        """Return whether each line of ``pair`` lies within ``max_jump_m`` at the car and
        ``max_bend_m`` in shape of the same side's line of ``previous`` (pixel coefficients)."""
        for now, before in zip(pair, previous):
            dx = (np.polyval(now, self._rows) - np.polyval(before, self._rows)) * self._xm
            if abs(dx[-1]) > self.config.max_jump_m or dx.max() - dx.min() > self.config.max_bend_m:
                return False
        return True

    def _confirmed_restart(self, side: str, fit: LineFit) -> str | None:
        """Return how a line that could restart the lane agrees with one the previous frame
        could have restarted it from on the same side, or None when none agrees: within
        ``max_jump_m`` at the car and ``max_bend_m`` in shape over the view (the checks of a line
        against its track, step 2). A single line's fit has no pair to check its shape: on an
        S-bend a lone line's fit can turn the wrong way far ahead, and the next frame's then
        bends metres away from it."""
        for previous_side, coeffs in self._restart_candidates[0]:
            if previous_side != side:
                continue
            dx = (np.polyval(fit.coeffs_px, self._rows) - np.polyval(coeffs, self._rows)) * self._xm
            if abs(dx[-1]) <= self.config.max_jump_m and dx.max() - dx.min() <= self.config.max_bend_m:
                return f"{abs(dx[-1]):.2f} m at the car and {dx.max() - dx.min():.2f} m in shape"
        return None

    def _inferred(self, seen: np.ndarray, track, side: int, top_px: int,
                  spread: np.ndarray | None = None) -> np.ndarray:
        """Return the pixel coefficients of the missing line ``side`` (0 left, 1 right): the
        ``seen`` line moved along its normal by the tracked lane's normal width on each row from
        ``top_px`` down (``fit.normal_width_m``, ``fit.offset_line``): where a grade widens or
        narrows the flat view's lane ahead, the track's width carries that change. At the car the
        width is the one measured in the last frames that saw both lines there (``seen_width_m``),
        not the tracked lane's: the track holds the lines inferred in earlier frames, and a width
        read back from them drifts frame after frame (step 3); the track's width on the other
        rows is scaled by the same factor. With a ``spread`` (``_stripe_spread``) the width is
        the seen width at the car times it. Without a ``track`` (a restart from one line, step 5)
        the width is the one seen at the car before the reset, on every row unless a ``spread``
        widens it; a restarted track goes on inferring at it until both lines are seen."""
        rows = offset_rows_px(self.pipeline.size[1], top_px)
        if track is None:  # a restart from one line (step 5): the width seen before the loss
            at_car = tracked = self._lost_track.width_m
        else:
            tracked = normal_width_m(track[0], track[1], self._bottom, self._xm, self._ym)
            at_car = (self.seen_width_m if self._seen_widths else
                      tracked if np.isnan(self._restart_width) else self._restart_width)
        if spread is not None:
            width = at_car * np.polyval(spread, self._bottom - rows)
        elif track is not None and tracked > 0.5 * at_car:
            # the track's change of width ahead, at the seen width at the car
            width = normal_width_m(track[0], track[1], rows, self._xm, self._ym) * (at_car / tracked)
        else:  # a restart, or a track whose width has collapsed: no shape ahead to keep
            width = np.full(len(rows), at_car)
        return np.array(offset_line(seen, -width if side == 0 else width, self._xm, self._ym,
                                    self.pipeline.size[1], top_px))

    def _pair_outvotes_track(self, bent: dict, track, rows: np.ndarray, top_px: int) -> bool:
        """Return whether two lines that both bent away from the track are the lane anyway.

        When both lines of a frame bend away from the track the same way, the road's curve
        changed faster than the smoothed track follows (a bend tightening over a crest); they
        are kept when they are a lane on their own (the pair's checks, ``_pair_alone``)
        and bend alike (their bends from the track differ by at most ``max_bend_m``). The jump
        check still holds: a line is never taken that moved at the car.
        """
        dl = np.polyval(bent["left"].coeffs_px, rows) - np.polyval(track[0], rows)
        dr = np.polyval(bent["right"].coeffs_px, rows) - np.polyval(track[1], rows)
        if float(np.abs(dl - dr).max()) * self._xm > self.config.max_bend_m:
            return False
        return not self._pair_alone(bent["left"], bent["right"], top_px)

    def _pair_alone(self, left: LineFit, right: LineFit, top_px: int) -> str:
        """Return why two lines checked on their own, not against the tracked width, are no lane
        (``checks.pair_problem``): with ``pitched_start_frames`` on, lines refused only as not
        parallel are a lane when they are one in a pitched flat view (``checks.pitched_pair_problem``):
        the track that checks their positions was measured in the same view."""
        h = self.pipeline.size[1]
        problem = pair_problem(left, right, h, self._xm, self._ym, self.checks, top_px)
        if problem.startswith("lines not parallel") and self.config.pitched_start_frames:
            return pitched_pair_problem(left, right, h, self._xm, self._ym, self.checks, top_px,
                                        self.config.max_pitch_change)
        return problem

    def _confirms_track(self, fit: LineFit, tracked: np.ndarray, top_px: int, side: int) -> bool:
        """Return whether a line seen only far ahead (``checks.gap_problem``) lies along its
        tracked line where its pixels are: within ``max_jump_m`` (``_jump_limit_m``) of it on the
        rows from its nearest pixels (``LineFit.gap_px``) up by its span, inside the look-ahead."""
        near = self._bottom - fit.gap_px
        rows = np.linspace(max(float(top_px), near - fit.span_px), near, 5)
        dx = (np.polyval(fit.coeffs_px, rows) - np.polyval(tracked, rows)) * self._xm
        return bool(np.abs(dx).max() <= self._jump_limit_m(side))

    def _joined(self, fit: LineFit, reference: np.ndarray, top_px: int) -> tuple[float, float, float]:
        """Return the pixel coefficients of a line seen only far ahead, joined to ``reference``
        (its tracked line, or the line inferred from the other line): a second-order fit to the
        line where its pixels are and to the reference on the rows between them and the view's
        bottom row, where nothing was seen (one sample per row)."""
        near = self._bottom - fit.gap_px
        seen = np.arange(max(float(top_px), near - fit.span_px), near)
        unseen = np.arange(near, self._bottom + 1.0)
        ys = np.concatenate([seen, unseen])
        xs = np.concatenate([np.polyval(fit.coeffs_px, seen), np.polyval(reference, unseen)])
        return least_squares_poly(ys, xs, 2, float(self.pipeline.size[1]))

    def _stripe_spread(self, binary: np.ndarray, coeffs_px, top_px: int) -> np.ndarray | None:
        """Return the flat view's scale across the road relative to the bottom row's, as a
        straight line in (bottom row - row), from the stripes of a double line along the fit
        ``coeffs_px`` (``roads.stripes.stripe_spacing_px``), or None.

        None unless the stripes show on at least 4 bands of rows covering half the look-ahead
        (from ``top_px``), their spacing lies within an eighth of ``double_line_px`` (RMS) of
        the straight line, and the scale at the look-ahead's top is 0.7-2.5: a spread read from
        fewer or scattered bands is noise, and the inferred line would follow it.
        The look-ahead is read only down from where the line lies in the view
        (``_in_view_top_px``): on a tight bend the line leaves the view sideways, and above
        that no stripes can show (as the bend check reads only rows in view, ``_bend_rows``).
        Rows where the line is out of view are not counted as stripes missing: on a tight bend
        in shade no spread would be read, and the double line, inferred from the other line,
        would drift off its paint.
        """
        spacing = self.pipeline.config.search.double_line_px
        if not spacing:
            return None
        ys, gaps = stripe_spacing_px(binary, coeffs_px, spacing, top_px)
        depth = self._bottom - max(float(top_px), self._in_view_top_px(coeffs_px, top_px))
        if len(ys) < 4 or ys.max() - ys.min() < 0.5 * depth:
            return None
        slope, at_car = np.polyfit(self._bottom - ys, gaps, 1)
        residual = gaps - np.polyval((slope, at_car), self._bottom - ys)
        if at_car <= 0 or float(np.sqrt(np.mean(residual ** 2))) > spacing / 8:
            return None
        if not 0.7 <= 1.0 + slope / at_car * depth <= 2.5:
            return None
        return np.array([slope / at_car, 1.0])

    def _in_view_top_px(self, coeffs_px, top_px: int) -> float:
        """Return the first row (px) from which the line ``coeffs_px`` lies inside the view's
        width all the way down to the bottom row (``top_px`` when it never leaves it)."""
        rows = np.arange(float(top_px), self._bottom + 1.0)
        x = np.polyval(coeffs_px, rows)
        outside = np.flatnonzero((x < 0) | (x >= self.pipeline.size[0]))
        return float(top_px) if not len(outside) else float(rows[outside[-1]] + 1.0)

    def _reach_car(self, fit: LineFit | None) -> bool:
        """Return whether ``fit`` is a line seen in this frame whose pixels reach within
        ``max_gap_m`` of the view's bottom row (not one seen only far ahead and joined nearer the
        car to another line)."""
        return fit is not None and fit.gap_px * self._ym <= self.config.max_gap_m

    def _gap_limits_m(self, left: LineFit, right: LineFit, bands: tuple[float, float], track
                      ) -> tuple[float, float]:
        """Return the largest gap (m) each line may stop short of the car by and count as seen
        there (step 2): ``_gap_limit_m`` (``near_gap_m``) for a line whose gap exceeds
        ``near_gap_m`` where its tracked line bends by more than ``near_gap_bend_m`` over the
        gap (|a| * gap**2: the curvature's share of the extrapolation) and the other line of
        this frame reaches the car within ``near_gap_m`` and passes ``checks.line_problem``: the
        line is then joined near the car to the line inferred from that one, a measurement.
        Else ``max_gap_m``: on a straight road the extrapolation does not rest on the curvature
        (a dashed line's gaps), and where the other line stops short too the join would be to
        the track alone, which drifts from the road while the car moves (an overpass's shade)."""
        cfg = self.config
        if not cfg.near_gap_m or track is None:
            return cfg.max_gap_m, cfg.max_gap_m
        fits = (left, right)
        # seen short of the car by more than near_gap_m, where the track bends over the gap
        bent = [fit.found and self._bent_gap(fit, track, i) for i, fit in enumerate(fits)]
        if not any(bent):  # the usual frame: both lines reach the car, or the road is straight
            return cfg.max_gap_m, cfg.max_gap_m
        near = [fit.found and fit.gap_px * self._ym <= cfg.near_gap_m
                and not line_problem(fit, bands[i], self.checks, self._xm, ("left", "right")[i])
                for i, fit in enumerate(fits)]
        return tuple(self._gap_limit_m(i) if bent[i] and near[1 - i] else cfg.max_gap_m
                     for i in range(2))

    def _bent_gap(self, fit: LineFit, track, side: int) -> bool:
        """Return whether line ``side``'s ``fit`` reaches the car only by an extrapolation that
        rests on the curvature: its pixels stop more than ``near_gap_m`` short of the view's
        bottom row where its tracked line bends by more than ``near_gap_bend_m`` over the gap
        (``_gap_limits_m``'s rule; False with ``near_gap_m`` 0 or without a track). Such a frame
        gives no width at the car (step 3, ``seen_width_m``)."""
        cfg = self.config
        return bool(cfg.near_gap_m and track is not None and fit.gap_px * self._ym > cfg.near_gap_m
                    and abs(track[side][0]) * fit.gap_px ** 2 * self._xm > cfg.near_gap_bend_m)

    def _gap_limit_m(self, side: int) -> float:
        """Return how far (m) short of the view's bottom row line ``side``'s pixels may stop for it
        to count as seen at the car (step 2): ``near_gap_m`` when its paint reached the car in the
        newest accepted frames (not inferred, not faded: the track there is a measurement), else
        ``max_gap_m``."""
        cfg = self.config
        if (cfg.near_gap_m and self._history and not self._history[-1].inferred[side]
                and not self._inferred_run[side] and not self._faded_run[side]):
            return min(cfg.near_gap_m, cfg.max_gap_m)
        return cfg.max_gap_m

    def _paint_at_car(self, fit: LineFit | None, faded_run: int) -> bool:
        """Return whether ``fit`` is paint seen at the car (``_reach_car``); on a side whose paint
        has been missing at the car for ``faded_run`` accepted frames, only when its pixels reach
        within ``return_gap_m`` of the view's bottom row (step 8: returning paint seen farther
        ahead is joined nearer the car to the line placed inside the asphalt edge)."""
        if not self._reach_car(fit):
            return False
        return not faded_run or fit.gap_px * self._ym <= self.config.return_gap_m

    def _graded_reference(self, left: LineFit, right: LineFit, rows: np.ndarray,
                          top_px: int, mask) -> np.ndarray | None:
        """Return the lane's width (px) on ``rows`` as the road ahead's grade makes it in the flat
        view (``TrackerConfig.grade_pair_check``): the pair's width at the car times the view's
        scale across the road read from a double line's stripes along either line
        (``_stripe_spread``, a straight line in the distance from the bottom row: a grade that
        changes at the car), or None when no stripes tell it (or no ``mask``, the frame's
        whole-view mask made on demand by ``update``). Costs a threshold of the whole view (shared
        with the fallback searches) and a pass over its pixels near the line, on frames whose pair
        failed against the track only."""
        if mask is None:
            return None
        for fit in (left, right):
            spread = self._stripe_spread(mask(), fit.coeffs_px, top_px)
            if spread is not None:
                at_car = float(np.polyval(right.coeffs_px, self._bottom)
                               - np.polyval(left.coeffs_px, self._bottom))
                return at_car * np.polyval(spread, self._bottom - rows)
        return None

    def _track_inferred(self, side: int) -> bool:
        """Return whether the newest accepted frame inferred line ``side`` (0 left, 1 right): a
        seen line is not checked for bending away from a line that was never seen."""
        return bool(self._history) and self._history[-1].inferred[side]

    def _width_reference(self, track, rows: np.ndarray) -> np.ndarray | None:
        """Return the tracked lane's width (px) on ``rows``, the reference the pair's width is
        compared with (``checks.pair_problem``), or None without a track or when the newest
        accepted frame inferred a line.

        An inferred line's width ahead is not a measurement: it is the tracked width carried
        over from the last frame that saw both lines (step 3), so on a bend that tightens it is
        as old as that frame. Against it a pair seen now on the lane would be refused as not
        parallel, and the track would go on inferring the line from a stale width. Such a pair is checked as a pair on its own, as without a
        track, just as a seen line is not checked for bending away from an inferred one.
        """
        if track is None or self._track_inferred(0) or self._track_inferred(1):
            return None
        return np.polyval(track[1], rows) - np.polyval(track[0], rows)

    def _band_px(self, search: LaneSearch) -> tuple[float, float]:
        """Return the width (px) of the band each line was searched in (``checks.search_bands_px``)."""
        return self.pipeline.search_bands_px(search)

    def _conf_of(self, fit: LineFit) -> float:
        """Return the 0-1 confidence of a detected line (``result.line_confidence``)."""
        return self.pipeline.line_confidence(fit)

    def _bases(self, track) -> tuple[float, float]:
        """Return the tracked lines' x (px) on the bottom row, where windows start."""
        return (float(np.polyval(track[0], self._bottom)), float(np.polyval(track[1], self._bottom)))

    def _weak_bases(self, search: LaneSearch) -> tuple[float, float] | None:
        """Return the bases to search again from when a histogram base is weak (step 6), or None."""
        remembered = self.remembered_bases
        if remembered is None or search.method != "windows":
            return None
        out, weak = [], False
        for base, conf, memory in zip(search.bases_px, search.base_confidence, remembered):
            if base is None or conf is None or conf < self.config.min_base_peak:
                out.append(memory)
                weak = True
            else:
                out.append(base)
        return (out[0], out[1]) if weak else None

    def _advance(self, search: LaneSearch, left: LineFit | None, right: LineFit | None,
                 why: list[str], track, images: dict, blind: bool = False,
                 spread: np.ndarray | None = None) -> FrameResult:
        """Update the state with this frame's accepted lines and return the frame's result
        (``blind``: no search saw a line at all in this frame; ``spread``: the view's scale
        across the road ahead for an inferred line, ``_stripe_spread``)."""
        notes = list(why)
        if left is not None or right is not None:
            coeffs = {}
            confs = {}
            for side, fit in (("left", left), ("right", right)):
                if fit is not None:
                    coeffs[side] = np.array(fit.coeffs_px, float)
                    confs[side] = self._conf_of(fit)
            for side, other, i in (("left", "right", 0), ("right", "left", 1)):
                if side not in coeffs:  # infer from the other line and the tracked lane width
                    coeffs[side] = self._inferred(coeffs[other], track, i, search.top_px, spread)
                    confs[side] = round(0.5 * confs[other], 3)
                    widened = " at the car, widened ahead as its double stripes" if spread is not None else ""
                    width = "the tracked width" if track is not None else "the width seen before the loss"
                    notes.append(f"{side} line inferred from the {other} line and {width}{widened}")
            if track is None and (left is None or right is None):  # restarted from one line (step 5)
                self._restart_width = self._lost_track.width_m
            accepted = _Accepted(coeffs["left"], coeffs["right"], confs["left"], confs["right"],
                                 search.top_px, self._frame, (left is None, right is None))
            self._history.append(accepted)
            self._trend.append(accepted)
            self._inferred_run = [0 if self._reach_car(fit) else run + 1
                                  for run, fit in zip(self._inferred_run, (left, right))]
            # a line placed the shoulder inside the asphalt edge (step 8) is no paint seen: its
            # paint is still missing, and the width at the car is not measured on it
            seen = [None if search.shoulder[i] else fit for i, fit in enumerate((left, right))]
            at_car = [self._paint_at_car(fit, run) for fit, run in zip(seen, self._faded_run)]
            self._faded_run = [0 if near else run + 1 for run, near in zip(self._faded_run, at_car)]
            if (self._reach_car(seen[0]) and self._reach_car(seen[1])  # both seen at the car: measured there
                    and not any(self._bent_gap(fit, track, i) for i, fit in enumerate(seen))):
                self._seen_widths.append(normal_width_m(coeffs["left"], coeffs["right"], self._bottom,
                                                        self._xm, self._ym))
            if self._base_history.maxlen:
                self._base_history.append(self._bases((coeffs["left"], coeffs["right"])))
            self._lost = self._blind = 0
            self._conf = (confs["left"], confs["right"])
            method = search.method
            sources = {"left": left, "right": right}
            for i, fit in enumerate((left, right)):
                if fit is not None:  # an inferred line keeps the side's kind
                    self._edge[i] = bool(search.edge[i])
            kinds = tuple("inferred" if fit is None else line_source(search, i)
                          for i, fit in enumerate((left, right)))
        elif track is not None and (note := self._hold(blind)):
            lc, rc = (round(c * self._hold_share(), 3) for c in self._conf)
            notes.append(note)
            return self._result(track, (lc, rc), "hold", {}, search, notes, images, ("held", "held"))
        else:
            if track is not None:
                blinds = f" beside {self._blind} frames with nothing seen" if self._blind else ""
                notes.append(f"lane lost for more than {self.config.hold_frames} frames{blinds}; "
                             "tracker reset")
                self._lost_track = self._remember_lost()
                self._forget_track()
            else:
                self._lost += 1
            return self._not_found(search, notes, images)
        smoothed = self.lane
        return self._result(smoothed, self._conf, method, sources, search, notes, images, kinds)

    def _hold(self, blind: bool) -> str:
        """Count one more frame without a lane and return the note of its hold, or "" when the
        hold is over (step 5).

        A frame in which nothing was seen (``blind``) uses the ``blind_hold_frames`` first and
        does not count toward ``hold_frames``; any other, or one beyond those, counts toward it.
        """
        cfg = self.config
        if blind and self._blind < cfg.blind_hold_frames:
            self._lost += 1
            self._blind += 1
            return (f"holding the last good lane (nothing seen: {self._blind} of "
                    f"{cfg.blind_hold_frames} blind frames)")
        counted = self._lost - self._blind
        if counted >= cfg.hold_frames:
            return ""
        self._lost += 1
        return f"holding the last good lane ({counted + 1} of {cfg.hold_frames} frames)"

    def _hold_share(self) -> float:
        """Return the share of the held lane's confidence that is left: that of each hold's
        frames that are left, multiplied."""
        cfg = self.config
        counted = self._lost - self._blind
        return (1.0 - counted / (cfg.hold_frames + 1)) * (1.0 - self._blind / (cfg.blind_hold_frames + 1))

    def _result(self, coeffs, confs, method: str, sources: dict, search: LaneSearch,
                notes: list[str], images: dict, kinds: tuple[str, str]) -> FrameResult:
        fits = []
        for side, c in zip(("left", "right"), coeffs):
            src = sources.get(side)
            fits.append(LineFit(tuple(float(v) for v in c), src.n_pixels if src else 0,
                                src.span_px if src else 0.0, "" if src else _note_for(side, notes)))
        left, right = fits
        return FrameResult(left, right, self.pipeline.measure(left, right), method,
                           float(confs[0]), float(confs[1]), "; ".join(notes), search, images,
                           sources=kinds)

    def _not_found(self, search: LaneSearch, notes: list[str], images: dict) -> FrameResult:
        reason = "; ".join(notes) or "no lane"
        left, right = LineFit(None, reason=reason), LineFit(None, reason=reason)
        return FrameResult(left, right, self.pipeline.measure(left, right), search.method,
                           0.0, 0.0, reason, search, images)


def _note_for(side: str, notes: list[str]) -> str:
    """Return the notes about one line (why it was inferred or held)."""
    mine = [n for n in notes if n.startswith(side) or n.startswith("holding")]
    return "; ".join(mine) or "not detected in this frame"
