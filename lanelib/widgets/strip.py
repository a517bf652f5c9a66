"""The strip under ``VideoTuner``'s frame: each tracked frame's line confidences and offset over
the clip, the frames with no lane or a held lane shaded, the frame shown marked."""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..result import FrameResult
from .base import fmt

STRIP_SIZE_PX = (1200, 160)  # (w, h) of the strip of confidences and offsets
STRIP_OFFSET_M = 1.0  # the strip's offset axis spans -1 .. +1 m
# strip colours (RGB)
_BG, _GRID, _TEXT = (24, 24, 24), (70, 70, 70), (200, 200, 200)
_LOST, _HELD = (110, 30, 30), (100, 80, 20)
_LEFT, _RIGHT, _OFFSET, _MARKER = (80, 220, 80), (80, 160, 255), (255, 170, 40), (255, 255, 255)


@dataclass(frozen=True)
class ClipSeries:
    """Per-frame series of a tracker run: confidences, offset (NaN where no lane), method."""

    left_conf: np.ndarray
    right_conf: np.ndarray
    offset_m: np.ndarray
    found: np.ndarray
    method: tuple[str, ...]

    @classmethod
    def of(cls, results: list[FrameResult]) -> "ClipSeries":
        return cls(np.array([r.left_conf for r in results], float),
                   np.array([r.right_conf for r in results], float),
                   np.array([r.offset_m if r.found else math.nan for r in results], float),
                   np.array([r.found for r in results], bool),
                   tuple(r.method for r in results))


def strip_x_of(n: int, w: int):
    """Return the function from a frame's index (of ``n``) to its x (px) in a strip ``w`` wide."""
    pad = 4
    if n <= 1:
        return lambda i: w // 2
    return lambda i: int(round(pad + i * (w - 1 - 2 * pad) / (n - 1)))


def draw_strip(s: ClipSeries, frame: int, size_px: tuple[int, int] = STRIP_SIZE_PX) -> np.ndarray:
    """Return the strip of a run: confidences and offset per frame, ``frame`` marked.

    Left (green) and right (blue) confidence on 0..1, the offset (orange) on -1..+1 m around
    the dashed centre line; frames with no lane are shaded red, held frames amber; the white
    line marks the frame shown. RGB uint8 of ``size_px`` (w, h).
    """
    w, h = size_px
    out = np.full((h, w, 3), _BG, np.uint8)
    top, bottom = 22, h - 7  # labels above the plot
    n = len(s.method)
    x_of = strip_x_of(n, w)
    half = max(1, int(np.ceil((x_of(1) - x_of(0)) / 2))) if n > 1 else w // 2
    for i in range(n):
        shade = _HELD if s.method[i] == "hold" else (None if s.found[i] else _LOST)
        if shade is not None:
            cv2.rectangle(out, (x_of(i) - half, top), (x_of(i) + half, bottom), shade, -1)
    mid = (top + bottom) // 2
    for y in (top, bottom):
        cv2.line(out, (0, y), (w - 1, y), _GRID, 1)
    for x in range(0, w, 12):
        cv2.line(out, (x, mid), (min(w - 1, x + 5), mid), _GRID, 1)

    def y_conf(c):
        return bottom - c * (bottom - top)

    def y_off(o):
        return mid - np.clip(o / STRIP_OFFSET_M, -1, 1) * (bottom - top) / 2

    xs = np.array([x_of(i) for i in range(n)], float)
    for values, colour, to_y in ((s.left_conf, _LEFT, y_conf), (s.right_conf, _RIGHT, y_conf),
                                 (s.offset_m, _OFFSET, y_off)):
        ok = np.isfinite(values)
        # one polyline per run of frames with a value
        breaks = np.flatnonzero(np.diff(ok.astype(int))) + 1
        for seg in np.split(np.arange(n), breaks):
            if seg.size and ok[seg[0]]:
                pts = np.stack([xs[seg], to_y(values[seg])], 1).round().astype(np.int32)
                if len(pts) == 1:
                    cv2.circle(out, tuple(int(v) for v in pts[0]), 1, colour, -1)
                else:
                    cv2.polylines(out, [pts], False, colour, 1, cv2.LINE_AA)
    x = x_of(min(frame, n - 1))
    cv2.line(out, (x, 0), (x, h - 1), _MARKER, 1)
    font, scale = cv2.FONT_HERSHEY_SIMPLEX, 0.4
    labels = (("confidence 0-1: left", _LEFT), ("right", _RIGHT),
              (f"offset -{STRIP_OFFSET_M:g}..+{STRIP_OFFSET_M:g} m", _OFFSET),
              ("no lane", (220, 90, 90)), ("held", (230, 190, 60)))
    tx = 8
    for text, colour in labels:
        cv2.putText(out, text, (tx, 15), font, scale, colour, 1, cv2.LINE_AA)
        tx += cv2.getTextSize(text, font, scale, 1)[0][0] + 14
    return out


def clip_readout(s: ClipSeries, results: list[FrameResult], frame: int, fps: float) -> str:
    """Return the figures of a tracked run (frames found, held, inferred; median offset and
    confidence) and those of its ``frame``, with why it was found so."""
    n = len(results)
    held = s.method.count("hold")
    inferred = sum("inferred" in r.reason for r in results if r.found)
    offs = np.abs(s.offset_m[np.isfinite(s.offset_m)])
    med_off = fmt(float(np.median(offs)), 2, " m") if offs.size else "not found"
    found_conf = np.concatenate([s.left_conf[s.found], s.right_conf[s.found]])
    med_conf = fmt(float(np.median(found_conf)), 2) if found_conf.size else "none"
    i = frame
    r = results[i]
    if r.found:
        now = (f"lane found, offset {fmt(r.offset_m, 2, ' m', True)}, width "
               f"{fmt(r.lane_width_m, 2, ' m')}, confidence {r.left_conf:.2f} / {r.right_conf:.2f}")
    else:
        now = "no lane"
    lines = [f"tracked {n} frames ({n / fps:.1f} s): lane found in {int(s.found.sum())} of {n}, "
             f"held {held}, a line inferred in {inferred}",
             f"median |offset| {med_off}, median line confidence {med_conf}",
             f"frame {i}: {r.method}, {now}"]
    if r.reason:
        lines.append(f"  why: {r.reason}")
    return "\n".join(lines)
