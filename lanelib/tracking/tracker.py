"""``LaneTracker``: one loop per frame over a ``LanePipeline``, its proposers and its checks."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..fit import normal_width_m, offset_line, offset_rows_px
from ..params import LaneChecks
from ..params.roads import TrackerConfig
from ..pipeline import LanePipeline
from ..records import LaneSearch, LineFit
from ..result import FrameResult, Rejected
from ..proposers import Frame, Proposer, choose
from ..roads.checks import inferred_spread
from ..roads.proposers import TRACKER_FIRST, TRACKER_LATER, measure_shoulders, reacquire_half_px
from ..roads.trend import predicted_lane
from ..search import lookahead_top_px
from ..thresholds import Made
from .judge import TrackChecks
from .proposers import WindowsFromTrack
from .state import LostTrack, TrackState
from .update import accept, hold_or_lose

# the tracker's own proposer between the opt-in ones (``roads.proposers``), each of which asks
# only when its switch is on
PROPOSERS: tuple[Proposer, ...] = (*TRACKER_FIRST, WindowsFromTrack(), *TRACKER_LATER)


class LaneTracker:
    """Track the lane through consecutive frames of one video with one ``LanePipeline``.

    Call ``update`` once per frame, in order; ``reset`` before a new video. After each ``update``,
    ``retries`` names the proposers that frame needed, in order (none when the first search
    passed); ``state`` is everything carried to the next frame.

    Parameters
    ----------
    pipeline : the pipeline that searches each frame (its size, perspective and search config).
    config : tracking parameters; defaults to ``pipeline.config.tracking``.
    checks : the plausibility checks; defaults to ``pipeline.config.checks`` (``detect``'s).
    proposers : where to look again when a frame's first search gives no lane, in order
        (``PROPOSERS``; the protocol in ``lanelib.proposers``).

    Examples
    --------
    >>> from lanelib import data, evaluate, io
    >>> clip = data.bundled("videos") / "project.mp4"
    >>> camera = evaluate.calibration_from_truth(clip)
    >>> tracker = LaneTracker(LanePipeline(calibration=camera, size=camera.image_size))
    >>> with io.VideoReader(clip, 0, 3) as frames:
    ...     [tracker.update(frame).method for frame in frames]
    ['windows', 'prior', 'prior']
    """

    def __init__(self, pipeline: LanePipeline, config: TrackerConfig | None = None,
                 checks: LaneChecks | None = None, proposers: tuple[Proposer, ...] = PROPOSERS):
        self.pipeline = pipeline
        self.config = config if config is not None else pipeline.config.tracking
        self.checks = checks if checks is not None else pipeline.config.checks
        self.proposers = tuple(proposers)
        self.checks_of_track = TrackChecks(self)
        h = pipeline.size[1]
        self.bottom = float(h - 1)  # the view's bottom row: the car
        self.rows = np.linspace(0.0, h - 1.0, self.checks.check_rows)  # the rows checks compare on
        self.xm = pipeline.perspective.xm_per_px
        self.ym = pipeline.perspective.ym_per_px
        self.reset()

    # ---- state ----------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget everything (a new video): the next frame is searched with sliding windows."""
        self.state = TrackState.new(self.config)
        self.retries: tuple[str, ...] = ()

    def forget_track(self) -> None:
        """Forget the track after a hold ran out, keeping what a restart from one line needs (the lost
        lines' bases and the width at the car; none if the track never saw both: no chained restarts).
        """
        lane, s = self.lane, self.state
        if lane is None or not s.seen_widths:
            s.lost_track = None
        else:
            newest = s.history[-1].inferred
            s.lost_track = LostTrack(self.bases(lane), (not newest[0], not newest[1]), s.seen_width_m)
        s.forgot_track(self.config)

    @property
    def lane(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the smoothed pixel coefficients (left, right), or None when reset: the last
        ``smooth_frames`` accepted fits weighted by ``recency_decay ** age`` times confidence (x(y) is
        linear in them, so this averages the curves row by row).
        """
        return self.state.lane(self.config.recency_decay)

    def predicted_lane(self, frame: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the tracked lane moved along its centre line's trend to ``frame`` (default: this one;
        ``roads.trend.predicted_lane``; the lane itself while ``trend_frames`` is off).
        """
        return predicted_lane(self.state, self.config, frame)

    @property
    def seen_width_m(self) -> float:
        """Return the lane's width at the car (m) that a missing line is inferred at: the median
        over the last ``smooth_frames`` frames that saw both lines at the car, NaN before any."""
        return self.state.seen_width_m

    @property
    def frame_number(self) -> int:
        """Return the number of the last frame tracked (1 for the first after ``reset``)."""
        return self.state.frame

    @property
    def lost_frames(self) -> int:
        """Return the number of frames since the last accepted detection."""
        return self.state.lost

    def state_key(self) -> bytes:
        """Return a fingerprint of the state the next frames' results depend on
        (``TrackState.key``); a Dask segment's warm-up compares it with the previous segment's."""
        return self.state.key()

    # ---- one frame ------------------------------------------------------------------------

    def update(self, raw: np.ndarray, keep_images: bool = False, index: int | None = None) -> FrameResult:
        """Return the tracked lane in the next RAW frame of the video.

        Predict the lane, search around it (windows without a track), check the lines against the
        track (``judge.TrackChecks``), ask the proposers while no lane passes, then infer a missing
        line, smooth, or hold (``update.accept``, ``update.hold_or_lose``). ``index``: the frame's
        number in the video, which picks the frames the shoulder is measured on (default: the frames
        tracked since ``reset``).
        """
        pipe, s = self.pipeline, self.state
        index = s.frame if index is None else index
        s.next_frame()
        track = self.predicted_lane()
        prior = None
        top = 0 if track is None else self.lookahead_top_px(track)
        if track is not None and s.lost == 0:
            prior = (LineFit(tuple(track[0])), LineFit(tuple(track[1])))
        made = Made()  # the whole view's masks, which the fallback rule's mask reuses
        search, images = pipe.search_frame(raw, prior=prior, keep_images=keep_images or prior is None,
                                           top_px=top, made=made)
        f = Frame(pipe, raw, None, images, track, top, prior, self, first=search, made=made)
        candidates = s.restart_candidates[1]  # the lines this frame could restart the lane from
        f.judge = lambda c: self.checks_of_track.judge(c, track, c.top_px, f.mask, candidates)
        choose(f, self.proposers)
        self.retries = tuple(f.ran)
        return self._report(f, keep_images, index)

    def _report(self, f: Frame, keep_images: bool, index: int) -> FrameResult:
        """Update the state with the frame's best candidate and return its result."""
        best = f.best
        search = best.search
        measure_shoulders(self, f, index)  # the shoulders beside paint, on the frames they are measured on
        images = f.images if keep_images else {}
        if keep_images and search is not f.first and "fallback binary" in images:
            images["binary"] = images["fallback binary"]  # the views show the mask the lane came from
        images.pop("fallback binary", None)
        blind = not any(s.left.found or s.right.found for s in f.looked)
        spread = inferred_spread(self, best, f.mask)  # one line to infer: its double stripes' grade
        if best.left is not None or best.right is not None:
            result = accept(self, best, f.track, images, spread)
        else:
            result = hold_or_lose(self, best, f.track, images, blind)
        if not best.failed:
            return result
        rejected = Rejected(search.left, search.right, self.pipeline.measure(search.left, search.right),
                            "; ".join(best.why))
        return replace(result, rejected=rejected)

    def check(self, left: LineFit, right: LineFit, track: tuple[np.ndarray, np.ndarray] | None,
              band_px: float | tuple[float, float] | None = None
              ) -> tuple[LineFit | None, LineFit | None, list[str]]:
        """Return the lines that pass the track's checks (None where refused) and why others failed,
        leaving the tracker as it is.

        Parameters
        ----------
        left, right : this frame's fits (bird's-eye pixels).
        track : the tracked pixel coefficients (left, right), or None without a track.
        band_px : width (px) of the lines' search bands, one or (left, right)
            (``checks.search_bands_px``); None: the band checks are skipped.
        """
        bands = band_px if isinstance(band_px, tuple) else (band_px or 0.0, band_px or 0.0)
        empty = (np.empty(0, int), np.empty(0, int))
        judged = self.checks_of_track.judge(LaneSearch(left, right, "given", empty, empty), track, bands=bands)
        return judged.left, judged.right, judged.why

    # ---- what the parts share -------------------------------------------------------------

    def lookahead_top_px(self, track: tuple[np.ndarray, np.ndarray]) -> int:
        """Return the first row (px) of this frame's look-ahead for ``track``: where the tracked lines
        stay in view (``search.lookahead_top_px``), at most ``lookahead_growth_m`` beyond the rows the
        tracked fits were measured on.
        """
        measured = max(acc.top_px for acc in self.state.history)
        grow = int(round(self.config.lookahead_growth_m / self.ym))
        top = lookahead_top_px(track, self.pipeline.size, self.pipeline.config.search)
        return max(top, measured - grow, 0)

    def bases(self, track) -> tuple[float, float]:
        """Return the tracked lines' x (px) on the bottom row, where windows start."""
        return (float(np.polyval(track[0], self.bottom)), float(np.polyval(track[1], self.bottom)))

    def reach_car(self, fit: LineFit | None) -> bool:
        """Return whether ``fit`` is a line seen in this frame whose pixels reach within
        ``max_gap_m`` of the bottom row (not one seen only far ahead and joined nearer the car)."""
        return fit is not None and fit.gap_px * self.ym <= self.config.max_gap_m

    def jump_limit_m(self, side: int) -> float:
        """Return how far (m) line ``side`` may lie from its track at the car: ``max_jump_m``, or the
        re-acquisition band's half width while re-acquired (``roads.proposers.reacquire_half_px``).
        """
        return max(self.config.max_jump_m, reacquire_half_px(self, side) * self.xm)

    def agree(self, now, before) -> str:
        """Return how a line lies within ``max_jump_m`` at the car and ``max_bend_m`` in shape of another
        (both pixel coefficients), "" when it does not (``start.pitched_start``, ``roads.checks.restart``).
        """
        dx = (np.polyval(now, self.rows) - np.polyval(before, self.rows)) * self.xm
        if abs(dx[-1]) > self.config.max_jump_m or dx.max() - dx.min() > self.config.max_bend_m:
            return ""
        return f"{abs(dx[-1]):.2f} m at the car and {dx.max() - dx.min():.2f} m in shape"

    def inferred_line(self, seen: np.ndarray, track, side: int, top_px: int,
                      spread: np.ndarray | None = None) -> np.ndarray:
        """Return the pixel coefficients of the missing line ``side`` (0 left, 1 right): the ``seen`` line
        moved along its normal by the lane's width on each row from ``top_px`` (``fit.offset_line``).

        At the car the width is that seen in the last frames with both lines (``seen_width_m``): a width
        read back from inferred lines drifts. Ahead it follows the tracked width (a grade changes the
        flat view's lane), or with ``spread`` (a double line's stripes) the seen width times it. Without
        a ``track`` (a restart from one line) it is the width seen before the loss.
        """
        s = self.state
        rows = offset_rows_px(self.pipeline.size[1], top_px)
        if track is None:  # a restart from one line: the width seen before the loss
            at_car = tracked = s.lost_track.width_m
        else:
            tracked = normal_width_m(track[0], track[1], self.bottom, self.xm, self.ym)
            at_car = (s.seen_width_m if s.seen_widths else
                      tracked if np.isnan(s.restart_width) else s.restart_width)
        if spread is not None:
            width = at_car * np.polyval(spread, self.bottom - rows)
        elif track is not None and tracked > 0.5 * at_car:
            width = normal_width_m(track[0], track[1], rows, self.xm, self.ym) * (at_car / tracked)
        else:  # a restart, or a track whose width has collapsed: no shape ahead to keep
            width = np.full(len(rows), at_car)
        return np.array(offset_line(seen, -width if side == 0 else width, self.xm, self.ym,
                                    self.pipeline.size[1], top_px))



