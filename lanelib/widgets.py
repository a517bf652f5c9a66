"""Interactive tuners for the notebooks: controls that edit a ``PipelineConfig`` and a live preview.

A tuner shows an image picker, its controls, one persistent ``ipywidgets.Image`` holding JPEG bytes
of a downscaled sheet of named views, and a text readout of the numbers that matter. Controls are
plain ipywidgets wired with ``observe`` (no ``interact()``, no matplotlib re-draw, no debounce):
a change rebuilds ``tuner.config``, recomputes only what that control affects, and replaces the
preview's bytes. What does not depend on the controls (the undistorted frame, the bird's-eye view,
colour conversions, the lane mask) is computed once per picked image.

- ``ThresholdTuner``: every mask of ``ThresholdConfig`` on the bird's-eye view (on/off, colour
  space and channel, low/high range, Sobel kernel, top-hat width) and the rule that combines them.
- ``PerspectiveTuner``: the src trapezoid (top y, top width, bottom width, centre x) and the dst
  margin; the trapezoid on the undistorted frame, the bird's-eye view and the straight-line check.
- ``FitTuner``: sliding windows (number, margin, minimum pixels) and the search around a fit.
- ``HoughTuner``: the basic pipeline's Canny thresholds, Hough parameters and region of interest
  (``PipelineConfig.hough``), on the raw frame; its picker adds the 960x540 Udacity P1 images.

Each tuner holds its ``PipelineConfig`` in ``tuner.config``; ``tuner.save(path)`` writes the JSON
that ``python -m lanelib images|video --config`` reads and ``tuner.load(path)`` reads one back into
the controls. Show a tuner by making it the last expression of a cell (or ``display(tuner)``): the
widget appears in JupyterLab and the text output is a short, stable line for nbval.

Every control is in ``tuner.controls`` under a key (``"white.range1"``, ``"top_y"``, ...). Sliders
carry the CSS class ``lanelib-slider-<key with '.' as '-'>`` (e.g. ``lanelib-slider-top_y``,
``lanelib-slider-white-range1``), other controls ``lanelib-control-<key>``; the preview Image
carries ``lanelib-preview``, the picker ``lanelib-picker`` and the readout ``lanelib-readout``.

A new tuner (e.g. for the Hough pipeline) subclasses ``Tuner`` and implements ``_build``,
``_prepare``, ``_apply``, ``_sync``, ``render`` and ``readout`` (see ``Tuner``).
"""
from __future__ import annotations

import html
import math
import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Mapping

import cv2
import ipywidgets as widgets
import numpy as np

from . import draw, hough, io, lanes, thresholds
from .camera import Calibration, FastBirdseye, Undistorter, calibrate
from .config import PipelineConfig, load_config, save_config
from .errors import InputError, LaneLibError
from .perspective import (Perspective, PerspectiveConfig, implied_focal_px, road_length_m, scaled,
                          trapezoid_src)
from .pipeline import LanePipeline

UDACITY_PREFIX = "udacity/"
UDACITY_ADVANCED = "udacity-advanced"


# --------------------------------------------------------------------------- where the data is

def repo_root(start: str | os.PathLike | None = None) -> Path:
    """Return the repository folder: the first folder holding ``test_images/``, walking up.

    Parameters
    ----------
    start : folder to start from (default: the current folder, e.g. ``notebooks/``).

    Raises
    ------
    InputError
        If neither ``start`` nor any folder above it holds ``test_images/``.
    """
    here = Path(start if start is not None else os.getcwd()).resolve()
    for folder in (here, *here.parents):
        if (folder / "test_images").is_dir():
            return folder
    raise InputError(f"{here}: no folder holding test_images/ here or above; run the notebook "
                     "from inside the lanelib repository or pass the repository folder")


def data_root(root: str | os.PathLike | None = None) -> Path:
    """Return the folder of the Udacity data: ``$LANELIB_DATA``, else ``<repo>/../shared/data``."""
    env = os.environ.get("LANELIB_DATA")
    if env:
        return Path(env)
    return Path(root if root is not None else repo_root()).resolve().parent / "shared" / "data"


def image_choices(root: str | os.PathLike | None = None,
                  data: str | os.PathLike | None = None) -> dict[str, Path]:
    """Return the picker's images: label -> path, bundled ``test_images/`` first.

    Bundled images are labelled by file name; the Udacity test images, when ``data`` (default
    ``data_root()``) holds ``udacity-advanced/test_images``, follow as ``"udacity/<name>"``.
    """
    root = repo_root(root)
    out = {p.name: p for p in io.list_images(root / "test_images")}
    extra = Path(data if data is not None else data_root(root)) / UDACITY_ADVANCED / "test_images"
    if extra.is_dir():
        out.update({UDACITY_PREFIX + p.name: p for p in io.list_images(extra)})
    return out


# --------------------------------------------------------------------------- preview sheet

