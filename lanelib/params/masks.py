"""The parameter records of the thresholds: one record per kind of mask, and ``ThresholdConfig``.

``thresholds`` computes the masks these records describe; ``compile_rule`` checks a rule over the
mask names (it runs when a ``ThresholdConfig`` is made, and ``thresholds.combine`` reads the tree
it returns). Colour spaces and their channels are named here as OpenCV's 8-bit conversions scale
them (``SPACE_CHANNELS``); ``thresholds.SPACES`` adds the conversion codes.
"""
from __future__ import annotations

import ast
import functools
from dataclasses import dataclass, fields

from ..errors import ConfigError

# colour space -> the letters of its channels, in order ("gray" has one channel, "y")
SPACE_CHANNELS: dict[str, str] = {"rgb": "rgb", "hls": "hls", "hsv": "hsv", "luv": "luv", "lab": "lab",
                                  "gray": "y"}


def check_channel(space: str, channel: str, where: str) -> None:
    """Raise ``ConfigError`` (naming ``where``) unless colour space ``space`` has ``channel``."""
    if space not in SPACE_CHANNELS:
        raise ConfigError(f"{where}: unknown colour space {space!r}; use one of {', '.join(SPACE_CHANNELS)}")
    if channel not in SPACE_CHANNELS[space]:
        raise ConfigError(f"{where}: colour space {space!r} has no channel {channel!r}; "
                          f"use one of {', '.join(SPACE_CHANNELS[space])}")


def _check_open(open_px: int, where: str) -> None:
    if open_px < 0:
        raise ConfigError(f"{where}: open_px {open_px} must be 0 (off) or more")


@dataclass(frozen=True)
class ChannelMask:
    """Pixels whose value in one channel lies in [low, high] (channel units, 0-255; hue 0-179).

    ``open_px`` opens this mask alone with a square kernel of that size (px; 0: off), which drops
    specks smaller than it before the rule combines the masks.
    """

    space: str = "hls"
    channel: str = "s"
    low: int = 170
    high: int = 255
    enabled: bool = True
    open_px: int = 0

    def __post_init__(self):
        check_channel(self.space, self.channel, "ChannelMask")
        _check_open(self.open_px, "ChannelMask")


@dataclass(frozen=True)
class ColorRange:
    """Pixels inside a box in one colour space (``cv2.inRange``), bounds per channel.

    ``open_px`` opens this mask alone with a square kernel of that size (px; 0: off), e.g. to
    drop yellow specks (leaves, sand) smaller than a line before the rule combines the masks.
    """

    space: str = "hsv"
    low: tuple[int, int, int] = (15, 80, 120)
    high: tuple[int, int, int] = (35, 255, 255)
    enabled: bool = True
    open_px: int = 0

    def __post_init__(self):
        _check_open(self.open_px, "ColorRange")
        if self.space == "gray" or self.space not in SPACE_CHANNELS:
            raise ConfigError(f"ColorRange: colour space {self.space!r} must be one of "
                              "rgb, hls, hsv, luv, lab")
        if len(self.low) != 3 or len(self.high) != 3:
            raise ConfigError("ColorRange: low and high need three values, one per channel")


@dataclass(frozen=True)
class SobelMask:
    """Pixels whose gradient lies in [low, high].

    ``kind`` is ``x``, ``y``, ``mag`` (gradient magnitude) or ``dir`` (direction
    atan2(|gy|, |gx|) in radians, 0 = a vertical edge). For x, y and mag the gradient is expressed
    as the height of an intensity step (0-255) across the kernel, so thresholds mean the same for
    every ``kernel_px``.
    """

    kind: str = "x"
    space: str = "hls"
    channel: str = "l"
    kernel_px: int = 3
    low: float = 20.0
    high: float = 255.0
    enabled: bool = True

    def __post_init__(self):
        check_channel(self.space, self.channel, "SobelMask")
        if self.kind not in ("x", "y", "mag", "dir"):
            raise ConfigError(f"SobelMask: kind {self.kind!r} must be x, y, mag or dir")
        if self.kernel_px not in (1, 3, 5, 7):
            raise ConfigError(f"SobelMask: kernel_px {self.kernel_px} must be 1, 3, 5 or 7")


