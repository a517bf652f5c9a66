"""``PerspectiveTuner``: the bird's-eye transform's four src corners and dst rectangle, set one by
one, by symmetric shortcuts, by clicks on the preview or estimated from the road itself
(``geometry.estimate_geometry``), with the straight-line check
(``perspective.straight_line_check``) as the measure of a good one. The estimate (``estimate``,
``set_geometry``) and its readout and drawing live in ``widgets/geometry_view.py``."""
from __future__ import annotations

import html
import math
from dataclasses import replace

import cv2
import ipyevents
import ipywidgets as widgets
import numpy as np

from .. import autogeometry, thresholds
from ..camera import MODEL_MARGIN, Calibration, Lens, Undistorter
from ..config import PipelineConfig
from ..draw import shrink
from ..errors import LaneLibError
from ..autogeometry import RoadGeometry
from ..perspective import (Homography, Perspective, PerspectiveConfig, implied_focal_px, road_length_m,
                           scaled, straight_line_check, trapezoid_src)
from .base import Tuner, row, sized
from .geometry_view import GeometryEstimate, draw_horizon, geometry_lines, low_confidence_line

SRC_KEYS = ("top_y", "top_width", "bottom_width", "centre_x")  # the symmetric src shortcut
KEYS = SRC_KEYS + ("dst_margin",)
CORNERS = ("tl", "bl", "br", "tr")  # the order of PerspectiveConfig.src_px and dst_px
CORNER_NAMES = {"tl": "top left", "bl": "bottom left", "br": "bottom right", "tr": "top right"}
SRC_POINT_KEYS = tuple(f"src.{c}.{a}" for c in CORNERS for a in ("x", "y"))
DST_KEYS = ("dst.left_x", "dst.right_x", "dst.top_y", "dst.bottom_y")
PLACE = "place_points"
ESTIMATE = "estimate"
ESTIMATE_LABELS = {False: "estimate from this frame", True: "estimate from this clip"}
STEP_PX = 0.1  # the symmetric sliders' step


def _trapezoid_of(src_px) -> dict[str, float]:
    """Return the least-squares symmetric summary of src points (tl, bl, br, tr).

    The symmetric trapezoid (``trapezoid_src``) nearest to the points in the sum of squared
    coordinate errors: each row's mean y, each row's width, and the mean of the two rows'
    centres. For a symmetric trapezoid these are its own values.
    """
    (tlx, tly), (blx, bly), (brx, bry), (trx, try_) = src_px
    return {"top_y": (tly + try_) / 2, "bottom_y": (bly + bry) / 2, "top_width": trx - tlx,
            "bottom_width": brx - blx, "centre_x": (tlx + trx + blx + brx) / 4}


def _rectangle_of(dst_px, width_px: float) -> dict[str, float]:
    """Return left_x, right_x, top_y, bottom_y and the symmetric dst_margin of dst points.

    Each value is the mean of the two corners on that side; ``dst_margin`` is the mean of the
    left line's and the right line's distance from their image edge (``width_px`` wide).
    """
    (tlx, tly), (blx, bly), (brx, bry), (trx, try_) = dst_px
    left, right = (tlx + blx) / 2, (trx + brx) / 2
    return {"left_x": left, "right_x": right, "top_y": (tly + try_) / 2, "bottom_y": (bly + bry) / 2,
            "dst_margin": (left + width_px - right) / 2}


def _rectangle(left_x: float, right_x: float, top_y: float, bottom_y: float) -> tuple:
    """Return the dst points (tl, bl, br, tr) of an upright rectangle; all arguments in px."""
    return ((left_x, top_y), (left_x, bottom_y), (right_x, bottom_y), (right_x, top_y))


