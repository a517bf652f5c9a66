"""``HoughTuner``: the basic Canny + region of interest + Hough pipeline (``PipelineConfig.hough``)
on the raw frame; its picker adds the 960x540 Udacity P1 images."""
from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Mapping

import cv2
import ipywidgets as widgets
import numpy as np

from .. import hough, io
from ..camera import Calibration
from ..config import PipelineConfig
from ..data import UDACITY_ADVANCED, UDACITY_P1, bundled, data_root
from ..draw import shrink
from .base import Tuner, row, sized
from .choices import UDACITY_PREFIX

UDACITY_P1_PREFIX = "udacity-p1/"
_PLAIN_KEYS = ("blur_kernel_px", "rho_px", "theta_deg", "threshold_votes", "min_line_length_px",
               "max_line_gap_px", "min_abs_slope")
COLORS = ("white", "yellow")  # the paint colours of HoughConfig: <colour>_hls_lo, <colour>_hls_hi
HLS_MAX = (179, 255, 255)  # OpenCV's 8-bit HLS: H in 0..179 (degrees / 2), L and S in 0..255
COLOR_KEYS = tuple(f"{c}.range{i}" for c in COLORS for i in range(3))


def hough_image_choices(root: str | os.PathLike | None = None,
                        data: str | os.PathLike | None = None) -> dict[str, Path]:
    """Return the Hough tuner's images: label -> path, bundled ``test_images/`` first.

    The 960x540 images of ``udacity-lanelines-p1/test_images`` follow as ``"udacity-p1/<name>"``
    and the Udacity highway images as ``"udacity/<name>"``, each when ``data`` (default
    ``data_root()``) holds them.
    """
    out = {p.name: p for p in io.list_images(bundled("test_images", root))}
    data = Path(data if data is not None else data_root())
    p1 = data / UDACITY_P1 / "test_images"
    if p1.is_dir():
        out.update({UDACITY_P1_PREFIX + p.name: p for p in io.list_images(p1)})
    adv = data / UDACITY_ADVANCED / "test_images"
    if adv.is_dir():
        out.update({UDACITY_PREFIX + p.name: p for p in io.list_images(adv)})
    return out


def _roi_fractions(roi_frac) -> dict[str, float]:
    """Return top_y and the four corner x fractions of a 4-vertex region (bl, tl, tr, br)."""
    pts = list(roi_frac)
    if len(pts) != 4:  # a polygon of another shape: its bounding trapezoid
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        return {"top_y": min(ys), "top_left": min(xs), "top_right": max(xs),
                "bottom_left": min(xs), "bottom_right": max(xs)}
    (blx, _), (tlx, tly), (trx, try_), (brx, _) = pts
    return {"top_y": (tly + try_) / 2, "top_left": tlx, "top_right": trx,
            "bottom_left": blx, "bottom_right": brx}


def _shown(lo: int, hi: int, top: int) -> tuple[int, int]:
    """Return a channel's (low, high) bounds as a range slider up to ``top`` can show them."""
    lo, hi = (min(max(int(v), 0), top) for v in (lo, hi))
    return (min(lo, hi), max(lo, hi))


