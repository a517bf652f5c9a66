"""Drawing: the lane mapped back onto the road, the measurements as text, grids of labelled views.

The lane polygon's points are mapped from the bird's-eye view into the frame drawn on (by the
perspective's ``inverse``, or the bird's-eye -> raw chain) and filled there, cheaper than
warping a whole drawn image back. ``sheet`` lays named views out as one labelled grid: the
tuners' previews and, as ``composite``, the pipeline's 2x2 debug view.
"""
from __future__ import annotations

import math
from typing import Callable, Mapping, Sequence

import cv2
import numpy as np

from .errors import InputError
from .params.stages import Color, DrawConfig


def line_points(coeffs, height_px: int, samples: int = 48, top_px: float = 0) -> np.ndarray:
    """Return (samples, 2) bird's-eye points (x, y) of x = f(y) from row ``top_px`` to the bottom."""
    ys = np.linspace(top_px, height_px - 1, samples)
    return np.column_stack([np.polyval(coeffs, ys), ys])


def pixel_points(pts: np.ndarray) -> np.ndarray:
    return np.round(pts).astype(np.int32).reshape(-1, 1, 2)


def lane_overlay(image: np.ndarray, left_coeffs, right_coeffs,
                 to_image: Callable[[np.ndarray], np.ndarray] | None,
                 config: DrawConfig = DrawConfig(), height_px: int | None = None,
                 held: bool = False, top_px: float = 0) -> np.ndarray:
    """Return ``image`` with the lane area and lines drawn, the fits mapped by ``to_image``.

    Parameters
    ----------
    image : the frame to draw on (RGB uint8).
    left_coeffs, right_coeffs : bird's-eye pixel fits (None: that line is not drawn, and the
        area only when both exist).
    to_image : the transform of bird's-eye points into ``image`` (``perspective.Transform``):
        ``perspective.inverse`` for the undistorted frame, ``(lens.inverse + perspective).inverse``
        for the raw one; None draws in the bird's-eye view itself.
    config : colours, opacity, line width, samples per line.
    height_px : height of the bird's-eye view (default: the image's).
    held : the lane is held from earlier frames: area and lines in ``config.held_color``.
    top_px : the bird's-eye row the lane is drawn from (``checks.holds_from_px``).
    """
    if isinstance(to_image, np.ndarray):
        raise InputError("lane_overlay: to_image is a transform of points, not a matrix; pass "
                         "perspective.inverse (or perspective.Homography(Minv))")
    h = height_px or image.shape[0]
    out = image.copy()
    mapped = {}
    for side, coeffs in (("left", left_coeffs), ("right", right_coeffs)):
        if coeffs is None:
            continue
        pts = line_points(coeffs, h, config.samples, top_px)
        mapped[side] = to_image(pts) if to_image is not None else pts
    if len(mapped) == 2:
        poly = pixel_points(np.vstack([mapped["left"], mapped["right"][::-1]]))
        # blend only inside the polygon's bounding box: outside it the blend gives the image back
        x, y, bw, bh = cv2.boundingRect(poly)
        x0, y0 = max(0, x - 1), max(0, y - 1)
        x1, y1 = min(out.shape[1], x + bw + 1), min(out.shape[0], y + bh + 1)
        if x0 < x1 and y0 < y1:
            box = out[y0:y1, x0:x1]
            fill = box.copy()
            cv2.fillPoly(fill, [poly], config.held_color if held else config.lane_color,
                         lineType=cv2.LINE_AA, offset=(-x0, -y0))
            cv2.addWeighted(fill, config.lane_alpha, box, 1 - config.lane_alpha, 0, dst=box)
    for side, pts in mapped.items():
        color = config.held_color if held else config.left_color if side == "left" else config.right_color
        cv2.polylines(out, [pixel_points(pts)], False, color, config.line_thickness_px, cv2.LINE_AA)
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


STRAIGHT_M = 10_000.0  # a radius at least this long is reported as "straight"


