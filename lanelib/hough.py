"""The basic lane-line pipeline: colour selection, Canny, region of interest, Hough, one line a side.

One frame goes

    RGB -> white/yellow mask (HLS) -> masked grayscale -> Gaussian blur -> Canny edges
        -> edges inside the region of interest -> probabilistic Hough segments
        -> split into left (negative slope) and right (positive slope) by the sign of dy/dx
        -> each side reduced to one straight line by a length-weighted fit of x(y),
           drawn from the bottom row up to the top of the region.

Slopes are dy/dx in image coordinates (y grows down), so the left lane line, whose x falls as
y grows, has a negative slope. The stage functions work on plain arrays, for notebooks and tests;
``HoughLaneFinder`` runs them from one ``HoughConfig`` on single images, and ``HoughTracker``
adds smoothing across video frames and holds a lost line for a few frames. Nothing in the
per-frame path raises on the frame's content: a side without a line says why in ``reason``.
Its batch runs (a folder of images, a video) are ``batch.hough_images`` and ``batch.hough_video``.
"""
from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import cv2
import numpy as np

from . import io
from .params.stages import HoughConfig, Triple

LEFT_COLOR_RGB: Triple = (255, 40, 40)
RIGHT_COLOR_RGB: Triple = (40, 120, 255)