def shrink(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Return ``image`` resized down to ``size`` (w, h): halved by area averaging, then linear.

    OpenCV's area averaging is fast for an exact factor of 2 and slow for others, so the image is
    halved while it is at least twice the target, and the rest is done by linear interpolation.
    """
    w, h = size
    while image.shape[1] >= 2 * w and image.shape[0] >= 2 * h:
        image = cv2.resize(image, (image.shape[1] // 2, image.shape[0] // 2),
                           interpolation=cv2.INTER_AREA)
    if (image.shape[1], image.shape[0]) == (w, h):
        return image
    return cv2.resize(image, (w, h), interpolation=cv2.INTER_LINEAR)


def sheet(views: Mapping[str, np.ndarray | None], tile_width_px: int = 320,
          columns: int = 3) -> np.ndarray:
    """Return the named views (RGB images or masks, None for "off") as one labelled RGB grid.

    Every tile is ``tile_width_px`` wide with the aspect of the first view; views are resized
    by ``shrink``, so the grid is cheap to make and to encode.
    """
    shown = [v for v in views.values() if v is not None]
    if not shown:
        raise InputError("sheet: no views to show")
    h0, w0 = shown[0].shape[:2]
    tw, th = int(tile_width_px), max(1, round(tile_width_px * h0 / w0))
    n = len(views)
    cols = max(1, min(columns, n))
    rows = -(-n // cols)
    out = np.zeros((rows * th, cols * tw, 3), np.uint8)
    scale = tw / 640
    thick = max(1, round(2 * scale))
    for i, (label, img) in enumerate(views.items()):
        if img is None:
            tile = np.full((th, tw, 3), 48, np.uint8)
            label = f"{label} (off)"
        else:
            tile = shrink(img, (tw, th))
            if tile.ndim == 2:
                tile = cv2.cvtColor(tile, cv2.COLOR_GRAY2RGB)
            elif tile is img:
                tile = tile.copy()  # the label is drawn on the tile, never on the caller's view
        (tw_txt, th_txt), base = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        cv2.rectangle(tile, (0, 0), (tw_txt + 8, th_txt + base + 8), (0, 0, 0), -1)
        cv2.putText(tile, label, (4, th_txt + 4), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 0),
                    thick, cv2.LINE_AA)
        r, c = divmod(i, cols)
        out[r * th:(r + 1) * th, c * tw:(c + 1) * tw] = tile
    return out


# --------------------------------------------------------------------------- base class

class Tuner:
    """Shared machinery of the tuners: image picker, controls, preview Image, readout, save/load.

    Parameters
    ----------
    images : label -> image path for the picker (default: ``image_choices()``).
    config : the PipelineConfig to start from.
    calibration : the camera of the bundled images (None: frames are taken as undistorted).
        Images labelled ``"udacity/..."`` use the Udacity camera, calibrated from its
        ``camera_cal/`` the first time one of them is picked.
    image : label of the image to show first (default: the first one).
    tile_width_px : width of one view in the preview sheet.
    jpeg_quality : JPEG quality of the preview bytes.

    A subclass implements

    - ``_build()``: make its controls with ``self._control(key, widget)``; return the rows of
      widgets laid out between the picker and the preview;
    - ``_prepare(raw, calibration)``: compute what depends only on the picked image;
    - ``_apply(key)``: return the new PipelineConfig after control ``key`` changed (raise
      ``LaneLibError`` to refuse the value: the readout then shows why);
    - ``_sync()``: set the controls from ``self.config`` (after ``load``);
    - ``render()``: the named views of the preview; ``readout()``: the numbers as text.
    """

    columns = 3
    default_tile_width_px = 400

    def __init__(self, images: Mapping[str, str | os.PathLike] | None = None,
                 config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                 image: str | None = None, tile_width_px: int | None = None, jpeg_quality: int = 80):
        self.images = {k: Path(v) for k, v in (images if images is not None else image_choices()).items()}
        if not self.images:
            raise InputError("tuner: no images to show; pass images={label: path} or add test_images/")
        image = image if image is not None else next(iter(self.images))
        if image not in self.images:
            raise InputError(f"tuner: image {image!r} is not among the picker's images "
                             f"({', '.join(self.images)})")
        self._config = config
        self._calibrations: dict[str, Calibration | None] = {"bundled": calibration}
        self.tile_width_px = int(tile_width_px or self.default_tile_width_px)
        self.jpeg_quality = int(jpeg_quality)
        self.controls: dict[str, widgets.Widget] = {}
        self._syncing = False
        self._widget: widgets.Widget | None = None
        self.error = ""
        self.picker = widgets.Dropdown(options=list(self.images), value=image, description="image",
                                       layout=widgets.Layout(width="420px"))
        self.picker.add_class("lanelib-picker")
        self.preview = widgets.Image(format="jpeg", layout=widgets.Layout(max_width="100%"))
        self.preview.add_class("lanelib-preview")
        self.message = widgets.HTML()
        self.message.add_class("lanelib-readout")
        self._rows = self._build()
        self._pick(image)
        self.picker.observe(self._on_pick, names="value")

    # ---- public ---------------------------------------------------------------------------

    @property
    def config(self) -> PipelineConfig:
        """The PipelineConfig the controls currently describe."""
        return self._config

    @property
    def image(self) -> str:
        """Label of the picked image."""
        return self.picker.value

    @property
    def widget(self) -> widgets.VBox:
        """The tuner's widget: picker, controls, preview and readout (made once)."""
        if self._widget is None:
            self._widget = widgets.VBox([self.picker, *self._rows, self.preview, self.message])
            self._widget.add_class("lanelib-tuner")
        return self._widget

    def preview_sheet(self) -> np.ndarray:
        """Return the preview as an RGB array (what the Image shows, before JPEG encoding)."""
        return sheet(self.render(), self.tile_width_px, self.columns)

    def set_config(self, config: PipelineConfig) -> None:
        """Show ``config`` in the controls and the preview."""
        self._config = config
        self._syncing = True
        try:
            self._sync()
        finally:
            self._syncing = False
        self._prepare(self._raw, self._calibration_for(self.image))
        self._refresh()

    def save(self, path: str | os.PathLike) -> Path:
        """Write the tuned PipelineConfig as JSON (the file the CLI's ``--config`` reads)."""
        return save_config(self.config, path)

    def load(self, path: str | os.PathLike) -> PipelineConfig:
        """Read a PipelineConfig JSON into the controls and the preview; return it."""
        config = load_config(path)
        self.set_config(config)
        return config

    def __repr__(self) -> str:
        return f"{type(self).__name__}(image={self.image!r})"

    def _repr_mimebundle_(self, **kwargs) -> dict:
        # the widget for JupyterLab; a short stable text instead of the widget tree's repr
        # (which holds the preview's JPEG bytes) for nbval and plain-text front ends
        bundle = dict(self.widget._repr_mimebundle_(**kwargs) or {})
        bundle["text/plain"] = repr(self)
        return bundle

    # ---- for subclasses -------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        raise NotImplementedError

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        raise NotImplementedError

    def _apply(self, key: str) -> PipelineConfig:
        raise NotImplementedError

    def _sync(self) -> None:
        raise NotImplementedError

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the named views of the preview (RGB images or masks; None for a view that is off)."""
        raise NotImplementedError

    def readout(self) -> str:
        """Return the numbers shown under the preview, as text."""
        return ""

    def _control(self, key: str, widget: widgets.Widget) -> widgets.Widget:
        """Register ``widget`` under ``key`` (CSS class, ``observe`` wiring); return it."""
        slider = isinstance(widget, (widgets.IntSlider, widgets.FloatSlider, widgets.IntRangeSlider,
                                     widgets.FloatRangeSlider))
        widget.add_class(("lanelib-slider-" if slider else "lanelib-control-") + key.replace(".", "-"))
        widget.observe(lambda change, k=key: self._on_change(k), names="value")
        self.controls[key] = widget
        return widget

    # ---- wiring ---------------------------------------------------------------------------

    def _on_change(self, key: str) -> None:
        if self._syncing:
            return
        try:
            config = self._apply(key)
        except LaneLibError as e:
            self.error = str(e)
            self.message.value = f'<pre style="color:#c00;margin:0">{html.escape(self.error)}</pre>'
            return
        self.error = ""
        self._config = config
        self._refresh()

    def _on_pick(self, change) -> None:
        self._pick(change["new"])

    def _pick(self, label: str) -> None:
        self._raw = io.read_image(self.images[label])
        self._prepare(self._raw, self._calibration_for(label))
        self._refresh()

    def _calibration_for(self, label: str) -> Calibration | None:
        camera = "udacity" if label.startswith(UDACITY_PREFIX) else "bundled"
        if camera not in self._calibrations:
            folder = self.images[label].parent.parent / "camera_cal"
            cal = None
            if folder.is_dir():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # boards with a corner cut off are skipped
                    cal = calibrate(folder)
            self._calibrations[camera] = cal
        return self._calibrations[camera]

    def _refresh(self) -> None:
        self.preview.value = io.encode_image(self.preview_sheet(), ".jpg", self.jpeg_quality)
        text = self.readout()
        self.message.value = f'<pre style="margin:0">{html.escape(text)}</pre>' if text else ""


def _row(*children: widgets.Widget) -> widgets.HBox:
    return widgets.HBox(list(children), layout=widgets.Layout(flex_flow="row wrap",
                                                              align_items="center"))


def _sized(width_px: int, label_px: int) -> dict:
    """Return the layout and style keywords of a control ``width_px`` wide with a label of ``label_px``."""
    return dict(layout=widgets.Layout(width=f"{width_px}px"), style={"description_width": f"{label_px}px"})


# --------------------------------------------------------------------------- thresholds

def _channel_max(space: str, channel: str) -> int:
    """Return the largest value of a channel in OpenCV's 8-bit units (hue: 179)."""
    return 179 if channel == "h" and space in ("hls", "hsv") else 255


_COLOR_SPACES = tuple(s for s in thresholds.SPACES if s != "gray")


class ThresholdTuner(Tuner):
    """Tune the masks of ``ThresholdConfig`` and their combination on the bird's-eye view.

    For each mask: an on/off box (``<mask>.enabled``), the colour space (``<mask>.space``) and
    channel (``<mask>.channel``), the low/high range (``<mask>.range``; a colour range has one
    per channel, ``<mask>.range0..2``), the Sobel kernel (``<mask>.kernel_px``) and the top-hat
    width (``<mask>.width_px``); then the rule (``rule``) and the clean-up (``open_px``,
    ``close_px``). The preview shows the bird's-eye view, every mask and the combination; only
    the mask whose control moved is recomputed.
    """

    columns = 4
    default_tile_width_px = 320

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
                        **_sized(250, 20))))
            else:
                parts.append(self._control(f"{name}.channel", widgets.Dropdown(
                    options=tuple(thresholds.SPACES[spec.space][1]), value=spec.channel,
                    layout=widgets.Layout(width="55px"))))
                if isinstance(spec, thresholds.SobelMask):
                    top, step = (round(math.pi / 2, 2), 0.01) if spec.kind == "dir" else (255.0, 1.0)
                    parts.append(self._control(f"{name}.range", widgets.FloatRangeSlider(
                        value=(spec.low, spec.high), min=0.0, max=top, step=step,
                        description=spec.kind, readout_format=".2f" if spec.kind == "dir" else ".0f",
                        **_sized(300, 30))))
                    parts.append(self._control(f"{name}.kernel_px", widgets.Dropdown(
                        options=(1, 3, 5, 7), value=spec.kernel_px, description="kernel",
                        layout=widgets.Layout(width="120px"), style={"description_width": "45px"})))
                else:
                    parts.append(self._control(f"{name}.range", widgets.IntRangeSlider(
                        value=(spec.low, spec.high), min=0, max=_channel_max(spec.space, spec.channel),
                        description=spec.channel, **_sized(300, 30))))
                    if isinstance(spec, thresholds.TopHatMask):
                        parts.append(self._control(f"{name}.width_px", widgets.IntSlider(
                            value=spec.width_px, min=3, max=201, step=2, description="width px",
                            layout=widgets.Layout(width="260px"),
                            style={"description_width": "60px"})))
            rows.append(_row(*parts))
        rows.append(_row(
            self._control("rule", widgets.Text(value=cfg.rule, description="rule",
                                               continuous_update=False,
                                               layout=widgets.Layout(width="640px"),
                                               style={"description_width": "40px"})),
            self._control("open_px", widgets.IntSlider(value=cfg.open_px, min=0, max=15,
                                                       description="open px", **_sized(240, 60))),
            self._control("close_px", widgets.IntSlider(value=cfg.close_px, min=0, max=15,
                                                        description="close px", **_sized(240, 60)))))
        return rows

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        key = (id(calibration), raw.shape, self.config.perspective)
        if getattr(self, "_pipeline_key", None) != key:
            self._pipeline = LanePipeline(self.config, calibration, size=(raw.shape[1], raw.shape[0]))
            self._pipeline_key = key
        self.birdseye = self._pipeline.birdseye(raw)
        self._channels = thresholds.Channels(self.birdseye)
        self._masks: dict[str, tuple[object, np.ndarray]] = {}

    # ---- config <-> controls --------------------------------------------------------------

    def _spec(self, name: str):
        c = self.controls
        old = getattr(self.config.thresholds, name)
        enabled, space = c[f"{name}.enabled"].value, c[f"{name}.space"].value
        if isinstance(old, thresholds.ColorRange):
            ranges = [c[f"{name}.range{i}"].value for i in range(3)]
            return thresholds.ColorRange(space, tuple(int(r[0]) for r in ranges),
                                         tuple(int(r[1]) for r in ranges), enabled)
        channel = c[f"{name}.channel"].value
        low, high = c[f"{name}.range"].value
        if isinstance(old, thresholds.SobelMask):
            return thresholds.SobelMask(old.kind, space, channel, int(c[f"{name}.kernel_px"].value),
                                        float(low), float(high), enabled)
        if isinstance(old, thresholds.TopHatMask):
            return thresholds.TopHatMask(space, channel, int(c[f"{name}.width_px"].value),
                                         int(low), int(high), enabled)
        return thresholds.ChannelMask(space, channel, int(low), int(high), enabled)

    def _apply(self, key: str) -> PipelineConfig:
        tc = self.config.thresholds
        name, _, part = key.partition(".")
        if key in ("rule", "open_px", "close_px"):
            tc = replace(tc, **{key: self.controls[key].value})
        else:
            if part in ("space", "channel"):
                self._fit_controls(name)
            tc = replace(tc, **{name: self._spec(name)})
        return replace(self.config, thresholds=tc)

    def _fit_controls(self, name: str) -> None:
        """Fit the channel choices, slider ranges and labels of mask ``name`` to its colour space."""
        c = self.controls
        space = c[f"{name}.space"].value
        letters = thresholds.SPACES[space][1]
        self._syncing = True
        try:
            if f"{name}.channel" in c:
                channel = c[f"{name}.channel"].value
                c[f"{name}.channel"].options = tuple(letters)
                c[f"{name}.channel"].value = channel = channel if channel in letters else letters[0]
                if isinstance(c[f"{name}.range"], widgets.IntRangeSlider):
                    c[f"{name}.range"].max = _channel_max(space, channel)
                    c[f"{name}.range"].description = channel
            else:
                for i, letter in enumerate(letters):
                    c[f"{name}.range{i}"].max = _channel_max(space, letter)
                    c[f"{name}.range{i}"].description = letter
        finally:
            self._syncing = False

    def _sync(self) -> None:
        cfg = self.config.thresholds
        c = self.controls
        for name in thresholds.mask_names(cfg):
            spec = getattr(cfg, name)
            c[f"{name}.enabled"].value = spec.enabled
            c[f"{name}.space"].value = spec.space
            letters = thresholds.SPACES[spec.space][1]
            if isinstance(spec, thresholds.ColorRange):
                for i, letter in enumerate(letters):
                    s = c[f"{name}.range{i}"]
                    s.max, s.description = _channel_max(spec.space, letter), letter
                    s.value = (spec.low[i], spec.high[i])
                continue
            c[f"{name}.channel"].options = tuple(letters)
            c[f"{name}.channel"].value = spec.channel
            if isinstance(spec, thresholds.SobelMask):
                c[f"{name}.kernel_px"].value = spec.kernel_px
            else:
                c[f"{name}.range"].max = _channel_max(spec.space, spec.channel)
                c[f"{name}.range"].description = spec.channel
                if isinstance(spec, thresholds.TopHatMask):
                    c[f"{name}.width_px"].value = spec.width_px
            c[f"{name}.range"].value = (spec.low, spec.high)
        for key in ("rule", "open_px", "close_px"):
            c[key].value = getattr(cfg, key)

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
        return thresholds.combine(self.birdseye, cfg, computed=made)

    def counts(self) -> dict[str, int]:
        """Return the pixels of each enabled mask and of the combination (key ``"combined"``)."""
        out = {n: cv2.countNonZero(m) for n in thresholds.mask_names(self.config.thresholds)
               if (m := self.mask(n)) is not None}
        out["combined"] = cv2.countNonZero(self.combined())
        return out

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the bird's-eye view, every mask (None if off) and the combination."""
        cfg = self.config.thresholds
        views: dict[str, np.ndarray | None] = {"bird's-eye": self.birdseye}
        views.update({n: self.mask(n) for n in thresholds.mask_names(cfg)})
        views["combined"] = self.combined()
        return views

    def readout(self) -> str:
        counts = self.counts()
        total = self.birdseye.shape[0] * self.birdseye.shape[1]
        per = ", ".join(f"{n} {v / total:.1%}" for n, v in counts.items() if n != "combined")
        return (f"combined: {counts['combined']} px ({counts['combined'] / total:.1%} of the view)"
                f"  rule: {self.config.thresholds.rule}\n{per}")


