"""Colour and gradient thresholds that turn a road image into a binary mask of lane-line pixels.

Every mask is a ``uint8`` array of 0 and 255. ``ThresholdConfig`` holds one record per named
mask and a ``rule`` combining them, a boolean expression over mask names with ``|``, ``&``, ``~``
and parentheses, e.g. ``"yellow | white | (sobel_x & s_channel)"``. A disabled mask drops out of
the rule (it neither adds pixels to an ``|`` nor removes them through an ``&``), so the tuner's
toggles do what a user expects. Colour spaces: ``rgb``, ``hls``, ``hsv``, ``luv``, ``lab`` and
``gray``; channels are named by letter (``h``, ``l``, ``s`` ...), scaled as OpenCV's 8-bit
conversions do (hue 0-179, the rest 0-255).
"""
from __future__ import annotations

import ast
import functools
import math
from dataclasses import dataclass, field
from typing import Callable

import cv2
import numpy as np

from .errors import ConfigError
from .params.masks import (SPACE_CHANNELS, ChannelMask, ColorRange, SobelMask, ThresholdConfig, TopHatMask,
                           check_channel, compile_rule, mask_names)

# OpenCV's conversion from RGB into each colour space (None: the image itself)
_CONVERSIONS = {"rgb": None, "hls": cv2.COLOR_RGB2HLS, "hsv": cv2.COLOR_RGB2HSV, "luv": cv2.COLOR_RGB2Luv,
                "lab": cv2.COLOR_RGB2Lab, "gray": cv2.COLOR_RGB2GRAY}
# colour space -> (its conversion, the letters of its channels)
SPACES: dict[str, tuple[int | None, str]] = {s: (_CONVERSIONS[s], letters)
                                             for s, letters in SPACE_CHANNELS.items()}
# rows of a band that ``Channels.space`` converts and splits while the band is still in the cache
BAND_ROWS = 180


def make_clahe(config: ThresholdConfig, size: tuple[int, int]) -> cv2.CLAHE | None:
    """Return the CLAHE of ``config`` for images of ``size`` (w, h) px, or None when it is off: tiles of
    about ``clahe_tile_px`` px (at least one each way). Make it once per configuration and size (as
    ``LanePipeline`` does) and pass it to ``combine`` and ``masks``.
    """
    if not config.clahe:
        return None
    w, h = size
    grid = (max(1, round(w / config.clahe_tile_px)), max(1, round(h / config.clahe_tile_px)))
    return cv2.createCLAHE(clipLimit=float(config.clahe_clip_limit), tileGridSize=grid)


def equalize_lightness(rgb: np.ndarray, clahe: cv2.CLAHE) -> np.ndarray:
    """Return ``rgb`` with ``clahe`` applied to its lightness (L of LAB), as RGB uint8."""
    lab = cv2.cvtColor(rgb, cv2.COLOR_RGB2Lab)
    lab[..., 0] = clahe.apply(np.ascontiguousarray(lab[..., 0]))
    return cv2.cvtColor(lab, cv2.COLOR_Lab2RGB)


def mask_input(rgb: np.ndarray, config: ThresholdConfig, clahe: cv2.CLAHE | None = None) -> np.ndarray:
    """Return the image the masks of ``config`` look at: ``rgb``, or (``config.clahe``) its
    equalised lightness; ``clahe`` passes the CLAHE made once by ``make_clahe``."""
    if not config.clahe:
        return rgb
    if clahe is None:
        clahe = make_clahe(config, (rgb.shape[1], rgb.shape[0]))
    return equalize_lightness(rgb, clahe)


# --------------------------------------------------------------------------- channels