@dataclass(frozen=True)
class LaneLine:
    """One straight lane line in pixels, from the bottom row up to the top of the region."""

    x_bottom_px: float
    y_bottom_px: float
    x_top_px: float
    y_top_px: float

    def points(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """Return the (bottom, top) endpoints rounded to pixel coordinates (x, y)."""
        return ((round(self.x_bottom_px), round(self.y_bottom_px)),
                (round(self.x_top_px), round(self.y_top_px)))


@dataclass(frozen=True, eq=False)
class HoughStages:
    """The intermediate images and segments of one frame (uint8 masks are 0/255).

    Segments are (N, 4) int32 arrays of (x1, y1, x2, y2) pixels.
    """

    color_mask: np.ndarray
    gray: np.ndarray
    blurred: np.ndarray
    edges: np.ndarray
    roi_edges: np.ndarray
    segments: np.ndarray
    left_segments: np.ndarray
    right_segments: np.ndarray


@dataclass(frozen=True, eq=False)
class HoughResult:
    """The lines found in one frame, how many segments fed each, and why a side is missing.

    ``left`` and ``right`` are None when that side has no line. In video, a line can be held from
    an earlier frame (``left_held`` / ``right_held``); ``reason`` then says so. ``reason`` is empty
    when both lines were measured in this frame. ``stages`` is set when asked for.
    """

    left: LaneLine | None
    right: LaneLine | None
    n_left_segments: int
    n_right_segments: int
    reason: str = ""
    left_held: bool = False
    right_held: bool = False
    stages: HoughStages | None = None

    @property
    def left_found(self) -> bool:
        """Whether a left line is reported (measured, or held in video)."""
        return self.left is not None

    @property
    def right_found(self) -> bool:
        """Whether a right line is reported (measured, or held in video)."""
        return self.right is not None

    def row(self) -> dict:
        """Return the result as a flat row: found flags, x at the bottom and top (px), reason."""
        def ends(line: LaneLine | None) -> tuple[float | None, float | None]:
            return (None, None) if line is None else (round(line.x_bottom_px, 1), round(line.x_top_px, 1))

        (left_bottom, left_top), (right_bottom, right_top) = ends(self.left), ends(self.right)
        return {"left_found": self.left_found, "right_found": self.right_found,
                "left_x_bottom": left_bottom, "left_x_top": left_top,
                "right_x_bottom": right_bottom, "right_x_top": right_top,
                "left_held": self.left_held, "right_held": self.right_held, "reason": self.reason}


# --------------------------------------------------------------------------- stage functions

def select_white_yellow(rgb: np.ndarray, white_hls_lo: Triple, white_hls_hi: Triple,
                        yellow_hls_lo: Triple, yellow_hls_hi: Triple) -> np.ndarray:
    """Return the 0/255 mask of pixels inside the white or the yellow HLS range (OpenCV units)."""
    hls = cv2.cvtColor(rgb, cv2.COLOR_RGB2HLS)
    white = cv2.inRange(hls, np.array(white_hls_lo), np.array(white_hls_hi))
    yellow = cv2.inRange(hls, np.array(yellow_hls_lo), np.array(yellow_hls_hi))
    return cv2.bitwise_or(white, yellow)


def grayscale(rgb: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Return the uint8 grayscale of ``rgb``, zero outside the 0/255 ``mask`` when one is given."""
    gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    return gray if mask is None else cv2.bitwise_and(gray, gray, mask=mask)


def blur(gray: np.ndarray, kernel_px: int) -> np.ndarray:
    """Return ``gray`` smoothed by a Gaussian of odd side ``kernel_px`` (sigma from the size)."""
    return cv2.GaussianBlur(gray, (kernel_px, kernel_px), 0)


def canny(gray: np.ndarray, low: float, high: float) -> np.ndarray:
    """Return the 0/255 Canny edge mask with hysteresis thresholds ``low`` and ``high``."""
    return cv2.Canny(gray, low, high)


def roi_mask(shape: tuple[int, ...], roi_frac) -> np.ndarray:
    """Return the 0/255 mask (H x W) of the polygon ``roi_frac`` of (x, y) image fractions."""
    h, w = shape[:2]
    pts = np.rint(np.asarray(roi_frac, dtype=np.float64) * (w - 1, h - 1)).astype(np.int32)
    mask = np.zeros((h, w), np.uint8)
    cv2.fillPoly(mask, [pts], 255)
    return mask


def roi_top_px(height_px: int, roi_frac) -> float:
    """Return the row (px) of the topmost vertex of the region of interest."""
    return min(y for _, y in roi_frac) * (height_px - 1)


def hough_segments(edges: np.ndarray, rho_px: float, theta_deg: float, threshold_votes: int,
                   min_line_length_px: float, max_line_gap_px: float) -> np.ndarray:
    """Return the probabilistic Hough segments of a 0/255 edge mask as an (N, 4) int32 array.

    Each row is (x1, y1, x2, y2) in pixels; no segments gives a (0, 4) array.
    """
    lines = cv2.HoughLinesP(edges, rho_px, math.radians(theta_deg), threshold_votes,
                            minLineLength=min_line_length_px, maxLineGap=max_line_gap_px)
    return np.zeros((0, 4), np.int32) if lines is None else lines.reshape(-1, 4)


def split_by_slope(segments: np.ndarray, min_abs_slope: float) -> tuple[np.ndarray, np.ndarray]:
    """Return (left, right) segments: slope dy/dx <= -min_abs_slope and >= +min_abs_slope.

    Vertical segments (dx = 0) have no slope sign and belong to neither side.
    """
    s = segments.astype(np.float64)
    dx, dy = s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]
    slope = np.divide(dy, dx, out=np.zeros_like(dy), where=dx != 0)
    steep = (np.abs(slope) >= min_abs_slope) & (dx != 0)
    return segments[steep & (slope < 0)], segments[steep & (slope > 0)]


def fit_side(segments: np.ndarray, y_bottom_px: float, y_top_px: float) -> LaneLine | None:
    """Return the length-weighted least-squares line x(y) through the segments' endpoints.

    Both endpoints of a segment weigh its length (px), so long segments dominate short noise.
    The line runs from ``y_bottom_px`` to ``y_top_px``; None when there are no segments of
    non-zero length or they span no height (a straight x(y) fit needs two rows).
    """
    s = segments.astype(np.float64).reshape(-1, 4)
    length = np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])
    if not length.any():
        return None
    x = np.concatenate([s[:, 0], s[:, 2]])
    y = np.concatenate([s[:, 1], s[:, 3]])
    w = np.concatenate([length, length])
    y_mean = np.average(y, weights=w)
    x_mean = np.average(x, weights=w)
    var_y = np.sum(w * (y - y_mean) ** 2)
    if var_y <= 1e-9 * w.sum():
        return None
    dxdy = np.sum(w * (y - y_mean) * (x - x_mean)) / var_y
    return LaneLine(float(x_mean + dxdy * (y_bottom_px - y_mean)), float(y_bottom_px),
                    float(x_mean + dxdy * (y_top_px - y_mean)), float(y_top_px))


def draw_lines(rgb: np.ndarray, lines, color_rgb: Triple, thickness_px: int = 2) -> np.ndarray:
    """Return a copy of ``rgb`` with ``lines`` drawn on it.

    ``lines`` are LaneLine records or (x1, y1, x2, y2) rows (e.g. Hough segments), in pixels.
    """
    out = rgb.copy()
    for line in lines:
        if isinstance(line, LaneLine):
            p, q = line.points()
        else:
            x1, y1, x2, y2 = (int(v) for v in line)
            p, q = (x1, y1), (x2, y2)
        cv2.line(out, p, q, color_rgb, thickness_px, cv2.LINE_AA)
    return out


def annotate(rgb: np.ndarray, result: HoughResult, opacity: float = 0.7,
             thickness_px: int = 10) -> np.ndarray:
    """Return a copy of ``rgb`` with the result's left and right lines blended over it.

    Left is red, right is blue; ``opacity`` in 0..1 is the weight of the drawn lines. Only the
    band of rows the lines cross is blended, which costs a fraction of a full-frame blend.
    """
    out = io.check_rgb(rgb).copy()
    lines = [(line, color) for line, color in ((result.left, LEFT_COLOR_RGB),
                                               (result.right, RIGHT_COLOR_RGB)) if line is not None]
    if not lines:
        return out
    top_px = min(min(line.y_top_px, line.y_bottom_px) for line, _ in lines)
    top = min(max(0, math.floor(top_px) - thickness_px), out.shape[0] - 1)
    band = out[top:]
    overlay = band.copy()
    for line, color in lines:
        (x0, y0), (x1, y1) = line.points()
        cv2.line(overlay, (x0, y0 - top), (x1, y1 - top), color, thickness_px, cv2.LINE_AA)
    cv2.addWeighted(overlay, opacity, band, 1.0 - opacity, 0.0, dst=band)
    return out


# --------------------------------------------------------------------------- one image

@dataclass(frozen=True, eq=False)
class _Region:
    """The region of interest for one image size: its bounding box and its mask inside the box."""

    rows: slice
    cols: slice
    mask: np.ndarray
    top_px: float

    @classmethod
    def make(cls, shape: tuple[int, ...], roi_frac) -> "_Region":
        full = roi_mask(shape, roi_frac)
        x, y, w, h = cv2.boundingRect(full)  # fillPoly paints a pixel even for a flat polygon
        rows, cols = slice(y, y + h), slice(x, x + w)
        return cls(rows, cols, np.ascontiguousarray(full[rows, cols]), roi_top_px(shape[0], roi_frac))

    def paste(self, box_image: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
        """Return a zero H x W image holding ``box_image`` at the box's place."""
        full = np.zeros(shape[:2] + box_image.shape[2:], box_image.dtype)
        full[self.rows, self.cols] = box_image
        return full


class HoughLaneFinder:
    """Finds the left and right lane lines in single images with one ``HoughConfig``.

    Only the bounding box of the region of interest is processed. The box and the region's mask
    depend only on the configuration and the image size, so they are made once for each size met
    and kept; ``process`` keeps no other state between frames.

    Examples
    --------
    >>> from lanelib import data, io
    >>> result = HoughLaneFinder().process(io.read_image(data.bundled("test_images") / "straight_1.jpg"))
    >>> result.left is not None and result.right is not None
    True
    """

    def __init__(self, config: HoughConfig = HoughConfig()):
        self.config = config
        self._regions: dict[tuple[int, int], _Region] = {}

    def _region(self, shape: tuple[int, ...]) -> _Region:
        key = (int(shape[0]), int(shape[1]))
        if key not in self._regions:
            self._regions[key] = _Region.make(key, self.config.roi_frac)
        return self._regions[key]

    def process(self, rgb: np.ndarray, keep_stages: bool = False) -> HoughResult:
        """Return the lines found in one RGB uint8 frame (and its stage images if asked).

        The stage images are full-frame size and zero outside the region's bounding box.

        Raises
        ------
        InputError
            If ``rgb`` is not an H x W x 3 uint8 array. The frame's content never raises.
        """
        c = self.config
        rgb = io.check_rgb(rgb)
        region = self._region(rgb.shape)
        box = rgb[region.rows, region.cols]
        color = select_white_yellow(box, c.white_hls_lo, c.white_hls_hi, c.yellow_hls_lo, c.yellow_hls_hi)
        gray = grayscale(box, color)
        blurred = blur(gray, c.blur_kernel_px)
        edges = canny(blurred, c.canny_low, c.canny_high)
        roi_edges = cv2.bitwise_and(edges, region.mask)
        segments = hough_segments(roi_edges, c.rho_px, c.theta_deg, c.threshold_votes,
                                  c.min_line_length_px, c.max_line_gap_px)
        segments += np.array([region.cols.start, region.rows.start] * 2, np.int32)
        left_segs, right_segs = split_by_slope(segments, c.min_abs_slope)
        y_bottom = rgb.shape[0] - 1
        left = fit_side(left_segs, y_bottom, region.top_px)
        right = fit_side(right_segs, y_bottom, region.top_px)
        # a segment with a slope spans two rows, so a side without a line has no segments
        reasons = [f"{side}: no segments with {sign} slope (|dy/dx| >= {c.min_abs_slope:g}) "
                   "in the region" for side, sign, line in (("left", "negative", left),
                                                           ("right", "positive", right))
                   if line is None]
        stages = None
        if keep_stages:
            color, gray, blurred, edges, roi_edges = (region.paste(im, rgb.shape) for im in
                                                      (color, gray, blurred, edges, roi_edges))
            stages = HoughStages(color, gray, blurred, edges, roi_edges, segments, left_segs, right_segs)
        return HoughResult(left, right, len(left_segs), len(right_segs), "; ".join(reasons),
                           stages=stages)


# --------------------------------------------------------------------------- video

class _SideTrack:
    """Exponential smoothing of one side's line endpoints, with a hold of lost lines."""

    def __init__(self, alpha: float, hold_frames: int):
        self.alpha = alpha
        self.hold_frames = hold_frames
        self.line: LaneLine | None = None
        self.missed = 0

    def update(self, measured: LaneLine | None) -> tuple[LaneLine | None, bool]:
        """Return (line to report, whether it is held from an earlier frame)."""
        if measured is not None:
            self.line = measured if self.line is None else self._blend(measured)
            self.missed = 0
            return self.line, False
        self.missed += 1
        if self.line is not None and self.missed > self.hold_frames:
            self.line = None
        return self.line, self.line is not None

    def _blend(self, new: LaneLine) -> LaneLine:
        a, old = self.alpha, self.line
        return LaneLine(a * new.x_bottom_px + (1 - a) * old.x_bottom_px, new.y_bottom_px,
                        a * new.x_top_px + (1 - a) * old.x_top_px, new.y_top_px)


def settle_frames(config: HoughConfig) -> int:
    """Return the frames a ``HoughTracker`` is run before a Dask segment of a video (its warm-up).

    The smoothing weighs where the tracker started by ``(1 - smoothing_alpha) ** n`` after ``n``
    frames: below 2**-53, a double's precision, two trackers that started apart agree to the last
    bit (then stay so), about 103 frames at the default 0.3; a fifth more for the rounding on the
    way (on the bundled clips two starts agreed after 81 to 106 frames). A joint that has not
    settled all the same is run again (``cluster.settle_joints``).
    """
    a = config.smoothing_alpha
    n = 0 if a >= 1.0 else math.ceil(53 * math.log(2.0) / -math.log1p(-a))
    return max(1, math.ceil(1.2 * n))


class HoughTracker:
    """Finds lane lines frame after frame: smooths each line and holds a lost one for a while.

    Each side's endpoints are smoothed exponentially with ``config.smoothing_alpha``; a side
    with no line in a frame keeps its last line for up to ``config.hold_frames`` frames (reported
    as held), then reports none until it is found again. A change of frame size starts afresh.
    """

    def __init__(self, config: HoughConfig = HoughConfig()):
        self.finder = HoughLaneFinder(config)
        self._shape: tuple[int, ...] | None = None
        self.reset()

    def reset(self) -> None:
        """Forget all earlier frames."""
        c = self.finder.config
        self._left = _SideTrack(c.smoothing_alpha, c.hold_frames)
        self._right = _SideTrack(c.smoothing_alpha, c.hold_frames)

    def state_key(self) -> bytes:
        """Return a fingerprint of the state the next frames' results depend on (each side's
        smoothed line and missed frames, the frame shape): equal keys, the same results."""
        state = (self._shape, [(s.line, s.missed) for s in (self._left, self._right)])
        return hashlib.sha256(repr(state).encode()).digest()

    def process(self, rgb: np.ndarray, keep_stages: bool = False) -> HoughResult:
        """Return the smoothed (or held) lines for the next frame of a video."""
        measured = self.finder.process(rgb, keep_stages)
        if rgb.shape != self._shape:
            self._shape = rgb.shape
            self.reset()
        left, left_held = self._left.update(measured.left)
        right, right_held = self._right.update(measured.right)
        reasons = [measured.reason] if measured.reason else []
        reasons += [f"{side} line held from the last good frame ({track.missed} missed)"
                    for side, is_held, track in (("left", left_held, self._left),
                                                 ("right", right_held, self._right)) if is_held]
        return HoughResult(left, right, measured.n_left_segments, measured.n_right_segments,
                           "; ".join(reasons), left_held, right_held, measured.stages)