def _slid(base: PerspectiveConfig, shown: dict[str, float], now: dict[str, float]) -> tuple:
    """Return the src and dst points of ``base`` moved by the symmetric sliders' changes.

    ``shown`` holds the symmetric sliders' values (``KEYS``) when the points were ``base``,
    ``now`` their values after a move. Each slider moves the corners by its change: ``top_y``
    the two top corners along y, ``top_width`` and ``bottom_width`` the two corners of their
    row apart by half of it each, ``centre_x`` all four along x, ``dst_margin`` both dst lines
    inwards (the symmetric trapezoid's change: ``trapezoid_src`` of the changes). Every corner
    keeps its offset from the symmetric summary: an off-centre set stays off-centre, and a
    coordinate no change moves keeps its exact value (a moved one is rounded to 0.01 px).
    """
    d = {k: now[k] - shown[k] for k in KEYS}
    m = d["dst_margin"]
    moves = (trapezoid_src(d["top_y"], 0.0, d["top_width"], d["bottom_width"], d["centre_x"]),
             ((m, 0.0), (m, 0.0), (-m, 0.0), (-m, 0.0)))
    return tuple(tuple((x if dx == 0 else round(x + dx, 2), y if dy == 0 else round(y + dy, 2))
                       for (x, y), (dx, dy) in zip(points, move))
                 for points, move in zip((base.src_px, base.dst_px), moves))


def _limits(pc: PerspectiveConfig) -> dict[str, float]:
    """Return the largest value of each slider for images of ``pc.size_px``."""
    w, h = pc.size_px
    return {"top_y": h - 1, "centre_x": w, "top_width": w, "bottom_width": 2 * w, "dst_margin": w / 2 - 1}


def _values(pc: PerspectiveConfig) -> dict[str, float]:
    """Return the value of every point control (symmetric and per corner) for ``pc``, in px.

    The symmetric sliders' values are the summary rounded to their step (``STEP_PX``), so that
    a slider moved away and back in the browser returns to the very value it showed.
    """
    w = pc.size_px[0]
    rect = _rectangle_of(pc.dst_px, w)
    out = {k: round(v, 1) for k, v in _trapezoid_of(pc.src_px).items() if k in SRC_KEYS}
    out["dst_margin"] = round(rect["dst_margin"], 1)
    for corner, (x, y) in zip(CORNERS, pc.src_px):
        out[f"src.{corner}.x"], out[f"src.{corner}.y"] = float(x), float(y)
    for side in ("left_x", "right_x", "top_y", "bottom_y"):
        out[f"dst.{side}"] = float(rect[side])
    return out


def _bounds(key: str, size_px: tuple[int, int]) -> tuple[float, float]:
    """Return (min, max) of the per-corner control ``key``: one image size beyond each edge."""
    w, h = size_px
    span = w if key.endswith("x") else h
    return -float(span), 2.0 * span


def carried_car_x(old: PerspectiveConfig, new: Perspective) -> float | None:
    """Return the bird's-eye x (px) of ``old``'s car centre line under the new points ``new``.

    ``old.car_x_px`` (set by an estimate: ``geometry.RoadGeometry.perspective_config``) is a
    line on the road; two of its points (the bird's-eye view's top and bottom rows) are mapped
    back to the undistorted frame through the old points and into the new view, and the result
    is where that line crosses the new view's bottom row, where the offset is measured. None
    when ``old`` has none (the default: where the image's bottom centre lands) or the line does
    not cross the new view's bottom row within one image width of it.
    """
    if old.car_x_px is None:
        return None
    if new.config.src_px == old.src_px and new.config.dst_px == old.dst_px:
        return old.car_x_px
    w, h = old.size_px
    image = Perspective(old).inverse([(old.car_x_px, 0.0), (old.car_x_px, h - 1.0)])
    (x0, y0), (x1, y1) = new(image)
    if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or abs(y1 - y0) < 1e-6:
        return None
    x = x0 + (h - 1.0 - y0) * (x1 - x0) / (y1 - y0)
    return round(float(x), 3) if -w <= x <= 2 * w else None


def click_to_frame(event: dict, tile_px: tuple[int, int], columns: int,
                   frame_px: tuple[int, int]) -> tuple[float, float] | None:
    """Return the frame pixel (x, y) of a click on the preview's first tile, or None elsewhere.

    Parameters
    ----------
    event : an ``ipyevents`` click: ``dataX``/``dataY`` are the clicked pixel of the preview
        image's own (natural) pixels, whatever size the browser shows it at. Without them,
        ``relativeX``/``relativeY`` scaled by ``boundingRectWidth``/``boundingRectHeight`` to
        the sheet's size (``columns`` tiles wide) are used.
    tile_px : (w, h) of one preview tile; the first tile (top left) is the undistorted frame.
    columns : the tiles per row of the preview sheet.
    frame_px : (w, h) of the undistorted frame the tile shows.
    """
    tw, th = tile_px
    if event.get("dataX") is not None and event.get("dataY") is not None:
        sx, sy = float(event["dataX"]), float(event["dataY"])
    elif event.get("boundingRectWidth") and event.get("boundingRectHeight"):
        sx = float(event["relativeX"]) * columns * tw / float(event["boundingRectWidth"])
        sy = float(event["relativeY"]) * th / float(event["boundingRectHeight"])
    else:
        return None
    if not (0 <= sx < tw and 0 <= sy < th):
        return None
    return round(sx * frame_px[0] / tw, 2), round(sy * frame_px[1] / th, 2)


