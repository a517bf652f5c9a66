"""The hard-road proposers that need no track: the whole view looked at again another way.

Each is a proposer (the protocol in ``lanelib.proposers``) that asks only without a track, when
the best search so far gives no pair, and only when its switch is on (the ``hard-roads`` preset's
parts; ``OtherPeaks`` with ``SearchConfig.candidates`` > 1). A single image
(``LanePipeline.detect``) and the tracker ask them alike.

- ``FallbackMasks``: the whole view under the fallback masks (``ThresholdConfig.fallback_rule``).
- ``ShorterViews``: shorter look-aheads, where a tight bend's lane stays in view
  (``short_view_search``).
- ``OtherPeaks``: windows from other histogram peaks, where a seam, a kerb or a shadow edge took
  a line (``robust_search``).
"""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from ..proposers import Frame, passes
from ..records import LaneSearch
from ..search import histogram, lane_pixels, sliding_windows


class FallbackMasks:
    """Without a track and no pair: the whole view on the fallback masks
    (``ThresholdConfig.fallback_rule``)."""

    name, rule, moves_lookahead = "fallback masks", "more lines", False

    def where(self, frame: Frame):
        return True if frame.track is None and not frame.best.pair and frame.pipeline.has_fallback_masks else None

    def propose(self, frame: Frame, where):
        return [(frame.search(), "")]


class ShorterViews:
    """Without a track and no pair: shorter look-aheads (``SearchConfig.short_views``), where a
    tight bend's lane stays in view (``short_view_search``)."""

    name, rule, moves_lookahead = "shorter views", "more lines", False

    def where(self, frame: Frame):
        ok = frame.track is None and not frame.best.pair and frame.pipeline.config.search.short_views
        return True if ok else None

    def propose(self, frame: Frame, where):
        return [(short_view_search(frame.pipeline, frame.mask(), frame.pixels()), "")]


class OtherPeaks:
    """Without a track and no pair: windows from other histogram peaks (``robust_search``,
    ``SearchConfig.candidates`` > 1)."""

    name, rule, moves_lookahead = "other peaks", "more lines", False

    def where(self, frame: Frame):
        ok = frame.track is None and not frame.best.pair and frame.pipeline.config.search.candidates > 1
        return True if ok else None

    def propose(self, frame: Frame, where):
        return [(robust_search(frame.pipeline, frame.mask(), frame.best.search, frame.pixels()), "")]


def short_view_search(pipeline, binary: np.ndarray,
                      pixels: tuple[np.ndarray, np.ndarray] | None = None) -> LaneSearch | None:
    """Return the first search in a shorter look-ahead whose lane passes the checks, or None.

    Sliding windows over the lower ``SearchConfig.short_views`` shares of the view in turn (a
    tight bend's lane stays in a shorter view; ``search.lookahead_top_px``). Its search's
    ``top_px`` says which. ``pixels``: the mask's ``search.lane_pixels`` when made already.
    """
    h = pipeline.size[1]
    pixels = lane_pixels(binary) if pixels is None else pixels
    for share in pipeline.config.search.short_views:
        search = pipeline.search(binary, top_px=int(round(h * (1.0 - share))), pixels=pixels)
        if passes(pipeline, search):
            return search
    return None


def candidate_bases(hist: np.ndarray, car_x: float | None, count: int,
                    min_gap_px: float) -> tuple[list[float], list[float]]:
    """Return up to ``count`` histogram peaks (x, strongest first) left and right of ``car_x``: columns
    holding the most pixels within ``min_gap_px`` either side (one per line), never empty ones.
    """
    mid = int(car_x if car_x is not None else len(hist) / 2)
    r = max(1, int(min_gap_px))
    kernel = np.ones((1, 2 * r + 1), np.uint8)
    local_max = cv2.dilate(hist.astype(np.float32).reshape(1, -1), kernel).ravel()
    peaks = np.flatnonzero((hist > 0) & (hist >= local_max))
    out = []
    for side in (peaks[peaks < mid], peaks[peaks >= mid]):
        chosen: list[float] = []
        for x in side[np.argsort(-hist[side], kind="stable")]:
            if all(abs(x - c) >= min_gap_px for c in chosen):
                chosen.append(float(x))
            if len(chosen) == count:
                break
        out.append(chosen)
    return out[0], out[1]


def robust_search(pipeline, binary: np.ndarray, first: LaneSearch,
                  pixels: tuple[np.ndarray, np.ndarray] | None = None) -> LaneSearch | None:
    """Return the first search from other histogram peaks whose lane passes the checks, or None.

    For a frame whose search from the strongest peaks failed its checks (a seam, a kerb or a
    shadow edge took a line): sliding windows from each pair of the ``candidates`` strongest
    peaks on each side (``candidate_bases``), the pairs with the stronger peaks first,
    skipping the pair already tried. Its search's ``method`` is "robust". ``pixels``: the mask's
    ``search.lane_pixels`` when made already.
    """
    sc = pipeline.config.search
    hist = histogram(binary, sc.histogram_fraction)
    lefts, rights = candidate_bases(hist, pipeline.car_x_px, sc.candidates, sc.margin_px)
    pairs = sorted(((l, r) for l in lefts for r in rights),
                   key=lambda p: -(int(hist[int(p[0])]) + int(hist[int(p[1])])))
    for bases in pairs:
        if first.bases_px == bases:
            continue
        search = sliding_windows(binary, sc, bases=bases, car_x=pipeline.car_x_px, pixels=pixels)
        if passes(pipeline, search):
            return replace(search, method="robust")
    return None