@dataclass(frozen=True)
class TopHatMask:
    """Pixels brighter than the road beside them: a horizontal white top-hat of one channel.

    ``width_px`` is the width of the opening (wider than a line, narrower than the road between
    lines); the mask holds pixels whose top-hat value lies in [low, high]. It keeps lines and
    drops shadows, light concrete and exposure changes, which are wider than ``width_px``.
    ``min_width_px`` (1: off) then drops what is narrower than that across the road (an opening
    of the mask with a 1-row kernel that wide): a light seam or crack a few cm wide is brighter
    than the road on both sides like paint, but paint is at least 10 cm wide.

    ``ratio`` (0: off) makes the test relative as well: a pixel is kept only when its top-hat
    is also at least ``ratio`` times the road beside it (the opening, the top-hat's background),
    i.e. ``value >= (1 + ratio) * background``. Paint reflects a fixed multiple of the light
    that falls on the road, in sun and in shade alike, so under an overpass or a tree paint keeps
    its ratio to the road while its top-hat in levels shrinks with the light; ``low`` is then
    the floor in levels below which a step is sensor noise and compression, not paint.
    ``max_background`` (255: everywhere) keeps only pixels whose background is at most that
    level, i.e. on road in shade, so sunlit texture is left to the other masks.
    """

    space: str = "hls"
    channel: str = "l"
    width_px: int = 61
    low: int = 30
    high: int = 255
    enabled: bool = True
    min_width_px: int = 1
    ratio: float = 0.0
    max_background: int = 255

    def __post_init__(self):
        check_channel(self.space, self.channel, "TopHatMask")
        if self.width_px < 3:
            raise ConfigError(f"TopHatMask: width_px {self.width_px} must be 3 or more")
        if not 1 <= self.min_width_px < self.width_px:
            raise ConfigError(f"TopHatMask: min_width_px {self.min_width_px} must be 1 (off) or more "
                              f"and below width_px {self.width_px}")
        if not 0 <= self.ratio <= 255:
            raise ConfigError(f"TopHatMask: ratio {self.ratio} must be 0 (off) to 255")
        if not 0 <= self.max_background <= 255:
            raise ConfigError(f"TopHatMask: max_background {self.max_background} must be 0-255 (255: off)")


