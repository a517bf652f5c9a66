"""The tracker's state: one record of everything the next frames' results depend on.

``TrackState`` holds the accepted frames the lane is smoothed over, the hold's counters and what
the hard-road parts remember. It is a plain record, compared, copied and pickled: a Dask segment
of a video starts from the state the previous one ended in (``cluster.settle_joints``), and
``key`` says whether two states give the same results.
"""
from __future__ import annotations

import hashlib
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..params.roads import TrackerConfig


@dataclass(frozen=True)
class Accepted:
    """One frame's accepted lane: pixel coefficients and confidence of each line, the first row
    of the look-ahead it was measured in, the frame's number and which lines were inferred."""

    left: np.ndarray
    right: np.ndarray
    left_conf: float
    right_conf: float
    top_px: int = 0
    frame: int = 0
    inferred: tuple[bool, bool] = (False, False)  # (left, right) inferred, not seen


@dataclass(frozen=True)
class LostTrack:
    """What a reset remembers for a restart from one line: the tracked lines' x (px) on the bottom row,
    whether each was seen (not inferred) in the last accepted frame, and the width seen at the car.
    """

    bases: tuple[float, float]
    seen: tuple[bool, bool]
    width_m: float


@dataclass(eq=False)
class TrackState:
    """Everything ``LaneTracker`` carries from one frame to the next; equal when ``key`` is.

    ``history`` and ``trend`` hold the accepted frames the lane is smoothed over and its trend read
    from (``roads.trend``); ``lost`` counts frames since the last accepted one, ``blind`` those with
    nothing seen. The rest serves single parts: ``seen_widths`` (a missing line's width),
    ``edge`` and ``shoulders`` (the asphalt edge, the shoulder beyond paint), ``inferred_run`` and
    ``faded_run`` (re-acquisition, a faded line), ``lost_track``, ``restart_width`` and
    ``restart_candidates`` (a restart from one line), ``pitched`` and ``base_history`` (bases).
    """

    history: deque = field(default_factory=deque)
    trend: deque = field(default_factory=deque)
    seen_widths: deque = field(default_factory=deque)
    shoulders: tuple[deque, deque] = field(default_factory=lambda: (deque(), deque()))
    base_history: deque = field(default_factory=deque)
    frame: int = 0
    lost: int = 0
    blind: int = 0
    conf: tuple[float, float] = (0.0, 0.0)
    edge: list = field(default_factory=lambda: [False, False])
    inferred_run: list = field(default_factory=lambda: [0, 0])
    faded_run: list = field(default_factory=lambda: [0, 0])
    restart_width: float = float("nan")
    lost_track: LostTrack | None = None
    # (side, pixel coefficients) of the lines that could restart the lane in the previous frame
    # and in this one, each waiting for the next frame to confirm it
    restart_candidates: tuple[list, list] = field(default_factory=lambda: ([], []))
    # (frames in a row, left and right pixel coefficients) of the pitched pairs of the previous
    # frame and of this one
    pitched: tuple[list, list] = field(default_factory=lambda: ([], []))

    @classmethod
    def new(cls, config: TrackerConfig) -> "TrackState":
        """Return the state of a tracker that has seen nothing (a new video)."""
        return cls(base_history=deque(maxlen=config.base_history_frames)).forgot_track(config)

    def forgot_track(self, config: TrackerConfig) -> "TrackState":
        """Forget the track (the lane was lost too long) and return the state; the frame
        number, the remembered bases and what a restart needs stay."""
        self.history = deque(maxlen=config.smooth_frames)
        self.trend = deque(maxlen=max(config.trend_frames, 1))
        self.lost = self.blind = 0
        self.seen_widths = deque(maxlen=config.smooth_frames)
        self.conf = (0.0, 0.0)
        self.edge = [False, False]
        self.shoulders = (deque(maxlen=config.shoulder_frames), deque(maxlen=config.shoulder_frames))
        self.inferred_run = [0, 0]
        self.faded_run = [0, 0]
        self.restart_width = float("nan")
        return self

    def next_frame(self) -> None:
        """Count a new frame: this frame's restart and pitched-start candidates become the
        previous frame's."""
        self.frame += 1
        self.restart_candidates = (self.restart_candidates[1], [])
        self.pitched = (self.pitched[1], [])

    def key(self) -> bytes:
        """Return a fingerprint of the state the next frames' results depend on: two trackers of one
        pipeline with equal keys give bit-identical results on the same next frames, whichever frame
        each started from (remembered frames are counted back from the last one tracked).
        """
        def accepted(acc: Accepted) -> tuple:
            return (acc.left.tobytes(), acc.right.tobytes(), acc.left_conf, acc.right_conf,
                    acc.top_px, self.frame - acc.frame, acc.inferred)

        state = ([accepted(a) for a in self.history], [accepted(a) for a in self.trend],
                 list(self.base_history), self.lost, self.blind, self.conf, list(self.seen_widths),
                 self.edge, [list(d) for d in self.shoulders], self.faded_run, self.inferred_run,
                 self.lost_track, self.restart_width,
                 [(side, c.tobytes()) for side, c in self.restart_candidates[1]],
                 [(run, l.tobytes(), r.tobytes()) for run, l, r in self.pitched[1]])
        return hashlib.sha256(repr(state).encode()).digest()

    def __eq__(self, other) -> bool:
        return isinstance(other, TrackState) and self.key() == other.key()

    __hash__ = None  # mutable

    # ---- the smoothed lane ----------------------------------------------------------------

    def smoothing_weights(self, recency_decay: float) -> np.ndarray:
        """Return the (left, right) weight of each remembered frame in ``lane``, oldest first:
        ``recency_decay ** age`` times the line's confidence (at least 0.05)."""
        weights = []
        for age, acc in enumerate(reversed(self.history)):
            decay = recency_decay ** age
            weights.append((decay * max(acc.left_conf, 0.05), decay * max(acc.right_conf, 0.05)))
        return np.array(weights[::-1])

    def lane(self, recency_decay: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the smoothed pixel coefficients (left, right), or None without a track."""
        if not self.history:
            return None
        w = self.smoothing_weights(recency_decay)
        left = np.array([a.left for a in self.history])
        right = np.array([a.right for a in self.history])
        return (w[:, 0] @ left / w[:, 0].sum(), w[:, 1] @ right / w[:, 1].sum())

    @property
    def seen_width_m(self) -> float:
        """Return the median width (m) seen at the car in the remembered frames, NaN before any."""
        return float(np.median(self.seen_widths)) if self.seen_widths else float("nan")

    def newest_inferred(self, side: int) -> bool:
        """Return whether the newest accepted frame inferred line ``side`` (0 left, 1 right)."""
        return bool(self.history) and self.history[-1].inferred[side]