def measurement_lines(radius_m: float, offset_m: float, lane_width_m: float, found: bool,
                      reason: str = "", held: bool = False, edges: tuple[str, ...] = ()) -> list[str]:
    """Return the text lines reporting a lane's measurements ("no lane found" when not found), with
    "Held: ..." for a lane held from earlier frames and "Asphalt edge, no paint: ..." naming the
    sides in ``edges`` whose line is the road's edge.
    """
    if not found or any(math.isnan(v) for v in (radius_m, offset_m, lane_width_m)):
        return ["No lane found" + (f": {reason}" if reason else "")]
    side = "right" if offset_m > 0 else "left"
    rad = "straight" if radius_m >= STRAIGHT_M else f"{radius_m:,.0f} m"
    lines = [f"Radius of curvature: {rad}",
             f"Vehicle is {abs(offset_m):.2f} m {side} of centre",
             f"Lane width: {lane_width_m:.2f} m"]
    if held:
        lines.append("Held: not seen in this frame")
    if edges:
        lines.append("Asphalt edge, no paint: " + " and ".join(edges))
    return lines


def mask_to_rgb(mask: np.ndarray) -> np.ndarray:
    """Return a 0/255 mask as a grey RGB image."""
    return cv2.cvtColor(mask, cv2.COLOR_GRAY2RGB)


def stacked_masks(masks: Mapping[str, "np.ndarray | None"], names: Sequence[str]) -> np.ndarray:
    """Return up to three 0/255 masks of one size as one RGB view, ``names[0]`` red, ``[1]`` green,
    ``[2]`` blue: overlaps mix (red + green = yellow), a None mask (disabled) leaves its channel black.
    """
    if not 1 <= len(names) <= 3:
        raise InputError(f"stacked_masks: give one to three mask names, got {len(names)}")
    missing = [n for n in names if n not in masks]
    if missing:
        raise InputError(f"stacked_masks: no mask {missing[0]!r}; masks given: {', '.join(masks)}")
    shapes = {masks[n].shape for n in names if masks[n] is not None}
    if len(shapes) != 1:
        raise InputError("stacked_masks: the masks need one common size (and at least one mask)")
    shape = shapes.pop()
    if len(shape) != 2:
        raise InputError(f"stacked_masks: masks are single-channel (H x W), got shape {shape}")
    zero = np.zeros(shape, np.uint8)
    planes = [masks[n] if masks[n] is not None else zero for n in names]
    planes += [zero] * (3 - len(planes))
    return cv2.merge([np.ascontiguousarray(p, dtype=np.uint8) for p in planes])


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
            cv2.polylines(view, [pixel_points(pts)], False, (255, 255, 0), 3, cv2.LINE_AA)
            if search.method == "prior":
                for dx in (-1, 1):
                    band = pts + [dx * prior_margin_px, 0]
                    cv2.polylines(view, [pixel_points(band)], False, (0, 255, 0), 1, cv2.LINE_AA)
    return view


# --------------------------------------------------------------------------- grids of views

Views = Mapping[str, "np.ndarray | None"] | Sequence[tuple[str, "np.ndarray | None"]]
LABEL_COLOR: Color = (255, 255, 0)