# --------------------------------------------------------------------------- perspective

@dataclass(frozen=True)
class StraightLineCheck:
    """How straight a straight lane comes out in the bird's-eye view.

    ``left_slope``/``right_slope`` are the x drift of each line's straight fit in px per 100 px
    of height (0: vertical; NaN: line not found); ``lane_width_m`` is the distance of the two
    fits on the bottom row in metres. ``left_fit``/``right_fit`` are (slope, intercept) of
    x = slope * y + intercept in bird's-eye px, or None.
    """

    left_slope: float
    right_slope: float
    lane_width_m: float
    left_fit: tuple[float, float] | None
    right_fit: tuple[float, float] | None

    def __str__(self) -> str:
        return (f"left {_fmt(self.left_slope, 2, ' px/100 px', True)}, right "
                f"{_fmt(self.right_slope, 2, ' px/100 px', True)}, lane width "
                f"{_fmt(self.lane_width_m, 2, ' m')}")


def straight_line_check(binary: np.ndarray, xm_per_px: float,
                        search: lanes.SearchConfig = lanes.SearchConfig(),
                        car_x: float | None = None) -> StraightLineCheck:
    """Return the straight-line check of a bird's-eye lane mask of a straight road.

    The lane pixels are found by sliding windows (``search``); each line gets a straight fit.
    """
    found = lanes.sliding_windows(binary, search, car_x=car_x)
    h = binary.shape[0]
    fits = []
    for ys, xs in (found.left_pixels, found.right_pixels):
        if len(ys) < search.min_line_pixels or ys.max() - ys.min() < search.min_found_span_fraction * h:
            fits.append(None)
            continue
        slope, intercept = np.polyfit(ys.astype(np.float64), xs.astype(np.float64), 1)
        fits.append((float(slope), float(intercept)))
    nan = float("nan")
    slopes = [100 * f[0] if f else nan for f in fits]
    width = nan
    if fits[0] and fits[1]:
        x_at = [f[0] * (h - 1) + f[1] for f in fits]
        width = (x_at[1] - x_at[0]) * xm_per_px
    return StraightLineCheck(slopes[0], slopes[1], width, fits[0], fits[1])


