"""``FitTuner``: the lane-pixel search (sliding windows, the search around a fit) on the bird's-eye
lane mask, with the fits and the lane drawn back on the road."""
from __future__ import annotations

import math
from dataclasses import replace

import ipywidgets as widgets
import numpy as np

from .. import draw, thresholds
from ..camera import Calibration
from ..config import PipelineConfig
from ..pipeline import LanePipeline
from ..search import search_around, sliding_windows
from .base import Tuner, fmt, row, sized

LIMITS = {"n_windows": (1, 30), "margin_px": (5, 300), "minpix": (0, 5000), "prior_margin_px": (5, 300)}
# the published tricks (``params.SearchConfig``), all off by default: key -> (kind, low, high, step)
SWITCHES = {"trim_outliers_pct": ("float", 0.0, 100.0, 0.5), "grow_margin_px": ("int", 0, 100, 5),
            "window_histogram": ("bool",), "centre_first": ("bool",)}


class FitTuner(Tuner):
    """Tune the lane-pixel search: sliding windows and the search around a previous fit.

    Sliders ``n_windows``, ``margin_px``, ``minpix`` (the sliding windows) and
    ``prior_margin_px`` (the band searched around a previous fit; here the windows' own fits
    stand in for the previous frame's); the published tricks of ``params.SearchConfig`` as
    switches (all off by default): ``trim_outliers_pct`` (0: off; else the share of each line's
    pixels kept for the refit), ``grow_margin_px`` (0: off), ``window_histogram`` and
    ``centre_first``. The preview shows the windows and fits, the band search and the lane drawn
    back on the road; the readout gives each base's peak confidence ((peak - mean) / mean of the
    histogram). The bird's-eye lane mask is made once per image.
    ``save`` writes the ``search`` part; ``load`` reads it and the ``perspective``,
    ``thresholds`` and ``draw`` parts the views use.
    """

    columns = 3
    default_tile_width_px = 400
    parts = ("search",)
    shows = ("perspective", "thresholds", "search", "draw")
    KEYS = tuple(LIMITS) + tuple(SWITCHES)

    def _build(self) -> list[widgets.Widget]:
        sc = self.config.search
        made = [self._control(k, widgets.IntSlider(value=getattr(sc, k), min=lo, max=hi,
                                                   description=k, **sized(460, 150)))
                for k, (lo, hi) in LIMITS.items()]
        tricks = []
        for k, spec in SWITCHES.items():
            if spec[0] == "bool":
                w = widgets.Checkbox(value=getattr(sc, k), description=k, indent=False,
                                     layout=widgets.Layout(width="170px"))
            else:
                cls = widgets.FloatSlider if spec[0] == "float" else widgets.IntSlider
                w = cls(value=getattr(sc, k), min=spec[1], max=spec[2], step=spec[3],
                        description=k, **sized(360, 130))
            tricks.append(self._control(k, w))
        return [row(*made[:2]), row(*made[2:]), row(*tricks)]

    def _sync(self) -> None:
        for k in self.KEYS:
            self.controls[k].value = getattr(self.config.search, k)

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        size = (raw.shape[1], raw.shape[0])
        self.pipeline = self._cached("pipeline", (id(calibration), size, self.config.perspective),
                                     lambda: LanePipeline(self.config, calibration, size=size))
        # the lane mask depends on the thresholds too: always from the current config
        self.undistorted = self.pipeline.undistort(raw)
        self.binary = thresholds.combine(self.pipeline.birdseye(raw), self.config.thresholds)

    def _apply(self, key: str) -> PipelineConfig:
        search = replace(self.config.search, **{k: _typed(k, self.controls[k].value) for k in self.KEYS})
        return replace(self.config, search=search)

    def _update(self, key: str | None) -> None:
        """Search the lane mask with the current search parameters (windows, then around them)."""
        sc = self.config.search
        self.windows = sliding_windows(self.binary, sc, car_x=self.pipeline.car_x_px)
        self.around = search_around(self.binary, self.windows.left, self.windows.right, sc)
        self.measurement = self.pipeline.measure(self.windows.left, self.windows.right)

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the windows and fits, the search around the fits, and the lane on the road."""
        dc = self.config.draw
        overlay = draw.lane_overlay(self.undistorted, self.windows.left.coeffs_px,
                                    self.windows.right.coeffs_px, self.pipeline.perspective.inverse, dc)
        return {"sliding windows": draw.search_view(self.binary, self.windows, dc),
                "search around the fits": draw.search_view(self.binary, self.around, dc,
                                                           self.config.search.prior_margin_px),
                "lane on the road": overlay}

    def readout(self) -> str:
        lines = []
        peaks = [("not found" if c is None else f"{c:.1f}") for c in self.windows.base_confidence]
        lines.append(f"base peaks (peak - mean) / mean: left {peaks[0]}, right {peaks[1]}")
        for title, s in (("sliding windows", self.windows), ("search around", self.around)):
            parts = []
            for side, fit in (("left", s.left), ("right", s.right)):
                parts.append(f"{side} {fit.n_pixels} px" + ("" if fit.found else f" (not found: {fit.reason})"))
            lines.append(f"{title}: " + ", ".join(parts))
        m = self.measurement
        if not math.isnan(m.radius_m):
            rad = "straight" if m.radius_m >= 10_000 else f"{m.radius_m:.0f} m"
            lines.append(f"radius {rad}, offset {fmt(m.offset_m, 2, ' m', True)}, "
                         f"lane width {fmt(m.lane_width_m, 2, ' m')}")
        return "\n".join(lines)


def _typed(key: str, value):
    """Return a control's value as its ``SearchConfig`` field's type."""
    kind = SWITCHES[key][0] if key in SWITCHES else "int"
    return {"int": int, "float": float, "bool": bool}[kind](value)