class FastBirdseye:
    """Bird's-eye views of raw frames for any perspective, as the pipeline's remap makes them, quickly.

    The exact composed remap (``(lens.inverse + perspective).remap_maps``) is too slow for a
    slider. Here the undistortion map of a canvas ``MODEL_MARGIN`` larger on each side (as far as
    ``Lens.valid`` lets the pipeline sample) is made once, and a perspective's maps are that map
    warped by its inverse: within 2 grey levels of the pipeline's view (warping the undistorted
    frame instead interpolates twice and moves marginal line pixels).
    """

    def __init__(self, lens: Lens):
        w, h = lens.size
        self.pad = (int(w * MODEL_MARGIN), int(h * MODEL_MARGIN))
        self.map = lens.undistort_maps(self.pad, cv2.CV_32FC2)[0]
        self.size = (w, h)

    def birdseye(self, raw: np.ndarray, perspective: Homography) -> np.ndarray:
        """Return the bird's-eye view of a RAW frame for ``perspective`` (undistorted -> view)."""
        to_canvas = (np.array([[1, 0, self.pad[0]], [0, 1, self.pad[1]], [0, 0, 1]], float)
                     @ perspective.inverse.params)
        maps = cv2.warpPerspective(self.map, to_canvas, self.size,
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=(-1, -1, -1, -1))
        return cv2.remap(raw, maps, None, cv2.INTER_LINEAR)