def _trapezoid_of(src_px) -> dict[str, float]:
    """Return top_y, bottom_y, top_width, bottom_width, centre_x of src points (tl, bl, br, tr)."""
    (tlx, tly), (blx, bly), (brx, bry), (trx, try_) = src_px
    return {"top_y": (tly + try_) / 2, "bottom_y": (bly + bry) / 2, "top_width": trx - tlx,
            "bottom_width": brx - blx, "centre_x": (blx + brx) / 2}


def _fmt(v: float, nd: int = 2, unit: str = "", sign: bool = False) -> str:
    """Return ``v`` rounded to ``nd`` decimals with its unit ("not found" for NaN, no "-0.00")."""
    if math.isnan(v):
        return "not found"
    return f"{round(v, nd) + 0.0:{'+' if sign else ''}.{nd}f}{unit}"


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
    trapezoid is kept as it is until a slider moves.
    """

    columns = 3
    default_tile_width_px = 400

    def _build(self) -> list[widgets.Widget]:
        t = _trapezoid_of(self.config.perspective.src_px)
        w, h = self.config.perspective.size_px
        margin = float(self.config.perspective.dst_px[0][0])
        sl = lambda key, value, top, desc: self._control(key, widgets.FloatSlider(  # noqa: E731
            value=value, min=0.0, max=float(top), step=0.1, description=desc, readout_format=".1f",
            **_sized(460, 150)))
        return [_row(sl("top_y", t["top_y"], h - 1, "top y (px)"),
                     sl("centre_x", t["centre_x"], w, "centre x (px)")),
                _row(sl("top_width", t["top_width"], w, "top width (px)"),
                     sl("bottom_width", t["bottom_width"], 2 * w, "bottom width (px)")),
                _row(sl("dst_margin", margin, w / 2 - 1, "dst margin (px)"))]

    def _sync(self) -> None:
        pc = self.config.perspective
        t = _trapezoid_of(pc.src_px)
        w, h = pc.size_px
        limits = {"top_y": h - 1, "centre_x": w, "top_width": w, "bottom_width": 2 * w,
                  "dst_margin": w / 2 - 1}
        values = dict(t, dst_margin=float(pc.dst_px[0][0]))
        for key, top in limits.items():
            self.controls[key].max = float(top)
            self.controls[key].value = float(values[key])

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        size = (raw.shape[1], raw.shape[0])
        if tuple(self.config.perspective.size_px) != size:
            self._config = replace(self.config, perspective=scaled(self.config.perspective, size))
            self._syncing = True
            try:
                self._sync()
            finally:
                self._syncing = False
        key = (id(calibration), size)
        if getattr(self, "_undistorter_key", None) != key:
            self._undistorter = Undistorter(calibration, size)
            self._canvas = FastBirdseye(self._undistorter.calibration, size)
            self._undistorter_key = key
        self.undistorted = self._undistorter.undistort(raw)
        self._focal_px = implied_focal_px(self.config.perspective)
        self._small = shrink(self.undistorted, self._tile_size())
        self._update_views()

    def _tile_size(self) -> tuple[int, int]:
        h, w = self.undistorted.shape[:2]
        return self.tile_width_px, max(1, round(self.tile_width_px * h / w))

    def _apply(self, key: str) -> PipelineConfig:
        pc = self.config.perspective
        v = {k: float(self.controls[k].value) for k in
             ("top_y", "top_width", "bottom_width", "centre_x", "dst_margin")}
        w, h = pc.size_px
        bottom_y = _trapezoid_of(pc.src_px)["bottom_y"]
        src = trapezoid_src(v["top_y"], bottom_y, v["top_width"], v["bottom_width"], v["centre_x"])
        dst = trapezoid_src(0.0, float(h), w - 2 * v["dst_margin"], w - 2 * v["dst_margin"], w / 2)
        src = tuple((round(x, 2), round(y, 2)) for x, y in src)
        length = round(road_length_m(src, pc.lane_width_m, self._focal_px), 3)
        new = PerspectiveConfig(src, dst, pc.size_px, pc.lane_width_m, length)
        Perspective(new)  # refuses collinear points with a ConfigError
        config = replace(self.config, perspective=new)
        self._config = config
        self._update_views()
        return config

    def _update_views(self) -> None:
        """Warp, threshold and check the current frame under the current perspective."""
        self.perspective = Perspective(self.config.perspective)
        self.birdseye = self._canvas.birdseye(self._raw, self.perspective.Minv)
        self.binary = thresholds.combine(self.birdseye, self.config.thresholds)
        w, h = self.config.perspective.size_px
        car_x = float(self.perspective.warp_points([(w / 2, h - 1)])[0, 0])
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


# --------------------------------------------------------------------------- fits

class FitTuner(Tuner):
    """Tune the lane-pixel search: sliding windows and the search around a previous fit.

    Sliders ``n_windows``, ``margin_px``, ``minpix`` (the sliding windows) and
    ``prior_margin_px`` (the band searched around a previous fit; here the windows' own fits
    stand in for the previous frame's). The preview shows the windows and fits, the band search
    and the lane drawn back on the road; the bird's-eye lane mask is made once per image.
    """

    columns = 3
    default_tile_width_px = 400
    KEYS = ("n_windows", "margin_px", "minpix", "prior_margin_px")

    def _build(self) -> list[widgets.Widget]:
        sc = self.config.search
        limits = {"n_windows": (1, 30), "margin_px": (5, 300), "minpix": (0, 5000),
                  "prior_margin_px": (5, 300)}
        made = [self._control(k, widgets.IntSlider(value=getattr(sc, k), min=lo, max=hi,
                                                   description=k, **_sized(460, 150)))
                for k, (lo, hi) in limits.items()]
        return [_row(*made[:2]), _row(*made[2:])]

    def _sync(self) -> None:
        for k in self.KEYS:
            self.controls[k].value = getattr(self.config.search, k)

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        key = (id(calibration), raw.shape, self.config.perspective)
        if getattr(self, "_pipeline_key", None) != key:
            self.pipeline = LanePipeline(self.config, calibration, size=(raw.shape[1], raw.shape[0]))
            self._pipeline_key = key
        # the lane mask depends on the thresholds too: always from the current config
        self.undistorted = self.pipeline.undistort(raw)
        self.binary = thresholds.combine(self.pipeline.birdseye(raw), self.config.thresholds)
        self._update_search()

    def _apply(self, key: str) -> PipelineConfig:
        search = replace(self.config.search, **{k: int(self.controls[k].value) for k in self.KEYS})
        self._config = replace(self.config, search=search)
        self._update_search()
        return self._config

    def _update_search(self) -> None:
        """Search the lane mask with the current search parameters (windows, then around them)."""
        sc = self.config.search
        self.windows = lanes.sliding_windows(self.binary, sc, car_x=self.pipeline.car_x_px)
        self.around = lanes.search_around(self.binary, self.windows.left, self.windows.right, sc)
        self.measurement = self.pipeline.measure(self.windows.left, self.windows.right)

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the windows and fits, the search around the fits, and the lane on the road."""
        dc = self.config.draw
        overlay = draw.lane_overlay(self.undistorted, self.windows.left.coeffs_px,
                                    self.windows.right.coeffs_px, self.pipeline.perspective.Minv, dc)
        return {"sliding windows": draw.search_view(self.binary, self.windows, dc),
                "search around the fits": draw.search_view(self.binary, self.around, dc,
                                                           self.config.search.prior_margin_px),
                "lane on the road": overlay}

    def readout(self) -> str:
        lines = []
        for title, s in (("sliding windows", self.windows), ("search around", self.around)):
            parts = []
            for side, fit in (("left", s.left), ("right", s.right)):
                parts.append(f"{side} {fit.n_pixels} px" + ("" if fit.found else f" (not found: {fit.reason})"))
            lines.append(f"{title}: " + ", ".join(parts))
        m = self.measurement
        if not math.isnan(m.radius_m):
            rad = "straight" if m.radius_m >= 10_000 else f"{m.radius_m:.0f} m"
            lines.append(f"radius {rad}, offset {_fmt(m.offset_m, 2, ' m', True)}, "
                         f"lane width {_fmt(m.lane_width_m, 2, ' m')}")
        return "\n".join(lines)


# --------------------------------------------------------------------------- Hough (basic pipeline)

UDACITY_P1_PREFIX = "udacity-p1/"
UDACITY_P1 = "udacity-lanelines-p1"


def hough_image_choices(root: str | os.PathLike | None = None,
                        data: str | os.PathLike | None = None) -> dict[str, Path]:
    """Return the Hough tuner's images: label -> path, bundled ``test_images/`` first.

    The 960x540 images of ``udacity-lanelines-p1/test_images`` follow as ``"udacity-p1/<name>"``
    and the Udacity highway images as ``"udacity/<name>"``, each when ``data`` (default
    ``data_root()``) holds them.
    """
    root = repo_root(root)
    out = {p.name: p for p in io.list_images(root / "test_images")}
    data = Path(data if data is not None else data_root(root))
    p1 = data / UDACITY_P1 / "test_images"
    if p1.is_dir():
        out.update({UDACITY_P1_PREFIX + p.name: p for p in io.list_images(p1)})
    adv = data / UDACITY_ADVANCED / "test_images"
    if adv.is_dir():
        out.update({UDACITY_PREFIX + p.name: p for p in io.list_images(adv)})
    return out


class HoughTuner(Tuner):
    """Tune the basic Canny + region of interest + Hough pipeline (``PipelineConfig.hough``).

    Controls: ``blur_kernel_px``, ``canny`` (low, high), ``rho_px``, ``theta_deg``,
    ``threshold_votes``, ``min_line_length_px``, ``max_line_gap_px``, ``min_abs_slope`` and the
    region of interest as fractions of the image: ``roi.top_y``, ``roi.top_left``,
    ``roi.top_right``, ``roi.bottom_left``, ``roi.bottom_right`` (the x of each corner; the bottom
    row stays where the config has it). The preview shows the Canny edges, the edges inside the
    region (outlined), the Hough segments coloured by side and the two lane lines on the frame.

    The Hough pipeline works on raw frames (no undistortion), so no calibration is used. A change
    reruns ``hough.HoughLaneFinder.process`` on the picked frame (only the region's bounding box
    is processed, a few ms at 1280x720), so the preview is exactly what a ``python -m lanelib
    hough`` run does. ``save`` writes the ``hough`` part into a PipelineConfig JSON, keeping the
    other parts a file already holds; ``load`` takes the ``hough`` part of one.
    """

    columns = 2
    default_tile_width_px = 480
    ROI_KEYS = ("roi.top_y", "roi.top_left", "roi.top_right", "roi.bottom_left", "roi.bottom_right")

    def __init__(self, images: Mapping[str, str | os.PathLike] | None = None,
                 config: PipelineConfig = PipelineConfig(), image: str | None = None,
                 tile_width_px: int | None = None, jpeg_quality: int = 80):
        super().__init__(images if images is not None else hough_image_choices(), config, None,
                         image, tile_width_px, jpeg_quality)

    # ---- building -------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        hc = self.config.hough
        roi = _roi_fractions(hc.roi_frac)
        isl = lambda key, value, lo, hi, desc: self._control(key, widgets.IntSlider(  # noqa: E731
            value=value, min=lo, max=hi, description=desc, **_sized(420, 150)))
        fsl = lambda key, value, lo, hi, step, desc, fmt=".2f": self._control(  # noqa: E731
            key, widgets.FloatSlider(value=value, min=lo, max=hi, step=step, description=desc,
                                     readout_format=fmt, **_sized(420, 150)))
        return [
            _row(self._control("blur_kernel_px", widgets.Dropdown(
                     options=sorted({1, 3, 5, 7, 9, 11, 13, 15, hc.blur_kernel_px}), value=hc.blur_kernel_px,
                     description="blur kernel (px)", **_sized(260, 150))),
                 self._control("canny", widgets.IntRangeSlider(
                     value=(hc.canny_low, hc.canny_high), min=0, max=500,
                     description="Canny low, high", **_sized(420, 150)))),
            _row(fsl("rho_px", hc.rho_px, 0.5, 5.0, 0.5, "rho (px)", ".1f"),
                 fsl("theta_deg", hc.theta_deg, 0.25, 5.0, 0.25, "theta (deg)")),
            _row(isl("threshold_votes", hc.threshold_votes, 1, 200, "threshold (votes)"),
                 isl("min_line_length_px", hc.min_line_length_px, 0, 300, "min length (px)")),
            _row(isl("max_line_gap_px", hc.max_line_gap_px, 0, 300, "max gap (px)"),
                 fsl("min_abs_slope", hc.min_abs_slope, 0.0, 3.0, 0.05, "min |slope|")),
            _row(fsl("roi.top_y", roi["top_y"], 0.0, 1.0, 0.01, "ROI top y"),
                 fsl("roi.top_left", roi["top_left"], 0.0, 1.0, 0.01, "ROI top left x")),
            _row(fsl("roi.top_right", roi["top_right"], 0.0, 1.0, 0.01, "ROI top right x"),
                 fsl("roi.bottom_left", roi["bottom_left"], 0.0, 1.0, 0.01, "ROI bottom left x")),
            _row(fsl("roi.bottom_right", roi["bottom_right"], 0.0, 1.0, 0.01, "ROI bottom right x")),
        ]

    def _sync(self) -> None:
        hc, c = self.config.hough, self.controls
        for key in ("blur_kernel_px", "rho_px", "theta_deg", "threshold_votes",
                    "min_line_length_px", "max_line_gap_px", "min_abs_slope"):
            c[key].value = getattr(hc, key)
        c["canny"].value = (hc.canny_low, hc.canny_high)
        for key, value in _roi_fractions(hc.roi_frac).items():
            c[f"roi.{key}"].value = value

    def _calibration_for(self, label: str) -> Calibration | None:
        return None  # the Hough pipeline works on raw frames

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
        self._config = replace(self.config, hough=new)
        self._run()
        return self._config

    def save(self, path: str | os.PathLike) -> Path:
        """Write the tuned ``hough`` part into the PipelineConfig JSON at ``path``; return the path.

        A file that already exists keeps its other parts (e.g. thresholds saved by another tuner);
        otherwise the whole config is written.
        """
        p = Path(path)
        base = load_config(p) if p.exists() else self.config
        return save_config(replace(base, hough=self.config.hough), p)

    def load(self, path: str | os.PathLike) -> PipelineConfig:
        """Read the ``hough`` part of a PipelineConfig JSON into the controls and the preview."""
        config = replace(self.config, hough=load_config(path).hough)
        self.set_config(config)
        return config

    # ---- the pipeline ---------------------------------------------------------------------

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        self.frame = hough.check_rgb(raw)
        self._small = shrink(self.frame, self._tile_size())
        self._run()

    def _tile_size(self) -> tuple[int, int]:
        h, w = self.frame.shape[:2]
        return self.tile_width_px, max(1, round(self.tile_width_px * h / w))

    def _run(self) -> None:
        """Run the Hough pipeline on the picked frame with the current config, keeping the stages."""
        if getattr(self, "_finder", None) is None or self._finder.config != self.config.hough:
            self._finder = hough.HoughLaneFinder(self.config.hough)
        self.result = self._finder.process(self.frame, keep_stages=True)
        self.stages = self.result.stages

    # ---- views ----------------------------------------------------------------------------

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the Canny edges, the edges in the region, the Hough segments and the lines."""
        tw, th = self._tile_size()
        h, w = self.frame.shape[:2]
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
        lines = shrink(hough.annotate(self.frame, self.result), (tw, th))
        return {"Canny edges": st.edges, "edges in the region": roi_view,
                "Hough segments (left red, right blue)": segs, "lane lines": lines}

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