class Channels:
    """Colour-space conversions of one RGB image, their channels and top-hats, each computed at most
    once."""

    def __init__(self, rgb: np.ndarray):
        self.rgb = rgb
        self._spaces: dict[str, np.ndarray] = {"rgb": rgb}
        self._planes: dict[str, list | tuple] = {}  # each space's channels, split once
        self._tophats: dict[tuple[str, str, int], tuple[np.ndarray, np.ndarray]] = {}

    def space(self, name: str) -> np.ndarray:
        """Return the image converted to colour space ``name``. A three-channel space is converted
        ``BAND_ROWS`` rows at a time, each band split into the planes ``channel`` reads while it is
        still in the cache: the same planes, without reading the whole conversion back from memory."""
        if name not in self._spaces:
            code, letters = SPACES[name]
            if len(letters) < 3:
                self._spaces[name] = cv2.cvtColor(self.rgb, code)
                return self._spaces[name]
            img = self._spaces[name] = np.empty_like(self.rgb)
            planes = self._planes[name] = [np.empty(img.shape[:2], img.dtype) for _ in letters]
            for r in range(0, len(img), BAND_ROWS):
                rows = slice(r, r + BAND_ROWS)
                cv2.split(cv2.cvtColor(self.rgb[rows], code, dst=img[rows]), [p[rows] for p in planes])
        return self._spaces[name]

    def cut(self, pieces: list[tuple[slice, slice]], join: Callable[[list[np.ndarray]], np.ndarray]
            ) -> "Channels":
        """Return the ``Channels`` of the ``pieces`` (row and column slices) of this image joined by
        ``join`` (e.g. ``np.hstack``), every colour space converted so far cut alike, not converted again.
        """
        out = Channels(join([self.rgb[c] for c in pieces]))
        for name, img in self._spaces.items():
            if name != "rgb":
                out._spaces[name] = join([img[c] for c in pieces])
        return out

    def tophat(self, spec: TopHatMask) -> tuple[np.ndarray, np.ndarray]:
        """Return how much each pixel is brighter than its surroundings (uint8 levels of
        ``spec.channel``), and the surroundings: a horizontal white top-hat ``spec.width_px`` wide,
        made once for every mask and reader of that channel and width.

        Examples
        --------
        >>> road = np.full((1, 9, 3), 80, np.uint8); road[0, 4] = 200
        >>> Channels(road).tophat(TopHatMask(space="gray", channel="y", width_px=5))[0].tolist()
        [[0, 0, 0, 0, 120, 0, 0, 0, 0]]
        """
        key = (spec.space, spec.channel, spec.width_px)
        if key not in self._tophats:
            values = self.channel(spec.space, spec.channel)
            background = morph(values, "open", spec.width_px, 1)
            self._tophats[key] = (cv2.subtract(values, background), background)
        return self._tophats[key]

    def channel(self, space: str, channel: str) -> np.ndarray:
        """Return one channel (uint8, H x W) of the image in ``space`` (the space's channels are split
        once: a split costs about what one ``cv2.extractChannel`` does)."""
        img = self.space(space)
        if img.ndim == 2:
            return img
        if space not in self._planes:
            self._planes[space] = cv2.split(img)
        return self._planes[space][SPACES[space][1].index(channel)]


def channel(rgb: np.ndarray, space: str, name: str) -> np.ndarray:
    """Return channel ``name`` of ``rgb`` in colour space ``space`` (uint8, H x W)."""
    check_channel(space, name, "channel")
    return Channels(rgb).channel(space, name)


# --------------------------------------------------------------------------- masks