@dataclass(frozen=True)
class ThresholdConfig:
    """The named masks and the rule that combines them (see the module docstring).

    The default rule, ``yellow | (white & line_tophat)``: yellow paint by its hue, white paint as
    light pixels (HLS L >= 160) that are also brighter than the road beside them (the top-hat),
    which drops light concrete, sunlit patches and glare, and keeps dashes whose brightness
    auto-exposure lowers; the top-hat also drops what is under 12 px (7 cm in the default view)
    across, a light seam or crack rather than paint (``TopHatMask.min_width_px``).

    ``fallback_rule`` ("": none, the default; the ``hard-roads`` and ``country`` presets set
    ``yellow | (white & line_tophat) | shade_tophat``) is the rule of the fallback searches only,
    which run when the lane of ``rule`` fails its checks (``LanePipeline.detect``, ``LaneTracker``):
    the presets' rule adds ``shade_tophat``, whose cost (a second top-hat, about 2 ms a view) a
    clean road never pays. ``shade_tophat`` finds paint, white or yellow, in deep shade, where the
    colour masks' floors (HSV V >= 120, HLS L >= 160) and the top-hat's 30 levels miss it: a top-hat
    of HSV V (the brightest of R, G, B, so yellow counts as much as white) that keeps a pixel at
    least 1.65x the road beside it (``ratio`` 0.65) and at least 8 levels above it (the floor: a
    step of a few levels on a road at level 20 is sensor noise and video compression), 12 px wide or
    more. Paint reflects a fixed multiple of the light on the road, so the test holds in sun and
    shade alike; in an overpass's shade paint is still about 1.5-2x the road. In the cheap rule it
    would cost every frame the second top-hat, and where it finds one line in shade but not the
    other, the pair it changes can fail the parallel check. A lower ``ratio`` takes a sunlit gap
    between two tree shadows for paint (it is as many times brighter than the shade beside it).

    The other masks are there to tune and combine (notebook 03); the rule leaves them out
    because they add noise rather than lines (``python -m lanelib evaluate`` measures such a
    change).

    ``close_px`` closes gaps in the combined mask with a square kernel of that size (0: off);
    ``open_px`` removes specks smaller than that (0: off).

    ``clahe`` (off by default) equalises the image's lightness before any mask looks at it:
    CLAHE (``cv2.createCLAHE``) on the L channel of LAB, with clip limit ``clahe_clip_limit``
    and tiles of about ``clahe_tile_px`` px square, then back to RGB, so every mask sees the
    equalised image. CLAHE depends on the whole image (its tiles), so the video's band path
    thresholds the whole view when it is on (``LanePipeline.band_binary``).
    """

    yellow: ColorRange = ColorRange("hsv", (15, 80, 120), (35, 255, 255))
    white: ColorRange = ColorRange("hls", (0, 160, 0), (179, 255, 255))
    lab_b: ChannelMask = ChannelMask("lab", "b", 150, 255)
    s_channel: ChannelMask = ChannelMask("hls", "s", 170, 255)
    line_tophat: TopHatMask = TopHatMask("hls", "l", 61, 30, 255, min_width_px=12)
    shade_tophat: TopHatMask = TopHatMask("hsv", "v", 61, 8, 255, min_width_px=12, ratio=0.65)
    sobel_x: SobelMask = SobelMask("x", "hls", "l", 3, 20.0, 255.0)
    sobel_y: SobelMask = SobelMask("y", "hls", "l", 3, 20.0, 255.0, enabled=False)
    sobel_mag: SobelMask = SobelMask("mag", "hls", "l", 3, 30.0, 255.0, enabled=False)
    sobel_dir: SobelMask = SobelMask("dir", "hls", "l", 7, 0.0, 0.7, enabled=False)
    rule: str = "yellow | (white & line_tophat)"
    fallback_rule: str = ""
    close_px: int = 0
    open_px: int = 0
    clahe: bool = False
    clahe_clip_limit: float = 2.0
    clahe_tile_px: int = 160

    def __post_init__(self):
        compile_rule(self.rule, mask_names(self))
        if self.fallback_rule:
            compile_rule(self.fallback_rule, mask_names(self))
        if self.clahe_clip_limit <= 0:
            raise ConfigError(f"thresholds: clahe_clip_limit {self.clahe_clip_limit} must be positive")
        if self.clahe_tile_px < 8:
            raise ConfigError(f"thresholds: clahe_tile_px {self.clahe_tile_px} must be 8 or more")


def mask_names(config: ThresholdConfig) -> tuple[str, ...]:
    """Return the names of the masks a ThresholdConfig holds (the names a rule may use)."""
    return tuple(f.name for f in fields(config) if isinstance(getattr(config, f.name), MASK_TYPES))


MASK_TYPES = (ChannelMask, ColorRange, SobelMask, TopHatMask)


@functools.lru_cache(maxsize=32)
def compile_rule(rule: str, names: tuple[str, ...]) -> ast.expr:
    """Return the parsed rule; anything but mask names, ``| & ~`` and parentheses raises.

    Parsed once per rule (cached: ``combine`` reads it on every frame's band pieces); the tree
    returned is shared, so it is only read, never changed."""
    try:
        tree = ast.parse(rule, mode="eval").body
    except SyntaxError as e:
        raise ConfigError(f"thresholds.rule {rule!r}: not a valid expression ({e.msg}); "
                          "combine mask names with |, & and ~") from None
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            if node.id not in names:
                raise ConfigError(f"thresholds.rule: unknown mask {node.id!r}; "
                                  f"use one of {', '.join(names)}")
        elif not isinstance(node, (ast.BinOp, ast.UnaryOp, ast.BitOr, ast.BitAnd, ast.Invert,
                                   ast.Load)):
            raise ConfigError(f"thresholds.rule {rule!r}: only mask names, |, &, ~ and "
                              "parentheses are allowed")
    return tree
