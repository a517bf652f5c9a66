"""Lane-pixel search in the bird's-eye mask: the histogram and its bases, sliding windows, the
search around a prior fit, and the look-ahead that keeps a tracked lane in the view. Each
returns a ``records.LaneSearch`` whose lines are fitted by ``fit_side``.
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from .fit import fit_line_with_first, parallel_fits
from .params import SearchConfig
from .records import LaneSearch, LineFit, Window
from .roads.stripes import centre_side, double_line_fit, fullest_column


def lane_pixels(binary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (ys, xs) of the nonzero pixels of a mask, sorted by y then x (int32 arrays).

    A contiguous uint8 mask whose width is a multiple of 8 is read as 64-bit words: the nonzero
    words by one vectorised test (``np.flatnonzero``), then the nonzero bytes of those, word by
    word; any other mask pixel by pixel (``cv2.findNonZero``). The same pixels in the same order.
    """
    w = binary.shape[1]
    if not (binary.ndim == 2 and binary.dtype == np.uint8 and w % 8 == 0 and binary.flags.c_contiguous):
        pts = cv2.findNonZero(binary)
        if pts is None:
            return np.empty(0, np.int32), np.empty(0, np.int32)
        pts = pts.reshape(-1, 2)  # findNonZero scans row by row: already sorted by y
        return pts[:, 1].copy(), pts[:, 0].copy()
    words = binary.view(np.uint64).ravel()
    nonzero = np.flatnonzero(words != 0)
    which, byte = np.nonzero(words.take(nonzero).view(np.uint8).reshape(-1, 8))
    ys, first = np.divmod(nonzero[which], w // 8)  # each word's row and first column / 8
    return ys.astype(np.int32), (first * 8 + byte).astype(np.int32)


def histogram(binary: np.ndarray, fraction: float = 0.5) -> np.ndarray:
    """Return the count of mask pixels per column over the lower ``fraction`` of the image."""
    h = binary.shape[0]
    start = int(h * (1 - fraction))
    return cv2.reduce(binary[start:], 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel() // 255


def find_bases(hist: np.ndarray, car_x: float | None = None) -> tuple[float | None, float | None]:
    """Return the x of the strongest column left and right of ``car_x`` (None where empty)."""
    mid = int(car_x if car_x is not None else len(hist) / 2)
    left = int(np.argmax(hist[:mid])) if hist[:mid].any() else None
    right = mid + int(np.argmax(hist[mid:])) if hist[mid:].any() else None
    return (None if left is None else float(left), None if right is None else float(right))


def base_peak_confidence(hist: np.ndarray, x: float | None) -> float | None:
    """Return how much the histogram's peak at column ``x`` stands out, (peak - mean) / mean: 0 for a
    flat or empty histogram, large for one strong line on an empty view; None for no base.
    """
    if x is None:
        return None
    mean = float(hist.sum()) / len(hist) if len(hist) else 0.0  # np.mean's: a sum of counts is exact
    if mean <= 0:
        return 0.0
    return (float(hist[int(x)]) - mean) / mean


def sliding_windows(binary: np.ndarray, config: SearchConfig = SearchConfig(),
                    bases: tuple[float | None, float | None] | None = None,
                    car_x: float | None = None, top_px: int = 0,
                    pixels: tuple[np.ndarray, np.ndarray] | None = None, fits: dict | None = None
                    ) -> LaneSearch:
    """Return the lane pixels found by sliding windows from the histogram bases, and their fits.

    With ``top_px`` > 0 only the rows from ``top_px`` down are read (``lookahead_top_px``): the
    histogram covers the lower ``histogram_fraction`` of them and the windows, as tall as in the
    whole view, stop there; fits and their span rules stay in the view's rows. ``pixels``: the
    mask's ``lane_pixels``, when already made; ``fits``: ``fit_side``'s memo of the image.
    """
    h = binary.shape[0]
    top_px = int(min(max(top_px, 0), h - 1))
    ys, xs = lane_pixels(binary) if pixels is None else pixels
    if top_px:
        first = int(np.searchsorted(ys, top_px))
        ys, xs = ys[first:], xs[first:]
    seen = binary[top_px:] if top_px else binary
    confidence: tuple[float | None, float | None] = (None, None)
    if bases is None:
        hist = histogram(seen, config.histogram_fraction)
        bases = find_bases(hist, car_x)
        confidence = tuple(base_peak_confidence(hist, b) for b in bases)
        if None in bases:  # a dashed line may have no dash in the lower part: look at all rows
            whole_hist = histogram(seen, 1.0)
            whole = find_bases(whole_hist, car_x)
            confidence = tuple(c if b is not None else base_peak_confidence(whole_hist, w)
                               for b, c, w in zip(bases, confidence, whole))
            bases = tuple(b if b is not None else w for b, w in zip(bases, whole))
    win_h = h / config.n_windows
    rows = []  # each window's rows (y_low, y_high), the same on both sides
    for i in range(config.n_windows):
        y_high = int(round(h - i * win_h))
        if y_high <= top_px:
            break
        rows.append((max(top_px, int(round(h - (i + 1) * win_h))), y_high))
    cuts = np.searchsorted(ys, [y for pair in rows for y in pair]).tolist()  # their slices of ys
    windows: list[Window] = []
    picked = {}
    for side, base in zip(("left", "right"), bases):
        chosen = []
        x = base
        margin = config.margin_px
        toward_centre = 1 if side == "left" else -1  # the lane centre lies right of the left line
        for (y_low, y_high), lo, hi in zip(rows, cuts[::2], cuts[1::2]):
            if x is None:
                break
            row_xs = xs[lo:hi]
            inside = ((row_xs >= x - margin) & (row_xs < x + margin)).nonzero()[0]
            windows.append(Window(side, int(x - margin), int(x + margin), y_low, y_high))
            if config.centre_first and len(inside) >= config.minpix:
                inside = centre_side(row_xs, inside, config.minpix, toward_centre)
            chosen.append(inside + lo)
            if len(inside) >= config.minpix:
                if config.window_histogram:
                    x = fullest_column(row_xs[inside])
                else:  # their mean: the sum is exact in int64, so this is np.mean's float
                    x = int(row_xs[inside].sum()) / len(inside)
                margin = config.margin_px
            elif config.grow_margin_px:
                margin += config.grow_margin_px
        idx = np.concatenate(chosen) if chosen else np.empty(0, np.int64)
        picked[side] = (ys[idx], xs[idx])
    left, picked["left"] = fit_side(picked["left"], "left", h, config, "no lane pixels left of the car",
                                    top_px, fits)
    right, picked["right"] = fit_side(picked["right"], "right", h, config, "no lane pixels right of the car",
                                      top_px, fits)
    left, right = parallel_fits(left, right, picked["left"], picked["right"], h, config)
    return LaneSearch(left, right, "windows", picked["left"], picked["right"], tuple(windows), bases,
                      confidence, top_px)


def search_around(binary: np.ndarray, left: LineFit, right: LineFit,
                  config: SearchConfig = SearchConfig(), top_px: int = 0) -> LaneSearch:
    """Return the lane pixels within ``prior_margin_px`` of previous fits, and their new fits (with
    ``top_px`` > 0, from the rows below it only).
    """
    h, w = binary.shape[:2]
    top_px = int(min(max(top_px, 0), h - 1))
    # only the columns that the bands around the found fits reach hold pixels the search reads
    found = [p.x_at(np.arange(top_px, h, dtype=np.float64)) for p in (left, right) if p.found]
    lo = min(float(x.min()) for x in found) - config.prior_margin_px if found else 0.0
    hi = max(float(x.max()) for x in found) + config.prior_margin_px if found else 0.0
    if math.isfinite(lo) and math.isfinite(hi):
        c0 = min(w, max(0, math.floor(lo) - 1))
        c1 = max(c0, min(w, math.ceil(hi) + 2))
    else:
        c0, c1 = 0, w
    if c1 > c0:
        ys, xs = lane_pixels(binary[top_px:, c0:c1])
        ys += top_px
        xs += c0
    else:
        ys, xs = np.empty(0, np.int32), np.empty(0, np.int32)
    picked = {}
    for side, prior in (("left", left), ("right", right)):
        if not prior.found:
            picked[side] = (ys[:0], xs[:0])
            continue
        near = np.abs(xs - prior.x_at(ys)) < config.prior_margin_px
        picked[side] = (ys[near], xs[near])
    new_left, picked["left"] = fit_side(
        picked["left"], "left", h, config, "no previous left fit to search around" if not left.found
        else "no lane pixels near the previous left fit", top_px)
    new_right, picked["right"] = fit_side(
        picked["right"], "right", h, config, "no previous right fit to search around" if not right.found
        else "no lane pixels near the previous right fit", top_px)
    new_left, new_right = parallel_fits(new_left, new_right, picked["left"], picked["right"], h, config)
    return LaneSearch(new_left, new_right, "prior", picked["left"], picked["right"], top_px=top_px)


def lookahead_top_px(lines, size_px: tuple[int, int], config: SearchConfig = SearchConfig()) -> int:
    """Return the first row (px) of the look-ahead that keeps the tracked lines in the view.

    On a tight bend the lane leaves the view sideways long before its top row (a line ``d`` m from
    the side leaves after sqrt(2 * R * d) of road on radius ``R``); above that the other line
    sweeps into its windows and checks compare a line with the extrapolation of one that is gone.
    The look-ahead ends on the lowest row where a line comes within ``margin_px / 2`` of the side,
    keeping at least ``min_view_fraction`` of the height. It is a band of rows of the same view,
    not a second warp: scale and coordinates stay the view's, so measurements, overlay and
    evaluation read the fits as the whole view's.

    Parameters
    ----------
    lines : pixel coefficients (a, b, c) of each tracked line (e.g. the tracked lane's two).
    size_px : (width, height) of the bird's-eye view.
    config : ``margin_px`` and ``min_view_fraction``.
    """
    w, h = size_px
    rows = np.arange(h - 1, -1, -8, dtype=np.float64)  # bottom to top, every 8 rows
    edge = config.margin_px / 2
    out = np.zeros(len(rows), bool)
    for coeffs in lines:
        x = np.polyval(coeffs, rows)
        out |= (x < edge) | (x > w - 1 - edge)
    if not out.any():
        return 0
    top = int(rows[int(np.argmax(out))]) + 1
    return int(min(top, round(h * (1.0 - config.min_view_fraction))))


def fit_side(pixels: tuple[np.ndarray, np.ndarray], side: str, height_px: int, config: SearchConfig,
              missing: str, top_px: int = 0, fits: dict | None = None
              ) -> tuple[LineFit, tuple[np.ndarray, np.ndarray]]:
    """Return ``fit_line`` of one line's pixels (``side``: "left" or "right"; ``top_px``: the
    look-ahead) and the pixels it rests on. With ``double_line_px`` on, pixels scattering like a
    double line (RMS above a quarter of it) are read at the inner stripe
    (``roads.stripes.double_line_fit``), so a single line costs no second fit. ``fits``: the fits
    of one image's searches so far (``thresholds.Made.fits``): pixels that another of its searches
    fitted under the same config (fallback windows often pick them again) are not fitted again.
    """
    key = (side, top_px > 0, missing, len(pixels[0]), height_px)  # only whether there is a look-ahead
    for c, ys, xs, out in fits.get(key, ()) if fits is not None else ():  # ``c``: the entry's config, held
        if c is config and np.array_equal(ys, pixels[0]) and np.array_equal(xs, pixels[1]):
            return out
    fit, first = fit_line_with_first(*pixels, height_px, config, missing, top_px)
    out = double_line_fit(fit, first, pixels, side, height_px, config, missing, top_px)
    if fits is not None:
        fits.setdefault(key, []).append((config, *pixels, out))
    return out