def in_range(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """Return a 0/255 mask of ``values`` within [low, high]."""
    return cv2.inRange(values, float(low), float(high))


def channel_mask(rgb: np.ndarray | Channels, spec: ChannelMask) -> np.ndarray:
    """Return the 0/255 mask of ``spec`` on an RGB image."""
    ch = rgb if isinstance(rgb, Channels) else Channels(rgb)
    return _open(in_range(ch.channel(spec.space, spec.channel), spec.low, spec.high), spec.open_px)


def color_range_mask(rgb: np.ndarray | Channels, spec: ColorRange) -> np.ndarray:
    """Return the 0/255 mask of pixels inside the colour box ``spec``: the AND of each channel's range,
    a channel whose range is the whole 0-255 left out (``cv2.inRange`` on one channel at a time costs
    far less than on three).
    """
    ch = rgb if isinstance(rgb, Channels) else Channels(rgb)
    m = None
    for name, low, high in zip(SPACES[spec.space][1], spec.low, spec.high):
        if low > 0 or high < 255:
            inside = in_range(ch.channel(spec.space, name), low, high)
            m = inside if m is None else cv2.bitwise_and(m, inside)
    if m is None:
        m = np.full(ch.rgb.shape[:2], 255, np.uint8)
    return _open(m, spec.open_px)


def morph(image: np.ndarray, op: str, width_px: int, height_px: int) -> np.ndarray:
    """Return ``image`` (a mask or grey image) opened (``op="open"``) or closed (``"close"``) by a
    width x height rectangle. OpenCV anchors an even kernel half a pixel off centre for both passes,
    which shifts the result a pixel; with the second pass's anchor mirrored, a shape wider than the
    kernel comes back in place for every size. A kernel one row tall on a uint8 image runs as
    ``row_extreme`` (OpenCV's result, in time growing with log2 of the width, not with the width).
    """
    if op not in ("open", "close"):
        raise ValueError(f"morph: op {op!r} must be 'open' or 'close'")
    first = (width_px // 2, height_px // 2)
    second = (width_px - 1 - first[0], height_px - 1 - first[1])
    if height_px == 1 and image.ndim == 2 and image.dtype == np.uint8:
        low = op == "open"  # an opening erodes first, a closing dilates first
        return row_extreme(row_extreme(image, width_px, first[0], low), width_px, second[0], not low)
    kernel = np.ones((height_px, width_px), np.uint8)
    if op == "open":
        return cv2.dilate(cv2.erode(image, kernel, anchor=first), kernel, anchor=second)
    return cv2.erode(cv2.dilate(image, kernel, anchor=first), kernel, anchor=second)


def row_extreme(image: np.ndarray, width_px: int, anchor_px: int, low: bool) -> np.ndarray:
    """Return ``cv2.erode`` (``low``) or ``cv2.dilate`` of a uint8 image by a kernel one row tall and
    ``width_px`` wide anchored at ``anchor_px``: each pixel's min (max) over the row's pixels from
    ``anchor_px`` left of it to ``width_px - 1 - anchor_px`` right, those beyond the edge left out.

    The row is padded with the value that changes no min (max); each step then takes the min (max)
    of two shifted runs, doubling their length, so about log2(width) whole-image passes replace
    OpenCV's one pass per kernel column.

    Examples
    --------
    >>> row = np.array([[5, 1, 7, 3, 9, 2]], np.uint8)
    >>> row_extreme(row, 3, 1, low=True).tolist()
    [[1, 1, 1, 3, 2, 2]]
    """
    op, border = (cv2.min, 255) if low else (cv2.max, 0)
    h, w = image.shape
    run = cv2.copyMakeBorder(image, 0, 0, anchor_px, width_px - 1 - anchor_px, cv2.BORDER_CONSTANT,
                             value=border)
    spare = np.empty_like(run)
    n, cols = 1, run.shape[1]  # ``run`` holds each pixel's extreme over ``n`` pixels from it, ``cols`` valid
    while n < width_px:
        step = min(n, width_px - n)
        cols -= step
        n += step
        dst = np.empty((h, w), np.uint8) if n == width_px else spare[:, :cols]
        run, spare = op(run[:, :cols], run[:, step:step + cols], dst=dst), run
    return run if width_px > 1 else np.ascontiguousarray(run[:, :w])


def _open(m: np.ndarray, size: int) -> np.ndarray:
    """Return mask ``m`` opened with a square kernel of ``size`` px (unchanged for size 0 or 1)."""
    if size <= 1:
        return m
    return morph(m, "open", size, size)


def _sobel_step_scale(kernel_px: int) -> float:
    """Return the Sobel response to a unit step edge for a kernel size (1 gives 1)."""
    kx, ky = cv2.getDerivKernels(1, 0, kernel_px)
    return float(np.abs(kx).sum() / 2 * ky.sum())


def sobel(gray: np.ndarray, kind: str, kernel_px: int = 3) -> np.ndarray:
    """Return the gradient of a channel as float32: step height (0-255) for x/y/mag, radians for dir."""
    scale = 1.0 / _sobel_step_scale(kernel_px)
    if kind in ("x", "y"):
        dx, dy = (1, 0) if kind == "x" else (0, 1)
        return np.abs(cv2.Sobel(gray, cv2.CV_32F, dx, dy, ksize=kernel_px, scale=scale))
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=kernel_px, scale=scale)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=kernel_px, scale=scale)
    if kind == "mag":
        return cv2.magnitude(gx, gy)
    if kind == "dir":
        return cv2.phase(np.abs(gx), np.abs(gy))
    raise ConfigError(f"sobel: kind {kind!r} must be x, y, mag or dir")


