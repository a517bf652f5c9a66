"""Every lane line in one frame: the lines view's mask, the search, and the lines in the frame.

``LanePipeline.detect_lines`` calls ``find_every_line`` with the lines view's setup it made once
(``LanePipeline.lines_view`` by ``make_setup``: a ``lines.view.LinesView``, its remap maps, the
thresholds rescaled to it, its transform back to the raw frame and the pixels that see the frame).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .. import thresholds
from ..errors import ConfigError
from ..params import LinesConfig
from ..params.masks import ChannelMask, ColorRange, ThresholdConfig, TopHatMask, mask_names
from ..perspective import Perspective, Transform
from . import vote
from .result import image_line
from .trace import find_lines
from .view import LinesView


def _scale_px(v: int, factor: float, least: int = 1) -> int:
    """Return ``v`` px times ``factor``, rounded, at least ``least`` (0 stays 0: off)."""
    return 0 if v == 0 else max(least, int(round(v * factor)))


def scaled_thresholds(config: ThresholdConfig, factor: float) -> ThresholdConfig:
    """Return ``config`` for a view whose pixels are ``1 / factor`` times as wide across the road (e.g.
    ``LinesView``: its px per metre over the ego view's). Widths across scale by ``factor``: top-hat
    ``width_px`` (at least 3) and ``min_width_px`` (1 stays off; below the width), ``open_px`` and
    ``close_px`` (0 stays off), ``clahe_tile_px`` (at least 8). Colour bounds and Sobel kernels do
    not change.
    """
    if factor <= 0:
        raise ConfigError(f"scaled_thresholds: factor {factor} must be positive")
    changes = {}
    for name in mask_names(config):
        spec = getattr(config, name)
        if isinstance(spec, TopHatMask):
            width = max(3, int(round(spec.width_px * factor)))
            least = 1 if spec.min_width_px <= 1 else min(width - 1, _scale_px(spec.min_width_px, factor))
            changes[name] = replace(spec, width_px=width, min_width_px=least)
        elif isinstance(spec, (ChannelMask, ColorRange)) and spec.open_px:
            changes[name] = replace(spec, open_px=_scale_px(spec.open_px, factor))
    return replace(config, **changes, open_px=_scale_px(config.open_px, factor),
                   close_px=_scale_px(config.close_px, factor),
                   clahe_tile_px=max(8, int(round(config.clahe_tile_px * factor))))


@dataclass(frozen=True)
class LinesSetup:
    """What the lines search needs of one camera, made once: the view (``lines.view.LinesView``),
    its remap maps from the raw frame, the thresholds rescaled to it, its transform back to the
    raw frame, and its pixels that see the frame away from its edge (255, else 0)."""

    view: LinesView
    maps: tuple[np.ndarray, np.ndarray]
    tconf: ThresholdConfig
    to_raw: Transform
    seen: np.ndarray


def make_setup(ego: Perspective, lens: Transform, size_px: tuple[int, int], config: LinesConfig,
               tconf: ThresholdConfig) -> LinesSetup:
    """Return the lines search's setup for frames of ``size_px`` (w, h) of one camera.

    The view is a ``LinesView`` of the ego view ``ego`` (``LinesConfig.view_*``, ``follow_ahead_m``
    further when lines are followed beyond ``view_ahead_m``), reached from the raw frame through
    ``lens.inverse`` (``camera.Lens``); the thresholds ``tconf`` are rescaled to it
    (``scaled_thresholds``); its pixels that see the frame are eroded away from the frame's edge,
    which is no paint.
    """
    view = LinesView(ego, config.view_half_width_m, config.view_xm_per_px,
                     config.view_ahead_m + config.follow_ahead_m, config.view_ym_per_px)
    raw_to_view = lens.inverse + view
    view_tconf = scaled_thresholds(tconf, view.scale_from_ego)
    maps = raw_to_view.remap_maps(view.size)
    seen = cv2.remap(np.full(tuple(size_px)[::-1], 255, np.uint8), maps[0], maps[1], cv2.INTER_NEAREST,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    edge = 2 * view_tconf.line_tophat.width_px + 1
    return LinesSetup(view, maps, view_tconf, raw_to_view.inverse,
                      cv2.erode(seen, np.ones((3, edge), np.uint8)))


def row_weights(setup: LinesSetup, config: LinesConfig) -> np.ndarray:
    """Return how much each row of the lines view counts in the vote (``LinesConfig``:
    ``row_weight_full``, ``row_weight_power``): the raw frame's rows it sees, over
    ``row_weight_full`` and at most 1, to the power ``row_weight_power``. A far row of the view
    is stretched from a fraction of one raw row, so a speck there would otherwise vote along
    metres of road."""
    view = setup.view
    rows = np.arange(view.size[1], dtype=np.float64)
    pts, ok = setup.to_raw.checked(np.column_stack([np.full(len(rows), view.car_x_px), rows]))
    seen = np.where(ok, np.abs(np.gradient(pts[:, 1])), 0.0)
    return np.clip(seen / config.row_weight_full, 0.0, 1.0) ** config.row_weight_power


def paint_strength(view: np.ndarray | thresholds.Channels, tconf: thresholds.ThresholdConfig,
                   config: LinesConfig) -> np.ndarray | None:
    """Return how much a run of paint on each pixel of the view counts in the vote
    (``LinesConfig.contrast_full``; None when off): its top-hat (``tconf.line_tophat``) over
    ``contrast_full`` times the lowest top-hat floor the mask takes (``line_tophat.low``, or
    ``LinesConfig.tophat_low`` when lower), between one half and 1. Paint stands out from the
    road; a seam, a barrier's foot or a vehicle's edge that passes the floor barely does, and
    counts half as much.

    ``view`` is the view's RGB image, or its ``thresholds.Channels`` made already (whose top-hat the
    mask read: it is not made again).

    Examples
    --------
    >>> view = np.full((1, 80, 3), 90, np.uint8); view[0, 10:14] = 102; view[0, 50:54] = 200
    >>> s = paint_strength(view, thresholds.ThresholdConfig(), LinesConfig(contrast_full=2))
    >>> float(s[0, 12]), float(s[0, 52]), float(s[0, 30])
    (0.5, 1.0, 0.5)
    """
    if config.contrast_full <= 0 or not tconf.line_tophat.enabled:
        return None
    spec = tconf.line_tophat
    floor = min(spec.low, config.tophat_low) if config.tophat_low > 0 else spec.low
    levels = (view if isinstance(view, thresholds.Channels) else thresholds.Channels(view)).tophat(spec)[0]
    return np.clip(levels.astype(np.float32) / (config.contrast_full * max(floor, 1)), 0.5, 1.0)


def search_first_row(view, config: LinesConfig) -> int:
    """Return the first row of the lines view that the search looks at: the row ``view_ahead_m``
    ahead of the ego view's bottom row when the view goes on beyond it (``follow_ahead_m``),
    else 0 (every row)."""
    if config.follow_ahead_m <= 0:
        return 0
    return max(0, int(round(view.bottom_px - config.view_ahead_m / view.ym_per_px)))


def find_every_line(raw: np.ndarray, setup: LinesSetup, config: LinesConfig,
                    weights: np.ndarray | None = None) -> tuple[tuple, dict, tuple]:
    """Return every lane line seen in a RAW frame (``lines.result.ImageLine``s, left to right), the
    view and its mask ("lines_birdseye", "lines_binary"), and the vote's refused lines with
    their reasons.

    The view is masked by the rescaled thresholds' rule (with ``tophat_low``, far paint, blurred
    and dimmer, by a lower top-hat floor beyond ``near_m``), narrowed to paint (a verge or a
    field beside the road is wider) and to the pixels that see the frame; the lines are found by
    ``vote.vote_lines`` or ``trace.find_lines`` (``LinesConfig.method``) within ``view_ahead_m``,
    followed beyond it with ``follow_ahead_m`` (``vote.follow_ahead``), and mapped back to the
    raw frame over the span where each is seen (``lines.result.image_line``). ``weights``: the vote's
    row weights (``row_weights``), None for every row alike.
    """
    view, maps, tconf = setup.view, setup.maps, setup.tconf
    bird = cv2.remap(raw, maps[0], maps[1], cv2.INTER_LINEAR)
    made = thresholds.Made()
    mask = thresholds.combine(bird, tconf, made=made)
    if config.tophat_low and tconf.line_tophat.enabled:  # far paint: blurred, dimmer
        far = replace(tconf.line_tophat, low=min(config.tophat_low, tconf.line_tophat.low))
        # the view's own pixels, not CLAHE's: the channels the mask made when it saw those
        unequalised = made.channels if made.channels is not None and not tconf.clahe else bird
        low = thresholds.mask(unequalised, far)
        top = max(0, int(view.bottom_px - config.near_m / view.ym_per_px))
        half = int(config.near_half_width_m / view.xm_per_px)
        cx = int(view.car_x_px)
        low[top:, max(0, cx - half):cx + half] = 0
        mask = cv2.bitwise_or(mask, low)
    wide = 2 * tconf.line_tophat.width_px  # paint is narrow: not a verge or a field beside the road
    mask = cv2.subtract(mask, thresholds.morph(mask, "open", wide, 1))
    mask = cv2.bitwise_and(mask, setup.seen)
    to_raw = functools.partial(image_line, view_to_raw=setup.to_raw, car_x_px=view.car_x_px,
                               bottom_px=view.bottom_px, xm_per_px=view.xm_per_px)
    first = search_first_row(view, config)
    refused: tuple = ()
    if config.method == "vote":
        strength = paint_strength(bird if made.channels is None else made.channels, tconf, config)
        weighed = vote.vote_candidates(mask[first:], config, view.xm_per_px, view.ym_per_px, view.car_x_px,
                                       None if weights is None else weights[first:],
                                       None if strength is None else strength[first:])
        found = vote.reported(weighed, config, mask.shape[0] - first, view.ym_per_px)
        refused = tuple((c.line, c.refused) for c in weighed if c.refused and c.line is not None)
    else:
        found = find_lines(mask[first:], config, view.xm_per_px, view.ym_per_px)
    ahead: list = [None] * len(found)
    if first:
        found = [line.shifted(first) for line in found]
        refused = tuple((line.shifted(first), why) for line, why in refused)
        ahead = vote.follow_ahead(found, mask, first, config, view.xm_per_px, view.ym_per_px)
    refused = tuple((to_raw(line), why) for line, why in refused)
    lines = tuple(to_raw(line) if far is None else to_raw(line).joined(to_raw(far))
                  for line, far in zip(found, ahead))
    return lines, {"lines_birdseye": bird, "lines_binary": mask}, refused
