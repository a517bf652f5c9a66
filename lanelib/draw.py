"""Drawing: the lane mapped back onto the road, the measurements as text, the debug composite.

The lane overlay is drawn by mapping the polygon's points from the bird's-eye view into the
undistorted frame (``Minv``) and filling it there, which is cheaper than drawing in the bird's-eye
view and warping a whole image back.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

Color = tuple[int, int, int]


@dataclass(frozen=True)
class DrawConfig:
    """Colours (RGB), opacity and text size of the overlays.

    ``video_undistorted``: the ``video`` command draws on the RAW frame by default, the lane
    mapped through the lens model (what the camera saw, and one full-frame remap per frame
    cheaper); true draws on the undistorted frame, as the ``images`` command does.
    """

    lane_color: Color = (0, 200, 90)
    left_color: Color = (255, 60, 40)
    right_color: Color = (40, 110, 255)
    lane_alpha: float = 0.3
    line_thickness_px: int = 12
    font_scale: float = 1.0
    samples: int = 48
    video_undistorted: bool = False


def line_points(coeffs, height_px: int, samples: int = 48) -> np.ndarray:
    """Return (samples, 2) bird's-eye points (x, y) of x = f(y) from the top row to the bottom."""
    ys = np.linspace(0, height_px - 1, samples)
    return np.column_stack([np.polyval(coeffs, ys), ys])


def _to_int(pts: np.ndarray) -> np.ndarray:
    return np.round(pts).astype(np.int32).reshape(-1, 1, 2)


def lane_overlay(image: np.ndarray, left_coeffs, right_coeffs, Minv: np.ndarray | None,
                 config: DrawConfig = DrawConfig(), height_px: int | None = None,
                 lens: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Return ``image`` with the lane area and lines drawn, fits mapped through ``Minv``.

    ``left_coeffs``/``right_coeffs`` are bird's-eye pixel fits (None: that line is not drawn,
    and the area only when both exist). ``Minv`` None draws in the bird's-eye view itself.
    ``lens`` maps undistorted-image points on into the image drawn on (e.g. the raw frame
    through the lens distortion, ``camera.distort_points``); None: ``image`` is undistorted.
    """
    h = height_px or image.shape[0]
    out = image.copy()
    mapped = {}
    for side, coeffs in (("left", left_coeffs), ("right", right_coeffs)):
        if coeffs is None:
            continue
        pts = line_points(coeffs, h, config.samples)
        if Minv is not None:
            pts = cv2.perspectiveTransform(pts.reshape(-1, 1, 2), Minv).reshape(-1, 2)
        mapped[side] = lens(pts) if lens is not None else pts
    if len(mapped) == 2:
        poly = _to_int(np.vstack([mapped["left"], mapped["right"][::-1]]))
        # blend only inside the polygon's bounding box: outside it the blend gives the image back
        x, y, bw, bh = cv2.boundingRect(poly)
        x0, y0 = max(0, x - 1), max(0, y - 1)
        x1, y1 = min(out.shape[1], x + bw + 1), min(out.shape[0], y + bh + 1)
        if x0 < x1 and y0 < y1:
            box = out[y0:y1, x0:x1]
            fill = box.copy()
            cv2.fillPoly(fill, [poly], config.lane_color, lineType=cv2.LINE_AA, offset=(-x0, -y0))
            cv2.addWeighted(fill, config.lane_alpha, box, 1 - config.lane_alpha, 0, dst=box)
    for side, pts in mapped.items():
        color = config.left_color if side == "left" else config.right_color
        cv2.polylines(out, [_to_int(pts)], False, color, config.line_thickness_px, cv2.LINE_AA)
    return out


def put_lines(image: np.ndarray, lines: list[str], config: DrawConfig = DrawConfig(),
              origin: tuple[int, int] = (30, 50)) -> np.ndarray:
    """Write text lines onto ``image`` in place (white with a dark outline); return it."""
    scale = config.font_scale * image.shape[1] / 1280
    step = int(45 * scale)
    x, y = origin
    for i, text in enumerate(lines):
        pos = (int(x * scale), int(y * scale) + i * step)
        cv2.putText(image, text, pos, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), max(1, int(5 * scale)),
                    cv2.LINE_AA)
        cv2.putText(image, text, pos, cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255),
                    max(1, int(2 * scale)), cv2.LINE_AA)
    return image


def measurement_lines(radius_m: float, offset_m: float, lane_width_m: float, found: bool,
                      reason: str = "") -> list[str]:
    """Return the text lines that report a lane's measurements ("no lane found" when not found)."""
    if not found or any(math.isnan(v) for v in (radius_m, offset_m, lane_width_m)):
        return ["No lane found" + (f": {reason}" if reason else "")]
    side = "right" if offset_m > 0 else "left"
    rad = "straight" if radius_m >= 10_000 else f"{radius_m:,.0f} m"
    return [f"Radius of curvature: {rad}",
            f"Vehicle is {abs(offset_m):.2f} m {side} of centre",
            f"Lane width: {lane_width_m:.2f} m"]


def mask_to_rgb(mask: np.ndarray) -> np.ndarray:
    """Return a 0/255 mask as a grey RGB image."""
    return cv2.cvtColor(mask, cv2.COLOR_GRAY2RGB)


def search_view(binary: np.ndarray, search, config: DrawConfig = DrawConfig(),
                prior_margin_px: int = 60) -> np.ndarray:
    """Return the bird's-eye mask with the line pixels coloured, windows (or bands) and fits drawn."""
    view = mask_to_rgb(binary) // 3
    for side, color in (("left", config.left_color), ("right", config.right_color)):
        ys, xs = getattr(search, f"{side}_pixels")
        view[ys, xs] = color
    for w in search.windows:
        cv2.rectangle(view, (w.x_low, w.y_low), (w.x_high, w.y_high), (0, 255, 0), 2)
    h = binary.shape[0]
    for fit in (search.left, search.right):
        if fit.found:
            pts = line_points(fit.coeffs_px, h, config.samples)
            cv2.polylines(view, [_to_int(pts)], False, (255, 255, 0), 3, cv2.LINE_AA)
            if search.method == "prior":
                for dx in (-1, 1):
                    band = pts + [dx * prior_margin_px, 0]
                    cv2.polylines(view, [_to_int(band)], False, (0, 255, 0), 1, cv2.LINE_AA)
    return view


def composite(panels: list[tuple[str, np.ndarray]], size: tuple[int, int]) -> np.ndarray:
    """Return a 2x2 grid of labelled panels (RGB or masks) as one image of ``size`` (w, h)."""
    w, h = size
    pw, ph = w // 2, h // 2
    out = np.zeros((h, w, 3), np.uint8)
    for i, (label, img) in enumerate(panels[:4]):
        tile = mask_to_rgb(img) if img.ndim == 2 else img
        tile = cv2.resize(tile, (pw, ph), interpolation=cv2.INTER_AREA)
        org = (10, ph - 15)  # bottom-left: the result panel has its own text at the top
        cv2.putText(tile, label, org, cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4, cv2.LINE_AA)
        cv2.putText(tile, label, org, cv2.FONT_HERSHEY_SIMPLEX, 0.8, (255, 255, 0), 2, cv2.LINE_AA)
        r, c = divmod(i, 2)
        out[r * ph:(r + 1) * ph, c * pw:(c + 1) * pw] = tile
    return out