def sobel_mask(rgb: np.ndarray | Channels, spec: SobelMask) -> np.ndarray:
    """Return the 0/255 mask of pixels whose gradient ``spec.kind`` lies in [low, high]."""
    ch = rgb if isinstance(rgb, Channels) else Channels(rgb)
    gray = ch.channel(spec.space, spec.channel)
    if spec.kind in ("x", "y") and spec.kernel_px in (1, 3):
        return _integer_sobel_mask(gray, spec)
    return in_range(sobel(gray, spec.kind, spec.kernel_px), spec.low, spec.high)


def _integer_sobel_mask(gray: np.ndarray, spec: SobelMask) -> np.ndarray:
    """Return ``sobel_mask`` for kind x or y and kernel 1 or 3 from the integer Sobel (int16), about 8x
    faster: the float gradient is exactly the integer one times 1 or 1/4, so [low, high] (compared
    as float32, as ``cv2.inRange`` does) becomes an integer range of |s|.
    """
    scale = 1.0 / _sobel_step_scale(spec.kernel_px)
    lo = max(0, math.ceil(float(np.float32(spec.low)) / scale))
    hi = min(32767, math.floor(float(np.float32(spec.high)) / scale))
    dx, dy = (1, 0) if spec.kind == "x" else (0, 1)
    s = cv2.Sobel(gray, cv2.CV_16S, dx, dy, ksize=spec.kernel_px)
    if hi < lo:
        return np.zeros(gray.shape, np.uint8)
    if lo == 0:
        return cv2.inRange(s, -hi, hi)
    return cv2.bitwise_or(cv2.inRange(s, lo, hi), cv2.inRange(s, -hi, -lo))


def tophat_mask(rgb: np.ndarray | Channels, spec: TopHatMask) -> np.ndarray:
    """Return the 0/255 mask of pixels brighter than their surroundings by [low, high] levels
    (and, with ``spec.ratio``, by that multiple of the surroundings; see ``TopHatMask``)."""
    tophat, background = (rgb if isinstance(rgb, Channels) else Channels(rgb)).tophat(spec)
    if spec.ratio <= 0 and spec.max_background >= 255:
        out = in_range(tophat, spec.low, spec.high)
    else:  # scaled where that gives the table (``_scales_exactly``): half a table lookup's time
        least = _scaled_up(background, spec) if _scales_exactly(spec) else cv2.LUT(background, _least_tophat(spec))
        out = cv2.compare(tophat, least, cv2.CMP_GE)
        if spec.high < 255:
            out = cv2.bitwise_and(out, in_range(tophat, 0, spec.high))
    if spec.min_width_px > 1:  # an opening 1 x k across the road
        out = rows_opened(out, spec.min_width_px, inplace=True)  # ``out`` is this call's own
    return out


def rows_opened(mask: np.ndarray, width_px: int, inplace: bool = False) -> np.ndarray:
    """Return ``morph(mask, "open", width_px, 1)`` of a uint8 mask, opening only its rows that hold a
    pixel: a kernel one row tall leaves an empty row empty, and a top-hat's mask holds pixels on a
    fraction of its rows. With ``inplace`` they are opened in ``mask`` itself (no new mask to clear)."""
    rows = np.flatnonzero(cv2.reduce(mask, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S))
    if len(rows) == len(mask):
        return morph(mask, "open", width_px, 1)
    out = mask if inplace else np.zeros_like(mask)
    if len(rows):
        out[rows] = morph(mask[rows], "open", width_px, 1)
    return out


# added to a scaled level before ``cv2.convertScaleAbs`` rounds it to the nearest: the level
# rounded up, but for a fraction under 2**-12 (exact in float32 at every level below 256)
ROUND_UP = 0.5 - 2.0 ** -12


