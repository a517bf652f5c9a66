"""Where to look again when a frame's first search gives no lane: one chain for images and video.

A proposer is any object with a ``name``, a ``rule``, ``moves_lookahead`` and two methods:

- ``where(frame)`` returns what to look for in this frame (a side, the bases, a row), or None;
- ``propose(frame, where)`` returns candidate searches, each with a note for the frame's
  reason, in the order they are to be judged.

``choose`` asks the proposers in order; each candidate is judged (``Frame.judge``: a single
image's checks for ``LanePipeline.detect``, the track's for ``LaneTracker``) and taken under the
proposer's ``rule``: "more lines" when more of its lines pass than of the best so far, "a pair"
only when both pass. The first taken ends the proposer's turn. The proposers live with the parts
they serve: ``tracking.proposers``, ``roads.fallbacks`` (no track needed: fallback masks, shorter
views, other peaks) and ``roads.proposers`` (the asphalt edge, and those reading the track).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

import numpy as np

from .records import LaneSearch, LineFit
from .search import lane_pixels
from .thresholds import Made

SIDES = ("left", "right")


@dataclass
class Candidate:
    """A search of one frame and what the checks kept of it: the lines that pass (None where
    refused or not found), why the others do not, and whether a check refused a found line."""

    search: LaneSearch
    left: LineFit | None
    right: LineFit | None
    why: list[str]
    failed: bool

    @property
    def lines(self) -> int:
        """Return how many lines pass."""
        return (self.left is not None) + (self.right is not None)

    @property
    def pair(self) -> bool:
        """Return whether both lines pass."""
        return self.left is not None and self.right is not None


@dataclass
class Frame:
    """One frame as the proposers see it: pipeline and raw frame, the predicted lane ``track`` (None
    without one), the look-ahead's first row ``top``, the prior fits, the images (masks made once,
    when first asked), the candidates' ``judge``, the best so far, the searches and proposers that
    ran, and ``tracker``, the ``LaneTracker`` of a video frame (None for a single image).
    """

    pipeline: Any
    raw: np.ndarray
    judge: Callable[[LaneSearch], Candidate]
    images: dict
    track: tuple[np.ndarray, np.ndarray] | None = None
    top: int = 0
    prior: tuple[LineFit, LineFit] | None = None
    tracker: Any = None
    best: Candidate | None = None
    first: LaneSearch | None = None
    looked: list = field(default_factory=list)  # every search run: did any see a line?
    ran: list = field(default_factory=list)  # the names of the proposers that ran
    made: Made | None = None  # the whole view's masks made already (``LanePipeline.binary``)
    mask_pixels: tuple[np.ndarray, np.ndarray] | None = None  # ``mask()``'s, once extracted

    def mask(self) -> np.ndarray:
        """Return the whole view under the fallback masks' rule, thresholded once."""
        pipe, images = self.pipeline, self.images
        if "fallback binary" not in images:
            if pipe.has_fallback_masks or "binary" not in images:
                bird = images.get("birdseye")
                images["fallback binary"] = pipe.binary(
                    bird if bird is not None else pipe.birdseye(self.raw), fallback=True, made=self.made)
            else:
                images["fallback binary"] = images["binary"]
        return images["fallback binary"]

    def pixels(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the lane pixels (``search.lane_pixels``) of ``mask()``, extracted once."""
        if self.mask_pixels is None:
            self.mask_pixels = lane_pixels(self.mask())
        return self.mask_pixels

    def search(self, prior: tuple[LineFit, LineFit] | None = None,
               bases: tuple[float, float] | None = None, top_px: int = 0) -> LaneSearch:
        """Return ``LanePipeline.search`` of ``mask()``, its pixels extracted once for all the
        window searches of the frame, a line on pixels fitted already not fitted again (``made``)."""
        return self.pipeline.search(self.mask(), prior, bases=bases, top_px=top_px, pixels=self.pixels(),
                                    made=self.made)

    def birdseye(self) -> np.ndarray:
        """Return the frame's bird's-eye view, warped once."""
        if self.images.get("birdseye") is None:
            self.images["birdseye"] = self.pipeline.birdseye(self.raw)
        return self.images["birdseye"]


class Proposer(Protocol):
    """Where to look again in a frame (see the module docstring)."""

    name: str
    rule: str  # "more lines" or "a pair"
    moves_lookahead: bool  # a candidate taken sets the frame's look-ahead (its ``top_px``)

    def where(self, frame: Frame) -> Any | None: ...

    def propose(self, frame: Frame, where: Any) -> list[tuple[LaneSearch | None, str]]: ...


def choose(frame: Frame, proposers) -> Candidate:
    """Return the best candidate of a frame after asking each proposer in turn; ``frame.best`` starts
    as the judged first search (``frame.first``), ``frame.looked`` and ``frame.ran`` collect the
    searches run and the proposers that ran.
    """
    if frame.best is None:
        frame.best = frame.judge(frame.first)
        frame.looked.append(frame.first)
    for proposer in proposers:
        where = proposer.where(frame)
        if where is None:
            continue
        frame.ran.append(proposer.name)
        for candidate, note in proposer.propose(frame, where):
            if candidate is None:
                continue
            frame.looked.append(candidate)
            judged = frame.judge(candidate)
            if judged.pair if proposer.rule == "a pair" else judged.lines > frame.best.lines:
                frame.best = judged
                if note:
                    judged.why.append(note)
                if proposer.moves_lookahead:
                    frame.top = candidate.top_px
                break
    return frame.best


def passes(pipeline, search: LaneSearch) -> bool:
    """Return whether a search found both lines and they pass a single image's checks."""
    return search.left.found and search.right.found and pipeline.check(search).ok