class HoughTuner(Tuner):
    """Tune the basic Canny + region of interest + Hough pipeline (``PipelineConfig.hough``).

    Controls: ``blur_kernel_px``, ``canny`` (low, high), ``rho_px``, ``theta_deg``,
    ``threshold_votes``, ``min_line_length_px``, ``max_line_gap_px``, ``min_abs_slope`` and the
    region of interest as fractions of the image: ``roi.top_y``, ``roi.top_left``,
    ``roi.top_right``, ``roi.bottom_left``, ``roi.bottom_right`` (the x of each corner; the bottom
    row stays where the config has it); the colour selection, one low-high range per HLS
    channel of each paint: ``white.range0`` .. ``white.range2`` (H 0-179, L, S 0-255:
    ``white_hls_lo``/``white_hls_hi``) and ``yellow.range0`` .. ``yellow.range2``
    (``yellow_hls_lo``/``yellow_hls_hi``), as ``ThresholdTuner`` shows its colour ranges. Moving
    one range rewrites only its paint's bounds (a loaded low bound above the high one shows
    sorted and is kept until its paint's ranges move). The preview shows the white and yellow
    selection (inside the region's bounding box, the part the pipeline processes), the Canny
    edges, the edges inside the region (outlined), the Hough segments coloured by side and the
    two lane lines on the frame.

    The Hough pipeline works on raw frames (no undistortion), so no calibration is used. A change
    reruns ``hough.HoughLaneFinder.process`` on the picked frame (only the region's bounding box
    is processed, a few ms at 1280x720), so the preview is exactly what a ``python -m lanelib
    hough`` run does. ``save`` writes the ``hough`` part; ``load`` reads only that part.
    """

    columns = 3
    default_tile_width_px = 400
    parts = ("hough",)
    shows = ("hough",)
    ROI_KEYS = ("roi.top_y", "roi.top_left", "roi.top_right", "roi.bottom_left", "roi.bottom_right")

    def __init__(self, images: Mapping[str, str | os.PathLike] | str | os.PathLike | None = None,
                 config: PipelineConfig = PipelineConfig(), image: str | None = None,
                 tile_width_px: int | None = None, jpeg_quality: int = 80):
        super().__init__(images if images is not None else hough_image_choices(), config, None,
                         image, tile_width_px, jpeg_quality)

    # ---- building -------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        hc = self.config.hough
        roi = _roi_fractions(hc.roi_frac)
        isl = lambda key, value, lo, hi, desc: self._control(key, widgets.IntSlider(  # noqa: E731
            value=value, min=lo, max=hi, description=desc, **sized(420, 150)))
        fsl = lambda key, value, lo, hi, step, desc, fmt=".2f": self._control(  # noqa: E731
            key, widgets.FloatSlider(value=value, min=lo, max=hi, step=step, description=desc,
                                     readout_format=fmt, **sized(420, 150)))
        return [
            row(self._control("blur_kernel_px", widgets.Dropdown(
                    options=sorted({1, 3, 5, 7, 9, 11, 13, 15, hc.blur_kernel_px}), value=hc.blur_kernel_px,
                    description="blur kernel (px)", **sized(260, 150))),
                self._control("canny", widgets.IntRangeSlider(
                    value=(hc.canny_low, hc.canny_high), min=0, max=500,
                    description="Canny low, high", **sized(420, 150)))),
            row(fsl("rho_px", hc.rho_px, 0.5, 5.0, 0.5, "rho (px)", ".1f"),
                fsl("theta_deg", hc.theta_deg, 0.25, 5.0, 0.25, "theta (deg)")),
            row(isl("threshold_votes", hc.threshold_votes, 1, 200, "threshold (votes)"),
                isl("min_line_length_px", hc.min_line_length_px, 0, 300, "min length (px)")),
            row(isl("max_line_gap_px", hc.max_line_gap_px, 0, 300, "max gap (px)"),
                fsl("min_abs_slope", hc.min_abs_slope, 0.0, 3.0, 0.05, "min |slope|")),
            row(fsl("roi.top_y", roi["top_y"], 0.0, 1.0, 0.01, "ROI top y"),
                fsl("roi.top_left", roi["top_left"], 0.0, 1.0, 0.01, "ROI top left x")),
            row(fsl("roi.top_right", roi["top_right"], 0.0, 1.0, 0.01, "ROI top right x"),
                fsl("roi.bottom_left", roi["bottom_left"], 0.0, 1.0, 0.01, "ROI bottom left x")),
            row(fsl("roi.bottom_right", roi["bottom_right"], 0.0, 1.0, 0.01, "ROI bottom right x")),
            *(row(widgets.HTML(f"{color} paint (HLS)", layout=widgets.Layout(width="120px")),
                  *(self._control(f"{color}.range{i}", widgets.IntRangeSlider(
                      value=_shown(lo, hi, top), min=0, max=top, description=letter,
                      **sized(260, 20)))
                    for i, (letter, lo, hi, top) in enumerate(zip(
                        "HLS", getattr(hc, f"{color}_hls_lo"), getattr(hc, f"{color}_hls_hi"), HLS_MAX))))
              for color in COLORS),
        ]

    def _sync(self) -> None:
        hc, c = self.config.hough, self.controls
        for key in _PLAIN_KEYS:
            c[key].value = getattr(hc, key)
        c["canny"].value = (hc.canny_low, hc.canny_high)
        for key, value in _roi_fractions(hc.roi_frac).items():
            c[f"roi.{key}"].value = value
        for color in COLORS:
            for i, (lo, hi, top) in enumerate(zip(getattr(hc, f"{color}_hls_lo"),
                                                  getattr(hc, f"{color}_hls_hi"), HLS_MAX)):
                c[f"{color}.range{i}"].value = _shown(lo, hi, top)

    def calibration_for(self, label: str) -> Calibration | None:
        """Return None for every item: the Hough pipeline works on the raw frame, undistorted by no
        camera's calibration."""
        return None

    # ---- config <-> controls --------------------------------------------------------------

    def _apply(self, key: str) -> PipelineConfig:
        c, hc = self.controls, self.config.hough
        low, high = c["canny"].value
        bottom_y = max(y for _, y in hc.roi_frac) if len(hc.roi_frac) == 4 else 1.0
        roi = hc.roi_frac
        if key.startswith("roi."):
            v = {k: round(float(c[k].value), 4) for k in self.ROI_KEYS}
            roi = ((v["roi.bottom_left"], bottom_y), (v["roi.top_left"], v["roi.top_y"]),
                   (v["roi.top_right"], v["roi.top_y"]), (v["roi.bottom_right"], bottom_y))
        new = replace(hc, blur_kernel_px=int(c["blur_kernel_px"].value), canny_low=int(low),
                      canny_high=int(high), roi_frac=roi, rho_px=float(c["rho_px"].value),
                      theta_deg=float(c["theta_deg"].value),
                      threshold_votes=int(c["threshold_votes"].value),
                      min_line_length_px=int(c["min_line_length_px"].value),
                      max_line_gap_px=int(c["max_line_gap_px"].value),
                      min_abs_slope=round(float(c["min_abs_slope"].value), 4))
        if key in COLOR_KEYS:  # only the moved paint's bounds: the other keeps the config's
            color = key.partition(".")[0]
            ranges = [c[f"{color}.range{i}"].value for i in range(3)]
            new = replace(new, **{f"{color}_hls_lo": tuple(int(r[0]) for r in ranges),
                                  f"{color}_hls_hi": tuple(int(r[1]) for r in ranges)})
        return replace(self.config, hough=new)

    # ---- the pipeline ---------------------------------------------------------------------

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        self.rgb = io.check_rgb(raw)
        self._small = shrink(self.rgb, self._tile_size())

    def _update(self, key: str | None) -> None:
        """Run the Hough pipeline on the picked frame with the current config, keeping the stages."""
        finder = self._cached("finder", self.config.hough,
                              lambda: hough.HoughLaneFinder(self.config.hough))
        self.result = finder.process(self.rgb, keep_stages=True)
        self.stages = self.result.stages

    # ---- views ----------------------------------------------------------------------------

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the colour selection, the Canny edges, the edges in the region, the Hough
        segments and the lines."""
        tw, th = self._tile_size()
        h, w = self.rgb.shape[:2]
        scale = np.array([tw / w, th / h, tw / w, th / h])
        st = self.stages
        roi_view = cv2.cvtColor(shrink(st.roi_edges, (tw, th)), cv2.COLOR_GRAY2RGB)
        poly = np.asarray(self.config.hough.roi_frac) * (w - 1, h - 1) * scale[:2]
        cv2.polylines(roi_view, [np.rint(poly).astype(np.int32).reshape(-1, 1, 2)], True,
                      (0, 255, 0), 1, cv2.LINE_AA)
        segs = self._small
        for group, color in ((st.segments, (255, 255, 0)), (st.left_segments, hough.LEFT_COLOR_RGB),
                             (st.right_segments, hough.RIGHT_COLOR_RGB)):
            if len(group):  # every segment yellow, then the kept ones in their side's colour
                segs = hough.draw_lines(segs, np.rint(group * scale).astype(np.int32), color, 2)
        lines = shrink(hough.annotate(self.rgb, self.result), (tw, th))
        return {"white/yellow selection (in the region's box)": st.color_mask, "Canny edges": st.edges,
                "edges in the region": roi_view, "Hough segments (left red, right blue)": segs,
                "lane lines": lines}

    def annotated(self) -> np.ndarray:
        """Return the picked frame with the Hough lines drawn (``hough.annotate``), as ``python -m
        lanelib hough`` writes it for an image with the tuner's ``hough`` config (a video frame
        too: found on its own, without the smoothing across frames of a video run)."""
        return hough.annotate(self.rgb, self.result)

    def readout(self) -> str:
        r = self.result
        parts = []
        for side, line, n in (("left", r.left, r.n_left_segments),
                              ("right", r.right, r.n_right_segments)):
            where = ("no line" if line is None else
                     f"x {line.x_bottom_px:.0f} px at the bottom, {line.x_top_px:.0f} px at the top")
            parts.append(f"{side}: {n} segments, {where}")
        text = f"{len(self.stages.segments)} Hough segments; " + "; ".join(parts)
        return text + (f"\n{r.reason}" if r.reason else "")