def _scaled_up(levels: np.ndarray, spec: TopHatMask) -> np.ndarray:
    """Return max(``low``, ``ratio`` times ``levels`` rounded up by ``ROUND_UP``), uint8 saturated."""
    return cv2.max(cv2.convertScaleAbs(levels, alpha=spec.ratio, beta=ROUND_UP), spec.low)


@functools.lru_cache(maxsize=32)
def _scales_exactly(spec: TopHatMask) -> bool:
    """Return whether ``_scaled_up`` gives ``_least_tophat``'s table at every level 0-255 in rows 1 to
    128 px wide (OpenCV's vector loop and its scalar tail of every length); not where
    ``max_background`` is below 255, nor where a scaled level falls within 2**-12 above an integer."""
    table = _least_tophat(spec)[:, None]
    levels = np.repeat(np.arange(256, dtype=np.uint8)[:, None], 128, axis=1)  # level i on row i
    return all(np.array_equal(_scaled_up(levels[:, :w], spec), np.repeat(table, w, axis=1))
               for w in range(1, 129))


@functools.lru_cache(maxsize=32)
def _least_tophat(spec: TopHatMask) -> np.ndarray:
    """Return the least top-hat a pixel needs for each background level 0-255 (uint8, 256), cached
    per (frozen) mask record: max(low, ratio * background) rounded up, 255 above ``max_background``.
    The cap is exact: no top-hat reaches 255 there, nor where ratio * background > 255 - background.
    """
    levels = np.arange(256, dtype=np.float64)
    least = np.maximum(spec.low, np.ceil(spec.ratio * levels - 1e-9))
    least[levels > spec.max_background] = 255
    table = np.minimum(least, 255).astype(np.uint8)
    table.flags.writeable = False
    return table


MASK_FUNCTIONS: dict[type, Callable] = {
    ChannelMask: channel_mask,
    ColorRange: color_range_mask,
    SobelMask: sobel_mask,
    TopHatMask: tophat_mask,
}


def mask(rgb: np.ndarray | Channels, spec) -> np.ndarray:
    """Return the 0/255 mask of any mask record (ChannelMask, ColorRange, SobelMask, TopHatMask)."""
    return MASK_FUNCTIONS[type(spec)](rgb, spec)


# --------------------------------------------------------------------------- rule


def _evaluate(node: ast.expr, get: Callable[[str], np.ndarray | None],
              made: dict[str, np.ndarray | None]) -> np.ndarray | None:
    """Evaluate a compiled rule; disabled masks (None) drop out of the expression. ``made``: the
    expressions evaluated on the image, by their ``_source``, each evaluated once (a fallback rule
    that extends the rule reuses it)."""
    if isinstance(node, ast.Name):
        return get(node.id)
    key = _source(node)
    if key in made:
        return made[key]
    if isinstance(node, ast.UnaryOp):
        m = _evaluate(node.operand, get, made)
        out = None if m is None else cv2.bitwise_not(m)
    else:
        a, b = _evaluate(node.left, get, made), _evaluate(node.right, get, made)
        if a is None or b is None:
            out = b if a is None else a
        else:
            out = cv2.bitwise_or(a, b) if isinstance(node.op, ast.BitOr) else cv2.bitwise_and(a, b)
    made[key] = out
    return out


# an expression's key in ``Made.expressions``: the same for the same expression in two rules, dumped
# once per node (``compile_rule`` keeps the trees)
_source = functools.lru_cache(maxsize=256)(ast.dump)


def rule_masks(config: ThresholdConfig) -> tuple[str, ...]:
    """Return the names of the enabled masks that ``config.rule`` uses, in order of appearance."""
    names: list[str] = []
    for node in ast.walk(compile_rule(config.rule, mask_names(config))):
        if isinstance(node, ast.Name) and node.id not in names and getattr(config, node.id).enabled:
            names.append(node.id)
    return tuple(names)


