"""The car's hood, found as what stays still while the road moves (``detect_hood``).

The hood row is given (``hood_row_px``), or found from three frames or more: the hood is still
while the road moves, and its top is an edge that stays put. The hood row is the highest row of
that edge over the middle 80 % of the columns. When none is found (a still car, a single frame,
no hood in view) the estimate starts the view just below the lowest lane-line pixel found.
"""
from __future__ import annotations

import cv2
import numpy as np

HOOD_STATIC_GREY = 1.5
HOOD_EDGE_GREY = 6.0
HOOD_MAX_FRAMES = 15            # frames (evenly spread) the hood is looked for in
HOOD_MAX_FRACTION = 0.35


def detect_hood(frames: list[np.ndarray]) -> np.ndarray | None:
    """Return the hood's top row in every column (float; h where there is none) from 3+ frames of
    a moving car, or None when no hood is seen (or it cannot be told: fewer frames, a car
    standing still).

    The hood is still while the road moves, and its top is an edge that stays put. Per pixel of
    the bottom HOOD_MAX_FRACTION of the frame: the standard deviation across frames of the frame
    minus its local mean (a box 2 % of the height wide, which cancels exposure changes) is below
    ``HOOD_STATIC_GREY`` on the hood; going up each column from the bottom row, the hood ends at
    the first pixel that changes, and only where the median across frames of the vertical
    gradient there is a near-horizontal edge of ``HOOD_EDGE_GREY`` or more (smooth asphalt near
    the car changes little too, but has no such edge). A hood must be seen in a third of the
    middle 80 % of the columns.
    """
    if len(frames) < 3:
        return None
    h, w = frames[0].shape[:2]
    top = int(h * (1 - HOOD_MAX_FRACTION))
    k = max(5, int(0.02 * h) | 1)
    pick = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), HOOD_MAX_FRAMES)).round().astype(int))
    grey = [cv2.cvtColor(frames[i][top:], cv2.COLOR_RGB2GRAY).astype(np.float32) for i in pick]
    std = cv2.blur(np.stack([g - cv2.blur(g, (k, k)) for g in grey]).std(0), (9, 3))
    gy = np.median(np.stack([cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=0.25) for g in grey]), axis=0)
    gx = np.median(np.stack([cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=0.25) for g in grey]), axis=0)
    strength = np.where(np.abs(gy) >= 2 * np.abs(gx), np.abs(gy), 0.0)
    up = (std >= HOOD_STATIC_GREY)[::-1]
    seen = up.any(0)
    if seen.mean() < 0.5:
        return None          # most columns never change: the car stands still
    n_rows = up.shape[0]
    first = np.where(seen, np.argmax(up, axis=0), 0)
    rows = n_rows - 1 - first                        # row (in the region) where the stillness ends
    # the edge: the strongest near-horizontal one from 2 rows below that to k rows above (the
    # local mean lets the road's changes reach k / 2 rows into the hood)
    offsets = np.arange(-k, 3)
    cand = np.clip(rows[None, :] + offsets[:, None], 0, n_rows - 1)
    cols = np.arange(w)
    vals = strength[cand, cols[None, :]]
    best = np.argmax(vals, axis=0)
    edge_row = cand[best, cols]
    has = seen & (first > 0) & (vals[best, cols] >= HOOD_EDGE_GREY)
    lo, hi = int(0.1 * w), int(0.9 * w)
    if has[lo:hi].mean() < 1 / 3:
        return None
    hood = np.where(has, top + edge_row + 0.5, h).astype(np.float64)
    return _running_median(hood, max(3, (w // 40) | 1))


def _running_median(values: np.ndarray, k: int) -> np.ndarray:
    pad = k // 2
    v = np.pad(values, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(v, k)
    return np.median(windows, axis=1)
