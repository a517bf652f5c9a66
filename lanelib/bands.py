"""The lane-pixel mask of a tracked frame, only in the bands around the prior fits.

A tracked frame is searched only within ``prior_margin_px`` of the previous lines
(``search.search_around``), so only those bands of the view need warping and thresholding.
``Bands.mask`` gives, inside them, exactly the pixels of
``LanePipeline.binary(LanePipeline.birdseye(raw))``.
"""
from __future__ import annotations

import cv2
import numpy as np

from . import thresholds
from .params.masks import ThresholdConfig
from .records import LineFit

BAND_STRIPS = 4  # horizontal strips in which the bands are cut


class Bands:
    """The band masks of one pipeline: its thresholds, search margin (px), raw -> bird's-eye
    remap maps and frame size (w, h); the border each mask looks beyond a pixel is found once."""

    def __init__(self, tconf: ThresholdConfig, margin_px: float, maps: tuple[np.ndarray, np.ndarray],
                 size: tuple[int, int]):
        self.tconf, self.margin_px, self.maps, self.size = tconf, margin_px, maps, size
        self.context_px = thresholds.context_px(tconf)
        self.context_masks = tuple(n for n in thresholds.rule_masks(tconf)
                                   if thresholds.mask_context_px(getattr(tconf, n)) != (0, 0))

    def mask(self, raw: np.ndarray, prior: tuple[LineFit, LineFit], whole: np.ndarray | None = None
             ) -> np.ndarray:
        """Return the mask of a RAW frame within ``margin_px`` of each found ``prior`` line, 0 elsewhere
        (with ``whole``, the whole view's mask, cut from it). In each of ``BAND_STRIPS`` horizontal
        strips the band pieces, grown by ``thresholds.context_px``, are laid side by side in x order (a
        piece cut by the image's edge keeps it) and remapped and thresholded in one call each.
        """
        w, h = self.size
        margin = self.margin_px
        cx, cy = self.context_px
        m1, m2 = self.maps
        out = np.zeros((h, w), np.uint8)
        edges = np.linspace(0, h, BAND_STRIPS + 1).round().astype(int)
        for y0, y1 in zip(edges[:-1], edges[1:]):
            rows = np.arange(y0, y1, dtype=np.float64)
            spans = []
            for fit in prior:
                if fit.found:
                    xs = fit.x_at(rows)
                    lo = max(0, int(np.floor(xs.min() - margin)))
                    hi = min(w, int(np.ceil(xs.max() + margin)) + 1)
                    if lo < hi:
                        spans.append([lo, hi])
            pieces: list[list[int]] = []  # [lo, hi] of band columns; the grown box is lo-cx..hi+cx
            for lo, hi in sorted(spans):
                if pieces and lo - cx <= pieces[-1][1] + cx:
                    pieces[-1][1] = max(pieces[-1][1], hi)
                else:
                    pieces.append([lo, hi])
            if not pieces:
                continue
            if whole is not None:
                for lo, hi in pieces:
                    out[y0:y1, lo:hi] = whole[y0:y1, lo:hi]
                continue
            b0, b1 = max(0, y0 - cy), min(h, y1 + cy)
            boxes = [(max(0, lo - cx), min(w, hi + cx)) for lo, hi in pieces]
            # each box remapped into its place on the canvas (no stacked copy of the maps)
            grown = np.empty((b1 - b0, sum(a1 - a0 for a0, a1 in boxes), raw.shape[2]), np.uint8)
            x = 0
            for a0, a1 in boxes:
                cv2.remap(raw, m1[b0:b1, a0:a1], m2[b0:b1, a0:a1], cv2.INTER_LINEAR,
                          dst=grown[:, x:x + a1 - a0])
                x += a1 - a0
            cuts, x = [], 0  # where each piece's band lies in the grown canvas
            for (lo, hi), (a0, a1) in zip(pieces, boxes):
                cuts.append((slice(y0 - b0, y1 - b0), slice(x + lo - a0, x + hi - a0)))
                x += a1 - a0
            part = self.threshold(grown, cuts)
            x = 0
            for lo, hi in pieces:
                out[y0:y1, lo:hi] = part[:, x:x + hi - lo]
                x += hi - lo
        return out

    def threshold(self, grown: np.ndarray, cuts: list[tuple[slice, slice]]) -> np.ndarray:
        """Return the combined mask of the band pieces ``cuts`` of a grown canvas, side by side: masks that
        look beyond a pixel (Sobel, top-hat) are computed on the grown canvas and cut, colour masks on
        the pieces; with a closing or opening of the combined mask, all on the grown canvas.
        """
        tconf = self.tconf
        join = (lambda parts: parts[0]) if len(cuts) == 1 else np.hstack
        if tconf.open_px > 1 or tconf.close_px > 1:
            full = thresholds.combine(grown, tconf)
            return join([full[c] for c in cuts])
        channels = thresholds.Channels(grown)
        computed = {}
        for name in self.context_masks:
            m = thresholds.mask(channels, getattr(tconf, name))
            computed[name] = join([m[c] for c in cuts])
        pieces = channels.cut(cuts, join)  # the colour spaces those masks converted, cut too
        return thresholds.combine(pieces.rgb, tconf, computed, channels=pieces)
