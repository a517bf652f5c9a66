"""``PerspectiveTuner``: the src trapezoid and the dst margin of the bird's-eye transform, with the
straight-line check (``perspective.straight_line_check``) as the measure of a good one."""
from __future__ import annotations

from dataclasses import replace

import cv2
import ipywidgets as widgets
import numpy as np

from .. import thresholds
from ..camera import Calibration, FastBirdseye, Undistorter
from ..config import PipelineConfig
from ..draw import shrink
from ..perspective import (Perspective, PerspectiveConfig, implied_focal_px, road_length_m, scaled,
                           straight_line_check, trapezoid_src)
from .base import Tuner, row, sized

KEYS = ("top_y", "top_width", "bottom_width", "centre_x", "dst_margin")


def _trapezoid_of(src_px) -> dict[str, float]:
    """Return top_y, bottom_y, top_width, bottom_width, centre_x of src points (tl, bl, br, tr)."""
    (tlx, tly), (blx, bly), (brx, bry), (trx, try_) = src_px
    return {"top_y": (tly + try_) / 2, "bottom_y": (bly + bry) / 2, "top_width": trx - tlx,
            "bottom_width": brx - blx, "centre_x": (blx + brx) / 2}


def _limits(pc: PerspectiveConfig) -> dict[str, float]:
    """Return the largest value of each slider for images of ``pc.size_px``."""
    w, h = pc.size_px
    return {"top_y": h - 1, "centre_x": w, "top_width": w, "bottom_width": 2 * w, "dst_margin": w / 2 - 1}


class PerspectiveTuner(Tuner):
    """Tune the bird's-eye transform: the src trapezoid and the dst margin.

    Sliders ``top_y``, ``top_width``, ``bottom_width``, ``centre_x`` (the symmetric src
    trapezoid; its bottom row stays where the config has it) and ``dst_margin`` (the dst lines'
    distance from the left and right edges). The preview shows the trapezoid on the undistorted
    frame, the bird's-eye view with the dst lines, and the bird's-eye lane mask with the
    straight fits of the straight-line check; the readout gives the check as numbers.

    Moving the trapezoid keeps the lane width in metres and updates the visible road length to
    the same camera (``perspective.road_length_m`` with the focal length the starting config
    implies), so the metric scale stays right. A config whose src is not a symmetric
    trapezoid is kept as it is until a slider moves. ``save`` writes the ``perspective`` part;
    ``load`` reads it and the ``thresholds`` and ``search`` parts the check uses.
    """

    columns = 3
    default_tile_width_px = 400
    parts = ("perspective",)
    shows = ("perspective", "thresholds", "search")

    def _build(self) -> list[widgets.Widget]:
        pc = self.config.perspective
        values = dict(_trapezoid_of(pc.src_px), dst_margin=float(pc.dst_px[0][0]))
        top = _limits(pc)
        sl = lambda key, desc: self._control(key, widgets.FloatSlider(  # noqa: E731
            value=values[key], min=0.0, max=float(top[key]), step=0.1, description=desc,
            readout_format=".1f", **sized(460, 150)))
        return [row(sl("top_y", "top y (px)"), sl("centre_x", "centre x (px)")),
                row(sl("top_width", "top width (px)"), sl("bottom_width", "bottom width (px)")),
                row(sl("dst_margin", "dst margin (px)"))]

    def _sync(self) -> None:
        pc = self.config.perspective
        values = dict(_trapezoid_of(pc.src_px), dst_margin=float(pc.dst_px[0][0]))
        for key, top in _limits(pc).items():
            self.controls[key].max = float(top)
            self.controls[key].value = float(values[key])

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        size = (raw.shape[1], raw.shape[0])
        if tuple(self.config.perspective.size_px) != size:
            self._show(replace(self.config, perspective=scaled(self.config.perspective, size)))
        undistorter = self._cached("undistorter", (id(calibration), size),
                                   lambda: Undistorter(calibration, size))
        self._canvas = self._cached("canvas", (id(calibration), size),
                                    lambda: FastBirdseye(undistorter.lens))
        self.undistorted = undistorter.undistort(raw)
        self._focal_px = implied_focal_px(self.config.perspective)
        self._small = shrink(self.undistorted, self._tile_size())

    def _apply(self, key: str) -> PipelineConfig:
        pc = self.config.perspective
        v = {k: float(self.controls[k].value) for k in KEYS}
        w, h = pc.size_px
        bottom_y = _trapezoid_of(pc.src_px)["bottom_y"]
        src = trapezoid_src(v["top_y"], bottom_y, v["top_width"], v["bottom_width"], v["centre_x"])
        dst = trapezoid_src(0.0, float(h), w - 2 * v["dst_margin"], w - 2 * v["dst_margin"], w / 2)
        src = tuple((round(x, 2), round(y, 2)) for x, y in src)
        length = round(road_length_m(src, pc.lane_width_m, self._focal_px), 3)
        new = PerspectiveConfig(src, dst, pc.size_px, pc.lane_width_m, length)
        Perspective(new)  # refuses collinear points with a ConfigError
        return replace(self.config, perspective=new)

    def _update(self, key: str | None) -> None:
        """Warp, threshold and check the picked frame under the current perspective."""
        self.perspective = Perspective(self.config.perspective)
        self.birdseye = self._canvas.birdseye(self._raw, self.perspective)
        self.binary = thresholds.combine(self.birdseye, self.config.thresholds)
        w, h = self.config.perspective.size_px
        car_x = float(self.perspective([(w / 2, h - 1)])[0, 0])
        self.check = straight_line_check(self.binary, self.perspective.xm_per_px,
                                         self.config.search, car_x)

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the undistorted frame with the src trapezoid, the bird's-eye view, and its mask."""
        tw, th = self._tile_size()
        h, w = self.undistorted.shape[:2]
        s = np.array([tw / w, th / h])
        road = self._small.copy()
        src = np.round(np.asarray(self.config.perspective.src_px) * s).astype(np.int32)
        cv2.polylines(road, [src.reshape(-1, 1, 2)], True, (255, 0, 0), 2, cv2.LINE_AA)
        bird = shrink(self.birdseye, (tw, th))
        mask = cv2.cvtColor(shrink(self.binary, (tw, th)), cv2.COLOR_GRAY2RGB)
        dst = np.asarray(self.config.perspective.dst_px) * s
        for x in (dst[0, 0], dst[2, 0]):
            cv2.line(bird, (round(x), 0), (round(x), th - 1), (255, 0, 0), 1, cv2.LINE_AA)
        for fit in (self.check.left_fit, self.check.right_fit):
            if fit is not None:
                top, bottom = fit[1] * s[0], (fit[0] * (h - 1) + fit[1]) * s[0]
                cv2.line(mask, (round(top), 0), (round(bottom), th - 1), (0, 255, 0), 2, cv2.LINE_AA)
        return {"undistorted + src": road, "bird's-eye + dst": bird, "lane pixels + straight fits": mask}

    def readout(self) -> str:
        c, pc = self.check, self.config.perspective
        return (f"straight-line check: {c}\n"
                f"scale: {pc.xm_per_px * 1000:.3f} mm/px across, {pc.ym_per_px * 1000:.1f} mm/px "
                f"along; visible road {pc.visible_length_m:.1f} m")