class PerspectiveTuner(GeometryEstimate, Tuner):
    """Tune the bird's-eye transform: the four src corners and the dst rectangle.

    Three ways to set the points, all kept in step:

    - the symmetric shortcut, sliders ``top_y``, ``top_width``, ``bottom_width``, ``centre_x``
      (the src trapezoid's top row, its two widths and its centre; the bottom row stays) and
      ``dst_margin`` (the dst lines' distance from the left and right edges). A slider moves
      the corners by its change only (``top_y`` the top two along y, a width the two corners
      of its row apart, ``centre_x`` all four along x, ``dst_margin`` the dst lines inwards),
      so each corner keeps its offset from the symmetric trapezoid: an off-centre point set
      stays off-centre, and sliders moved away and back leave the perspective exactly as it
      was last set by any other way (a file, the per-corner controls, clicks, an estimate);
    - the per-corner controls in the "all four points" section: ``src.tl.x``, ``src.tl.y``, ...
      (corners tl, bl, br, tr, the order of ``PerspectiveConfig.src_px``) and ``dst.left_x``,
      ``dst.right_x``, ``dst.top_y``, ``dst.bottom_y``; each moves only its own corner or side.
      ``set_points`` sets all of them at once;
    - clicks on the undistorted frame (the preview's first tile; ``click``): the ``place_points``
      toggle arms it, the next four clicks give the corners tl, bl, br, tr, and after the fourth
      the four are set together (one corner at a time could pass through shapes that are no
      trapezoid) and the toggle disarms (``click_to_frame`` maps a click to frame pixels).
    - "estimate from this clip" (a video) or "estimate from this frame" (an image), the
      ``estimate`` button beside ``place_points``: the road geometry estimated from the road
      itself (``estimate``, ``set_geometry``) sets the src and dst points, the visible length
      and ``PerspectiveConfig.car_x_px`` (the car's centre line in the bird's-eye view). The
      readout adds the estimate's summary (vanishing point, horizon, scale, confidence) and
      what it assumed, and flags an estimate below ``geometry.LOW_CONFIDENCE`` ("low
      confidence: ... check the points before saving"); the preview draws its horizon and
      vanishing point on the undistorted frame until another item is picked. An estimate that
      fails (``GeometryError``: no road, too few segments, inconsistent, road not straight)
      shows its reason in red and leaves the points as they are.

    Whatever set the points, every control then shows them: the per-corner controls the exact
    points, the symmetric sliders the least-squares symmetric summary of the corners (each
    row's mean y and width, the mean of the two rows' centres, the mean dst margin; the very
    values for a symmetric config), rounded to their 0.1 px step. Showing the summary moves
    no point.

    The preview shows the src quadrilateral on the undistorted frame, the bird's-eye view with
    the dst lines, and the bird's-eye lane mask with the straight fits of the straight-line
    check; the readout gives the check as numbers. Moving the src corners keeps the lane width
    in metres and updates the visible road length to the same camera
    (``perspective.road_length_m`` from the rows' widths, with the focal length the starting
    config implies), so the metric scale stays right. Moving points by hand after an estimate
    keeps its car centre line as a line on the road (``carried_car_x``: the same line, seen
    through the new points; a config without ``car_x_px`` keeps None, where the image's
    bottom centre lands). ``save`` writes the ``perspective`` part (with ``car_x_px``);
    ``load`` reads it and the ``thresholds`` and ``search`` parts the check uses.

    ``geometry_options`` (an ``autogeometry.GeometryOptions``) is what the estimate button uses: 20 s
    of a clip from its start, 50 frames, 3.7 m lanes, a 25 m look-ahead, and
    ``accept_low_confidence`` on (a low-confidence estimate is applied and flagged, not
    refused); set it, or pass options to ``estimate``, to change them.
    """

    columns = 3
    default_tile_width_px = 400
    parts = ("perspective",)
    shows = ("perspective", "thresholds", "search")

    # ---- public ---------------------------------------------------------------------------

    def set_points(self, src_px, dst_px, visible_length_m: float | None = None) -> PipelineConfig:
        """Set exactly these src and dst points; return the new config.

        Parameters
        ----------
        src_px : four (x, y) points (tl, bl, br, tr) in px of the picked undistorted frame.
        dst_px : the same four corners in the bird's-eye view, in px.
        visible_length_m : the real road length between the dst rows; None: computed for the
            tuner's camera from the src rows' widths (``perspective.road_length_m``).

        Raises ``ConfigError`` for points that are no trapezoid of road ahead (collinear or
        repeated points, a top row not narrower than the bottom one). The car's centre line
        (``car_x_px``) of an earlier estimate is carried over (``carried_car_x``).
        """
        new = self._points_config(src_px, dst_px, visible_length_m)
        self.error = ""
        self._pending = []
        self._show(replace(self.config, perspective=new))
        self._update(None)
        self._refresh()
        return self.config

    def click(self, x: float, y: float) -> None:
        """Do what a click at pixel (x, y) of the preview image does.

        Parameters
        ----------
        x, y : the pixel, in the preview image's own pixels (ipyevents' ``dataX``, ``dataY``).
            While ``place_points`` is armed, a pixel on the undistorted frame (the first tile) is
            the next src corner; the fourth sets the four (the dst stays) and disarms the toggle,
            or the readout says why they are no trapezoid. Otherwise the click is ignored.
        """
        self._on_click({"type": "click", "dataX": x, "dataY": y})

    # ---- hooks ----------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        pc = self.config.perspective
        values, top = _values(pc), _limits(pc)
        self._pending: list[tuple[float, float]] = []
        sl = lambda key, desc: self._control(key, widgets.FloatSlider(  # noqa: E731
            value=values[key], min=0.0, max=float(top[key]), step=STEP_PX, description=desc,
            readout_format=".1f", **sized(460, 150)))

        def box(key: str, desc: str) -> widgets.Widget:
            low, high = _bounds(key, pc.size_px)
            return self._control(key, widgets.BoundedFloatText(
                value=values[key], min=low, max=high, step=0.1, description=desc, **sized(200, 110)))

        src_rows = [row(box(f"src.{c}.x", f"{CORNER_NAMES[c]} x"), box(f"src.{c}.y", "y"))
                    for c in CORNERS]
        dst_rows = [row(box("dst.left_x", "dst left x"), box("dst.right_x", "right x")),
                    row(box("dst.top_y", "dst top y"), box("dst.bottom_y", "bottom y"))]
        points = widgets.Accordion(
            children=[widgets.VBox([widgets.HTML("src corners (undistorted frame, px):"), *src_rows,
                                    widgets.HTML("dst rectangle (bird's-eye view, px):"), *dst_rows])],
            titles=("all four points",), selected_index=None)
        points.add_class("lanelib-points")
        self.place = widgets.ToggleButton(value=False, description="place points", icon="crosshairs",
                                          tooltip="then click tl, bl, br, tr on the undistorted frame")
        self.place.add_class(f"lanelib-control-{PLACE}")
        self.place.observe(self._on_place, names="value")
        self._events = ipyevents.Event(source=self.preview, watched_events=["click"],
                                       prevent_default_action=True)
        self._events.on_dom_event(self._on_click)
        self.geometry_options = autogeometry.GeometryOptions(accept_low_confidence=True)
        self.geometry: RoadGeometry | None = None  # the last estimate for the picked item
        self._geometry: tuple[str, PerspectiveConfig, str] | None = None  # (item, its points, source)
        self.estimate_button = widgets.Button(description=ESTIMATE_LABELS[False], icon="road",
                                              tooltip="estimate the points from the road itself "
                                                      "(vanishing point, horizon, lane width, dashes)",
                                              layout=widgets.Layout(width="200px"))
        self.estimate_button.add_class(f"lanelib-control-{ESTIMATE}")
        self.estimate_button.on_click(self._on_estimate)
        rows = [row(sl("top_y", "top y (px)"), sl("centre_x", "centre x (px)")),
                row(sl("top_width", "top width (px)"), sl("bottom_width", "bottom width (px)")),
                row(sl("dst_margin", "dst margin (px)"), self.place, self.estimate_button),
                points]
        # the points the symmetric sliders move from, and the values they showed with them
        self._anchor = (pc, {k: float(self.controls[k].value) for k in KEYS})
        return rows

    def _sync(self) -> None:
        self._set_controls(self.config.perspective, skip=None)

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        size = (raw.shape[1], raw.shape[0])
        undistorter = self._cached("undistorter", (id(calibration), size),
                                   lambda: Undistorter(calibration, size))
        self._canvas = self._cached("canvas", (id(calibration), size),
                                    lambda: FastBirdseye(undistorter.lens))
        if tuple(self.config.perspective.size_px) != size:  # after the lens took this size
            self._show(replace(self.config, perspective=scaled(self.config.perspective, size)))
        self.undistorted = undistorter.undistort(raw)
        self._focal_px = implied_focal_px(self.config.perspective)
        self._small = shrink(self.undistorted, self._tile_size())
        self._pending = []
        self.estimate_button.description = ESTIMATE_LABELS[self.is_video]
        if self._geometry is not None and self._geometry[0] != self.image:
            self.geometry, self._geometry = None, None  # another item: perhaps another camera

    def _apply(self, key: str) -> PipelineConfig:
        pc = self.config.perspective
        v = {k: float(self.controls[k].value) for k in self.controls}
        src, dst = pc.src_px, pc.dst_px
        if key in KEYS:  # moved from the points as last set otherwise, and back to them exactly
            base, shown = self._anchor
            src, dst = _slid(base, shown, v)
            length = base.visible_length_m if src == base.src_px else None
            return replace(self.config, perspective=self._points_config(src, dst, length, base))
        if key in SRC_POINT_KEYS:
            _, corner, axis = key.split(".")
            i = CORNERS.index(corner)
            point = list(src[i])
            point["xy".index(axis)] = v[key]
            src = tuple(tuple(point) if j == i else p for j, p in enumerate(src))
        elif key in DST_KEYS:
            dst = _rectangle(*(v[k] for k in DST_KEYS))
        length = pc.visible_length_m if src == pc.src_px else None
        return replace(self.config, perspective=self._points_config(src, dst, length))

    def _update(self, key: str | None) -> None:
        """Warp, threshold and check the picked frame; show the new points in the other controls."""
        if key is not None:
            self._set_controls(self.config.perspective, skip=key)
        self.perspective = Perspective(self.config.perspective)
        self.birdseye = self._canvas.birdseye(self._raw, self.perspective)
        self.binary = thresholds.combine(self.birdseye, self.config.thresholds)
        self.check = straight_line_check(self.binary, self.perspective.xm_per_px,
                                         self.config.search, self.perspective.car_x_px)

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the undistorted frame with the src corners, the bird's-eye view, and its mask."""
        tw, th = self._tile_size()
        h, w = self.undistorted.shape[:2]
        s = np.array([tw / w, th / h])
        road = self._small.copy()
        if self.geometry is not None:
            draw_horizon(road, self.geometry)
        src = np.round(np.asarray(self.config.perspective.src_px) * s).astype(np.int32)
        cv2.polylines(road, [src.reshape(-1, 1, 2)], True, (255, 0, 0), 2, cv2.LINE_AA)
        for x, y in self._pending:
            cv2.circle(road, (round(x * s[0]), round(y * s[1])), 4, (255, 255, 0), -1, cv2.LINE_AA)
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
        text = (f"straight-line check: {c}\n"
                f"scale: {pc.xm_per_px * 1000:.3f} mm/px across, {pc.ym_per_px * 1000:.1f} mm/px "
                f"along; visible road {pc.visible_length_m:.1f} m")
        if self.place.value:
            corner = CORNERS[len(self._pending)]
            text += (f"\nplacing points: click the {CORNER_NAMES[corner]} corner on the undistorted "
                     f"frame ({len(self._pending) + 1} of 4)")
        if self.geometry is not None:
            text += "\n" + "\n".join(geometry_lines(self.geometry, *self._geometry[1:], self.config.perspective))
        return text

    # ---- points and clicks ----------------------------------------------------------------

    def _points_config(self, src_px, dst_px, visible_length_m: float | None,
                       base: PerspectiveConfig | None = None) -> PerspectiveConfig:
        """Return the perspective with these points (length None: from the camera); refuse bad ones.

        The size, the lane width and the car's centre line (``carried_car_x``) come from
        ``base`` (default: the tuner's perspective).
        """
        pc = base if base is not None else self.config.perspective
        src = tuple((float(x), float(y)) for x, y in src_px)
        dst = tuple((float(x), float(y)) for x, y in dst_px)
        if visible_length_m is None:
            visible_length_m = round(road_length_m(src, pc.lane_width_m, self._focal_px), 3)
        new = PerspectiveConfig(src, dst, pc.size_px, pc.lane_width_m, visible_length_m)
        warp = Perspective(new)  # refuses collinear points with a ConfigError
        car_x = carried_car_x(pc, warp)
        return new if car_x is None else replace(new, car_x_px=car_x)

    def _set_controls(self, pc: PerspectiveConfig, skip: str | None) -> None:
        """Show ``pc`` in every point control but ``skip`` (the one the user moved), quietly.

        After a symmetric slider's move the symmetric sliders keep their values (each moved
        the summary by its own change only); after anything else they show the summary of
        ``pc``, which becomes the points the symmetric sliders move from (``_anchor``).
        """
        values = _values(pc)
        if skip in KEYS:
            values = {k: v for k, v in values.items() if k not in KEYS}
        with self._quiet():
            for key, top in _limits(pc).items():
                self.controls[key].max = float(top)
            for key in SRC_POINT_KEYS + DST_KEYS:
                self.controls[key].min, self.controls[key].max = _bounds(key, pc.size_px)
            for key, value in values.items():
                if key != skip and abs(float(self.controls[key].value) - value) > 1e-9:
                    self.controls[key].value = value
        if skip not in KEYS:
            self._anchor = (pc, {k: float(self.controls[k].value) for k in KEYS})

    def _on_place(self, change) -> None:
        self._pending = []
        self._refresh()

    def _on_click(self, event: dict) -> None:
        """Take an ``ipyevents`` click on the preview as ``click`` does (``click_to_frame``)."""
        if not self.place.value:
            return
        h, w = self.undistorted.shape[:2]
        point = click_to_frame(event, self._tile_size(), self.columns, (w, h))
        if point is None:
            return
        self._pending.append(point)
        if len(self._pending) < len(CORNERS):
            self._refresh()
            return
        src = self._pending
        self.place.value = False  # disarms: _on_place drops the collected clicks and refreshes
        try:
            self.set_points(src, self.config.perspective.dst_px)
        except LaneLibError as e:
            self._show_error(f"placed points {src}: {e}")

    def _refresh(self) -> None:
        super()._refresh()
        flag = low_confidence_line(self.geometry)
        if flag:  # the flag in orange, the rest as the base shows it
            text = html.escape(self.readout()).replace(
                html.escape(flag), f'<b style="color:#c60">{html.escape(flag)}</b>')
            self.message.value = f'<pre style="margin:0">{text}</pre>'
