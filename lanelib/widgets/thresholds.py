"""``ThresholdTuner``: the masks of ``ThresholdConfig`` and the rule that combines them, on the
bird's-eye view."""
from __future__ import annotations

import math
from dataclasses import replace

import cv2
import ipywidgets as widgets
import numpy as np

from .. import draw, thresholds
from ..camera import Calibration
from ..config import PipelineConfig
from ..pipeline import LanePipeline
from .base import Tuner, row, sized

_COLOR_SPACES = tuple(s for s in thresholds.SPACES if s != "gray")
_COMBINE_KEYS = ("rule", "fallback_rule", "open_px", "close_px")
_CLAHE_KEYS = ("clahe", "clahe_clip_limit", "clahe_tile_px")
_STACK_KEYS = ("stack.r", "stack.g", "stack.b")  # the stacked view's channels: a view, not config
_NONE = "(none)"


def _channel_max(space: str, channel: str) -> int:
    """Return the largest value of a channel in OpenCV's 8-bit units (hue: 179)."""
    return 179 if channel == "h" and space in ("hls", "hsv") else 255


class ThresholdTuner(Tuner):
    """Tune the masks of ``ThresholdConfig`` and their combination on the bird's-eye view.

    For each mask: an on/off box (``<mask>.enabled``), the colour space (``<mask>.space``) and
    channel (``<mask>.channel``), the low/high range (``<mask>.range``; a colour range has one
    per channel, ``<mask>.range0..2``), the Sobel kernel (``<mask>.kernel_px``), the top-hat's
    width (``<mask>.width_px``), least width (``<mask>.min_width_px``), least ratio to the road
    beside (``<mask>.ratio``) and brightest road beside it applies on (``<mask>.max_background``), the
    opening of a colour or channel mask alone
    (``<mask>.open_px``); then the rule (``rule``), the fallback searches' rule
    (``fallback_rule``, not previewed), the clean-up (``open_px``, ``close_px``) and
    CLAHE on the lightness before every mask (``clahe`` on/off, ``clahe_clip_limit``,
    ``clahe_tile_px``). The preview shows the bird's-eye view (equalised when CLAHE is on), every
    mask, the combination and the stacked view (``stack.r``/``stack.g``/``stack.b`` pick the
    masks shown in red, green and blue: ``draw.stacked_masks``); only the mask whose control
    moved is recomputed. ``save`` writes the ``thresholds`` part; ``load`` reads the
    ``perspective`` (the bird's-eye view) and ``thresholds`` parts.
    """

    columns = 4
    default_tile_width_px = 320
    parts = ("thresholds",)
    shows = ("perspective", "thresholds")

    # ---- building -------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        cfg = self.config.thresholds
        rows = []
        for name in thresholds.mask_names(cfg):
            spec = getattr(cfg, name)
            parts = [self._control(f"{name}.enabled", widgets.Checkbox(
                value=spec.enabled, description=name, indent=False,
                layout=widgets.Layout(width="110px")))]
            spaces = _COLOR_SPACES if isinstance(spec, thresholds.ColorRange) else tuple(thresholds.SPACES)
            parts.append(self._control(f"{name}.space", widgets.Dropdown(
                options=spaces, value=spec.space, layout=widgets.Layout(width="75px"))))
            if isinstance(spec, thresholds.ColorRange):
                for i, letter in enumerate(thresholds.SPACES[spec.space][1]):
                    top = _channel_max(spec.space, letter)
                    parts.append(self._control(f"{name}.range{i}", widgets.IntRangeSlider(
                        value=(spec.low[i], spec.high[i]), min=0, max=top, description=letter,
                        **sized(250, 20))))
                parts.append(self._open_control(name, spec))
            else:
                parts.append(self._control(f"{name}.channel", widgets.Dropdown(
                    options=tuple(thresholds.SPACES[spec.space][1]), value=spec.channel,
                    layout=widgets.Layout(width="55px"))))
                if isinstance(spec, thresholds.SobelMask):
                    top, step = (round(math.pi / 2, 2), 0.01) if spec.kind == "dir" else (255.0, 1.0)
                    parts.append(self._control(f"{name}.range", widgets.FloatRangeSlider(
                        value=(spec.low, spec.high), min=0.0, max=top, step=step,
                        description=spec.kind, readout_format=".2f" if spec.kind == "dir" else ".0f",
                        **sized(300, 30))))
                    parts.append(self._control(f"{name}.kernel_px", widgets.Dropdown(
                        options=(1, 3, 5, 7), value=spec.kernel_px, description="kernel",
                        layout=widgets.Layout(width="120px"), style={"description_width": "45px"})))
                else:
                    parts.append(self._control(f"{name}.range", widgets.IntRangeSlider(
                        value=(spec.low, spec.high), min=0, max=_channel_max(spec.space, spec.channel),
                        description=spec.channel, **sized(300, 30))))
                    if isinstance(spec, thresholds.TopHatMask):
                        parts.append(self._control(f"{name}.width_px", widgets.IntSlider(
                            value=spec.width_px, min=3, max=201, step=2, description="width px",
                            layout=widgets.Layout(width="260px"),
                            style={"description_width": "60px"})))
                        parts.append(self._control(f"{name}.min_width_px", widgets.IntSlider(
                            value=spec.min_width_px, min=1, max=41, step=1, description="min width",
                            layout=widgets.Layout(width="260px"),
                            style={"description_width": "70px"})))
                        parts.append(self._control(f"{name}.ratio", widgets.FloatSlider(
                            value=spec.ratio, min=0.0, max=3.0, step=0.05, description="ratio",
                            readout_format=".2f", **sized(230, 45))))
                        parts.append(self._control(f"{name}.max_background", widgets.IntSlider(
                            value=spec.max_background, min=0, max=255, description="max bg",
                            **sized(230, 50))))
                    else:
                        parts.append(self._open_control(name, spec))
            rows.append(row(*parts))
        rows.append(row(
            self._control("rule", widgets.Text(value=cfg.rule, description="rule",
                                               continuous_update=False,
                                               layout=widgets.Layout(width="640px"),
                                               style={"description_width": "40px"})),
            self._control("fallback_rule", widgets.Text(
                value=cfg.fallback_rule, description="fallback", continuous_update=False,
                layout=widgets.Layout(width="640px"), style={"description_width": "60px"})),
            self._control("open_px", widgets.IntSlider(value=cfg.open_px, min=0, max=15,
                                                       description="open px", **sized(240, 60))),
            self._control("close_px", widgets.IntSlider(value=cfg.close_px, min=0, max=15,
                                                        description="close px", **sized(240, 60)))))
        rows.append(row(
            self._control("clahe", widgets.Checkbox(value=cfg.clahe, description="CLAHE", indent=False,
                                                    layout=widgets.Layout(width="80px"))),
            self._control("clahe_clip_limit", widgets.FloatSlider(
                value=cfg.clahe_clip_limit, min=0.5, max=10.0, step=0.5, description="clip limit",
                **sized(260, 70))),
            self._control("clahe_tile_px", widgets.IntSlider(
                value=cfg.clahe_tile_px, min=16, max=640, step=16, description="tile px",
                **sized(260, 70))),
            *(self._control(key, widgets.Dropdown(
                options=(_NONE, *thresholds.mask_names(cfg)), value=first, description=key[-1].upper(),
                layout=widgets.Layout(width="160px"), style={"description_width": "15px"}))
              for key, first in zip(_STACK_KEYS, self._stack_defaults(cfg)))))
        return rows

    def _open_control(self, name: str, spec) -> widgets.Widget:
        """Return the slider of one colour or channel mask's own opening (``open_px``)."""
        return self._control(f"{name}.open_px", widgets.IntSlider(
            value=spec.open_px, min=0, max=15, description="open", **sized(190, 40)))

    @staticmethod
    def _stack_defaults(cfg: thresholds.ThresholdConfig) -> tuple[str, str, str]:
        """Return the stacked view's first masks: those the rule uses, in order, then none."""
        used = thresholds.rule_masks(cfg)[:3]
        return tuple(used) + (_NONE,) * (3 - len(used))

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        size = (raw.shape[1], raw.shape[0])
        pipeline = self._cached("pipeline", (id(calibration), size, self.config.perspective),
                                lambda: LanePipeline(self.config, calibration, size=size))
        self.birdseye = pipeline.birdseye(raw)
        self._equalise()

    def _equalise(self) -> None:
        """Make the image the masks see (``thresholds.mask_input``) and forget the masks made."""
        cfg = self.config.thresholds
        self.mask_view = thresholds.mask_input(self.birdseye, cfg)
        self._clahe_spec = tuple(getattr(cfg, k) for k in _CLAHE_KEYS)
        self._channels = thresholds.Channels(self.mask_view)
        self._masks: dict[str, tuple[object, np.ndarray]] = {}

    # ---- config <-> controls --------------------------------------------------------------

    def _spec(self, name: str):
        """Return the spec of mask ``name`` that its controls describe.

        A channel that the chosen colour space lacks becomes the space's first; ranges are
        capped at the channel's largest value (as the controls will be when fitted to them).
        """
        c = self.controls
        old = getattr(self.config.thresholds, name)
        enabled, space = c[f"{name}.enabled"].value, c[f"{name}.space"].value
        letters = thresholds.SPACES[space][1]
        if isinstance(old, thresholds.ColorRange):
            ranges = [c[f"{name}.range{i}"].value for i in range(3)]
            tops = [_channel_max(space, letter) for letter in letters]
            return thresholds.ColorRange(space, tuple(min(int(r[0]), t) for r, t in zip(ranges, tops)),
                                         tuple(min(int(r[1]), t) for r, t in zip(ranges, tops)), enabled,
                                         int(c[f"{name}.open_px"].value))
        channel = c[f"{name}.channel"].value
        channel = channel if channel in letters else letters[0]
        low, high = c[f"{name}.range"].value
        if isinstance(old, thresholds.SobelMask):
            return thresholds.SobelMask(old.kind, space, channel, int(c[f"{name}.kernel_px"].value),
                                        float(low), float(high), enabled)
        top = _channel_max(space, channel)
        low, high = min(int(low), top), min(int(high), top)
        if isinstance(old, thresholds.TopHatMask):
            width = int(c[f"{name}.width_px"].value)
            return thresholds.TopHatMask(space, channel, width, low, high, enabled,
                                         min(int(c[f"{name}.min_width_px"].value), width - 1),
                                         float(c[f"{name}.ratio"].value),
                                         int(c[f"{name}.max_background"].value))
        return thresholds.ChannelMask(space, channel, low, high, enabled, int(c[f"{name}.open_px"].value))

    def _apply(self, key: str) -> PipelineConfig:
        tc = self.config.thresholds
        if key in _STACK_KEYS:
            return self.config
        if key in _COMBINE_KEYS + _CLAHE_KEYS:
            tc = replace(tc, **{key: self.controls[key].value})
        else:
            name = key.partition(".")[0]
            tc = replace(tc, **{name: self._spec(name)})
        return replace(self.config, thresholds=tc)

    def _update(self, key: str | None) -> None:
        # the masks are made when shown (``mask``), each kept while its spec stays the same;
        # a new colour space or channel changes the choices and ranges of that mask's controls
        name, _, part = (key or "").partition(".")
        if tuple(getattr(self.config.thresholds, k) for k in _CLAHE_KEYS) != self._clahe_spec:
            self._equalise()
        if part in ("space", "channel"):
            with self._quiet():
                self._sync_mask(name)

    def _sync(self) -> None:
        for name in thresholds.mask_names(self.config.thresholds):
            self._sync_mask(name)
        for key in _COMBINE_KEYS + _CLAHE_KEYS:
            self.controls[key].value = getattr(self.config.thresholds, key)

    def _sync_mask(self, name: str) -> None:
        """Set the controls of mask ``name`` (choices, ranges, labels, values) from the config."""
        spec = getattr(self.config.thresholds, name)
        c = self.controls
        c[f"{name}.enabled"].value = spec.enabled
        c[f"{name}.space"].value = spec.space
        if f"{name}.open_px" in c:
            c[f"{name}.open_px"].value = spec.open_px
        letters = thresholds.SPACES[spec.space][1]
        if isinstance(spec, thresholds.ColorRange):
            for i, letter in enumerate(letters):
                s = c[f"{name}.range{i}"]
                s.max, s.description = _channel_max(spec.space, letter), letter
                s.value = (spec.low[i], spec.high[i])
            return
        c[f"{name}.channel"].options = tuple(letters)
        c[f"{name}.channel"].value = spec.channel
        if isinstance(spec, thresholds.SobelMask):
            c[f"{name}.kernel_px"].value = spec.kernel_px
        else:
            c[f"{name}.range"].max = _channel_max(spec.space, spec.channel)
            c[f"{name}.range"].description = spec.channel
            if isinstance(spec, thresholds.TopHatMask):
                c[f"{name}.width_px"].value = spec.width_px
                c[f"{name}.min_width_px"].value = spec.min_width_px
                c[f"{name}.ratio"].value = spec.ratio
                c[f"{name}.max_background"].value = spec.max_background
        c[f"{name}.range"].value = (spec.low, spec.high)

    # ---- views ----------------------------------------------------------------------------

    def mask(self, name: str) -> np.ndarray | None:
        """Return the 0/255 bird's-eye mask ``name`` under the current config (None if off)."""
        spec = getattr(self.config.thresholds, name)
        if not spec.enabled:
            return None
        on = replace(spec, enabled=True)
        cached = self._masks.get(name)
        if cached is None or cached[0] != on:
            cached = (on, thresholds.mask(self._channels, on))
            self._masks[name] = cached
        return cached[1]

    def combined(self) -> np.ndarray:
        """Return the combined 0/255 bird's-eye lane mask under the current config."""
        cfg = self.config.thresholds
        made = {n: m for n in thresholds.mask_names(cfg) if (m := self.mask(n)) is not None}
        return thresholds.combine(self.mask_view, replace(cfg, clahe=False), computed=made)

    def counts(self) -> dict[str, int]:
        """Return the pixels of each enabled mask and of the combination (key ``"combined"``)."""
        out = {n: cv2.countNonZero(m) for n in thresholds.mask_names(self.config.thresholds)
               if (m := self.mask(n)) is not None}
        out["combined"] = cv2.countNonZero(self.combined())
        return out

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the bird's-eye view, every mask (None if off) and the combination."""
        cfg = self.config.thresholds
        views: dict[str, np.ndarray | None] = {
            "bird's-eye (CLAHE)" if cfg.clahe else "bird's-eye": self.mask_view}
        views.update({n: self.mask(n) for n in thresholds.mask_names(cfg)})
        views["combined"] = self.combined()
        views["stacked " + " ".join(self.stacked_names())] = self.stacked()
        return views

    def stacked_names(self) -> tuple[str, ...]:
        """Return the masks of the stacked view as red, green, blue ("-" for none)."""
        return tuple(self.controls[k].value if self.controls[k].value != _NONE else "-"
                     for k in _STACK_KEYS)

    def stacked(self) -> np.ndarray | None:
        """Return the stacked view: the picked masks as the red, green and blue channels (None if
        no mask is picked or all picked are off)."""
        names = [self.controls[k].value for k in _STACK_KEYS]
        made = {n: self.mask(n) for n in names if n != _NONE}
        if not any(m is not None for m in made.values()):
            return None
        h, w = self.birdseye.shape[:2]
        made[_NONE] = None
        made = {n: m if m is not None else np.zeros((h, w), np.uint8) for n, m in made.items()}
        return draw.stacked_masks(made, names)

    def readout(self) -> str:
        counts = self.counts()
        total = self.birdseye.shape[0] * self.birdseye.shape[1]
        per = ", ".join(f"{n} {v / total:.1%}" for n, v in counts.items() if n != "combined")
        clahe = (f"  CLAHE clip {self.config.thresholds.clahe_clip_limit:g}, "
                 f"tiles {self.config.thresholds.clahe_tile_px} px" if self.config.thresholds.clahe else "")
        return (f"combined: {counts['combined']} px ({counts['combined'] / total:.1%} of the view)"
                f"  rule: {self.config.thresholds.rule}{clahe}\n{per}")
