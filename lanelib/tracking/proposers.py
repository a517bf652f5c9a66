"""The proposers that read the track: where the tracker looks again in a frame.

The protocol and the chain are ``lanelib.proposers`` (``choose``), shared with a single image's
``LanePipeline.detect``. These three need a track, or what the tracker remembers: windows
started from the tracked lines, windows from the remembered bases where a histogram peak is
weak, and the re-acquisition of a line inferred for several frames. The hard-road ones (the
crest's road view, the asphalt edge, a faded line's shoulder) live in ``lanelib.roads.proposers``.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..fit import parallel_fits
from ..proposers import Frame
from ..records import LaneSearch, LineFit, Window
from ..search import search_around


class WindowsFromTrack:
    """With a track and no pair: sliding windows started from the tracked lines' bases."""

    name, rule, moves_lookahead = "windows from the track", "more lines", False

    def where(self, frame: Frame):
        return frame.tracker.bases(frame.track) if frame.track is not None and not frame.best.pair else None

    def propose(self, frame: Frame, where):
        return [(frame.search(bases=where, top_px=frame.top), "")]


class RememberedBases:
    """Without a track, when a histogram peak is weak (``min_base_peak``): windows started
    from the median of the recent accepted bases (``base_history_frames``) on that side."""

    name, rule, moves_lookahead = "remembered bases", "more lines", False

    def where(self, frame: Frame):
        if frame.track is not None or frame.best.pair:
            return None
        t = frame.tracker
        remembered, search = t.remembered_bases, frame.first
        if remembered is None or search.method != "windows":
            return None
        out, weak = [], False
        for base, conf, memory in zip(search.bases_px, search.base_confidence, remembered):
            if base is None or conf is None or conf < t.config.min_base_peak:
                out.append(memory)
                weak = True
            else:
                out.append(base)
        return (out[0], out[1]) if weak else None

    def propose(self, frame: Frame, where):
        return [(frame.search(bases=where),
                 "windows started from the remembered bases (weak histogram peak)")]


class Reacquire:
    """A line the track has inferred for ``reacquire_after_frames`` frames, looked for in a band
    around its inference that widens with the frames it has been inferred (up to
    ``reacquire_band_m``): an inference drifts while nothing shows the line."""

    name, rule, moves_lookahead = "re-acquire", "more lines", False

    def where(self, frame: Frame):
        if frame.track is None:
            return None
        best = frame.best
        for i, (mine, other) in enumerate(((best.left, best.right), (best.right, best.left))):
            if mine is None and other is not None and frame.tracker.reacquire_half_px(i) > 0:
                return i
        return None

    def propose(self, frame: Frame, where):
        return [(reacquired(frame.tracker, frame.best.search, frame.mask(), frame.pixels(),
                            frame.track, where, frame.top), "")]


def reacquired(tracker: "LaneTracker", search: LaneSearch, binary: np.ndarray,
               pixels: tuple[np.ndarray, np.ndarray], track, side: int, top_px: int) -> LaneSearch | None:
    """Return ``search`` with line ``side`` looked for again in ``binary``, the whole view, or
    None when no line could lie within ``reacquire_half_px`` of its inference. ``pixels``: the
    mask's ``search.lane_pixels`` (``Frame.pixels``, extracted once for the frame's searches).

    The inference is moved across to the median distance of the lane pixels in the bin nearest
    it (bins ``prior_margin_px`` wide, every half margin, out to the band's half width) that
    holds ``min_line_pixels``, and the line is searched within ``prior_margin_px`` of it
    (``search.search_around``), its curvature shared with the other line when it is short
    (``fit.parallel_fits``). The band goes into the search's windows, so the line's band checks
    compare it with the band it was searched in.
    """
    cfg = tracker.pipeline.config.search
    half = tracker.reacquire_half_px(side)
    margin = cfg.prior_margin_px
    ys, xs = pixels
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
    h = tracker.pipeline.size[1]
    slabs = np.linspace(float(h), float(top_px), cfg.n_windows + 1).round().astype(int)
    band = tuple(Window(name, int(x - margin), int(x + margin), int(lo), int(hi))
                 for hi, lo in zip(slabs[:-1], slabs[1:])
                 for x in [float(np.polyval(moved, (lo + hi) / 2))])
    merged = replace(search, **{name: getattr(found, name), f"{name}_pixels": getattr(found, f"{name}_pixels")},
                     windows=tuple(w for w in search.windows if w.side != name) + band)
    left, right = parallel_fits(merged.left, merged.right, merged.left_pixels, merged.right_pixels, h, cfg)
    return replace(merged, left=left, right=right)