def shrink(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Return ``image`` resized down to ``size`` (w, h): halved by area averaging (fast only for an
    exact factor of 2) while at least twice the target, the rest by linear interpolation.
    """
    w, h = size
    while image.shape[1] >= 2 * w and image.shape[0] >= 2 * h:
        image = cv2.resize(image, (image.shape[1] // 2, image.shape[0] // 2),
                           interpolation=cv2.INTER_AREA)
    if (image.shape[1], image.shape[0]) == (w, h):
        return image
    return cv2.resize(image, (w, h), interpolation=cv2.INTER_LINEAR)


def sheet(views: Views, tile_width_px: int = 320, columns: int = 3,
          tile_height_px: int | None = None, interpolation: int | None = None,
          label_at: str = "top", font_scale: float | None = None) -> np.ndarray:
    """Return the named views (RGB images or masks) as one labelled RGB grid; a None view is a grey
    tile labelled "(off)". The views themselves are never drawn on.

    Parameters
    ----------
    views : label -> view, or (label, view) pairs (labels may repeat); laid out row by row.
    tile_width_px, tile_height_px : size of one tile; the height defaults to the aspect of the
        first view that is not None.
    columns : tiles per row (fewer when there are fewer views); an unfilled slot stays black.
    interpolation : OpenCV interpolation of the resize to the tile; None: ``shrink`` (fast).
    label_at : ``"top"``: on a black box at the top left; ``"bottom"``: outlined text at the bottom
        left (for views with their own text at the top).
    font_scale : scale of the label's font (default: ``tile_width_px / 640``).
    """
    items = list(views.items()) if isinstance(views, Mapping) else list(views)
    if not items:
        raise InputError("sheet: no views to show")
    tw = int(tile_width_px)
    if tile_height_px is None:
        shown = [v for _, v in items if v is not None]
        if not shown:
            raise InputError("sheet: every view is off; nothing gives the tiles' aspect")
        h0, w0 = shown[0].shape[:2]
        th = max(1, round(tile_width_px * h0 / w0))
    else:
        th = int(tile_height_px)
    if label_at not in ("top", "bottom"):
        raise InputError(f"sheet: label_at is 'top' or 'bottom', not {label_at!r}")
    cols = max(1, min(columns, len(items)))
    rows = -(-len(items) // cols)
    out = np.zeros((rows * th, cols * tw, 3), np.uint8)
    scale = font_scale if font_scale is not None else tw / 640
    thick = max(1, round(2 * scale))
    for i, (label, img) in enumerate(items):
        if img is None:
            tile = np.full((th, tw, 3), 48, np.uint8)
            label = f"{label} (off)"
        else:
            tile = (shrink(img, (tw, th)) if interpolation is None
                    else cv2.resize(img, (tw, th), interpolation=interpolation))
            if tile.ndim == 2:
                tile = cv2.cvtColor(tile, cv2.COLOR_GRAY2RGB)
            elif tile is img:
                tile = tile.copy()  # the label is drawn on the tile, never on the caller's view
        _label(tile, label, label_at, scale, thick)
        r, c = divmod(i, cols)
        out[r * th:(r + 1) * th, c * tw:(c + 1) * tw] = tile
    return out


def _label(tile: np.ndarray, text: str, at: str, scale: float, thick: int) -> None:
    """Write ``text`` onto ``tile`` in place: on a black box at the top, or outlined at the bottom."""
    font = cv2.FONT_HERSHEY_SIMPLEX
    if at == "top":
        (w, h), base = cv2.getTextSize(text, font, scale, thick)
        cv2.rectangle(tile, (0, 0), (w + 8, h + base + 8), (0, 0, 0), -1)
        cv2.putText(tile, text, (4, h + 4), font, scale, LABEL_COLOR, thick, cv2.LINE_AA)
        return
    org = (10, tile.shape[0] - 15)
    cv2.putText(tile, text, org, font, scale, (0, 0, 0), 2 * thick, cv2.LINE_AA)
    cv2.putText(tile, text, org, font, scale, LABEL_COLOR, thick, cv2.LINE_AA)


def composite(panels: Sequence[tuple[str, np.ndarray]], size: tuple[int, int]) -> np.ndarray:
    """Return the ``sheet`` of the first four panels (RGB or masks) as a 2x2 grid of ``size`` (w, h),
    labelled at the bottom left (the result panel has its own text at the top); black where none.
    """
    w, h = size
    out = np.zeros((h, w, 3), np.uint8)
    if not panels:
        return out
    grid = sheet(list(panels)[:4], w // 2, 2, tile_height_px=h // 2,
                 interpolation=cv2.INTER_AREA, label_at="bottom", font_scale=0.8)
    if grid.shape[:2] == (h, w):
        return grid
    out[:grid.shape[0], :grid.shape[1]] = grid
    return out