def mask_context_px(spec) -> tuple[int, int]:
    """Return the border (x, y) in px around a pixel that one mask record looks at: a colour mask (0, 0),
    or 2 * (k // 2) each way with its ``open_px`` k; a Sobel kernel k max(1, k // 2); the top-hat's
    opening 2 * (width_px // 2) across, plus k - 1 for its least width's 1 x k opening.
    """
    if isinstance(spec, SobelMask):
        r = max(1, spec.kernel_px // 2)
        return r, r
    if isinstance(spec, TopHatMask):
        return 2 * (spec.width_px // 2) + spec.min_width_px - 1, 0
    if isinstance(spec, (ChannelMask, ColorRange)) and spec.open_px > 1:
        r = 2 * (spec.open_px // 2)
        return r, r
    return 0, 0


def context_px(config: ThresholdConfig) -> tuple[int, int]:
    """Return the border (x, y) in px a crop needs for ``combine`` on it to give, inside the crop, the
    whole image's mask: the widest ``mask_context_px`` the rule uses, plus 2 * (size // 2) for each
    opening or closing of the combined mask.
    """
    cx = cy = 0
    for name in rule_masks(config):
        mx, my = mask_context_px(getattr(config, name))
        cx, cy = max(cx, mx), max(cy, my)
    for size in (config.open_px, config.close_px):
        if size > 1:
            cx, cy = cx + 2 * (size // 2), cy + 2 * (size // 2)
    return cx, cy


def masks(rgb: np.ndarray, config: ThresholdConfig = ThresholdConfig(),
          names: tuple[str, ...] | None = None, clahe: cv2.CLAHE | None = None) -> dict[str, np.ndarray]:
    """Return the 0/255 mask of each enabled mask (all of them, or those in ``names``); with
    ``config.clahe`` they see the equalised image (``clahe``: the one ``make_clahe`` made).
    """
    ch = Channels(mask_input(rgb, config, clahe))
    wanted = names if names is not None else mask_names(config)
    return {n: mask(ch, getattr(config, n)) for n in wanted if getattr(config, n).enabled}


@dataclass
class Made:
    """What ``combine`` made of one image (masks by name, colour conversions, the rules' expressions),
    so a second rule on it (``fallback_rule``) makes only the masks and expressions it adds and
    converts no colour space twice; and the line fits of its searches (``search.fit_side``).
    """

    masks: dict[str, np.ndarray] = field(default_factory=dict)
    channels: Channels | None = None
    expressions: dict[str, np.ndarray | None] = field(default_factory=dict)  # by ``_source``
    fits: dict = field(default_factory=dict)  # by side, look-ahead, reason if missing, pixels, height; with config


def combine(rgb: np.ndarray, config: ThresholdConfig = ThresholdConfig(),
            computed: dict[str, np.ndarray] | None = None, clahe: cv2.CLAHE | None = None,
            rule: str | None = None, channels: Channels | None = None,
            made: Made | None = None) -> np.ndarray:
    """Return the combined 0/255 lane-pixel mask of ``rgb`` under ``config.rule`` (or ``rule``, e.g.
    ``config.fallback_rule``), computing only the enabled masks the rule names.

    ``computed``: masks already made (e.g. by ``masks``, for the tuner). With ``config.clahe`` the
    masks see the equalised image (``clahe``: the one ``make_clahe`` made). ``channels``: the image's
    ``Channels`` made already (``Channels.cut``; without ``config.clahe`` only). ``made``: a ``Made``
    read like ``computed``, to which every mask and conversion made here is added.
    """
    if made is None:
        made = Made(dict(computed or {}))
    if channels is not None and not config.clahe and made.channels is None:
        made.channels = channels
    cache = made.masks

    def get(name: str) -> np.ndarray | None:
        spec = getattr(config, name)
        if not spec.enabled:
            return None
        if name not in cache:
            if made.channels is None:  # made (and equalised) only if a mask is still to compute
                made.channels = Channels(mask_input(rgb, config, clahe))
            cache[name] = mask(made.channels, spec)
        return cache[name]

    out = _evaluate(compile_rule(rule or config.rule, mask_names(config)), get, made.expressions)
    if out is None:
        out = np.zeros(rgb.shape[:2], np.uint8)
    out = _open(out, config.open_px)
    if config.close_px > 1:
        out = morph(out, "close", config.close_px, config.close_px)
    return out
