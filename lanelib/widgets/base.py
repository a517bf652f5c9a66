"""The tuners' shared machinery: ``Tuner`` (picker, controls, preview, readout) and the layout
helpers of the controls; the picker's choices live in ``widgets/choices.py``, reading the picked
item in ``widgets/picking.py``, export, save and load in ``widgets/export.py``.

A tuner shows an image picker, its controls, one persistent ``ipywidgets.Image`` holding JPEG bytes
of a downscaled ``draw.sheet`` of named views, and a text readout of the numbers that matter.
Controls are plain ipywidgets wired with ``observe`` (no ``interact()``, no matplotlib re-draw, no
debounce): a change builds the new config (``_apply``), recomputes what that control affects
(``_update``) and replaces the preview's bytes. What does not depend on the controls (the
undistorted frame, the bird's-eye view, colour conversions, the lane mask) is computed once per
picked image (``_prepare``).

The picker's items may be videos (``io.VIDEO_SUFFIXES``) as well as images: a video shows a frame
slider (``frame_slider``, ``tuner.frame``) under the picker, and each frame it stops on is read by
seeking (``io.read_frame``) and goes through the same ``_prepare`` and ``_update`` as an image.
The items may also be a folder (``folder_choices``: its images and videos at any depth, e.g. a
CULane folder of 1640x590 frames or a TuSimple tree of clips), of any size.

Every tuner exports what it shows (``export``, the ``export`` button): the preview sheet and the
picked frame annotated with the tuned config as the command line draws it (``annotated``), as
PNG files, never over the picked input.
"""
from __future__ import annotations

import contextlib
import html
import math
import os
from dataclasses import fields
from pathlib import Path
from typing import Callable, Iterator, Mapping, TypeVar

import ipywidgets as widgets
import numpy as np

from .. import io
from ..camera import Calibration
from ..config import PipelineConfig
from ..draw import sheet
from ..errors import InputError, LaneLibError
from ..pipeline import LanePipeline
from .choices import (UDACITY_PREFIX, VIDEO_PREFIX, folder_choices, image_choices,  # noqa: F401
                      is_video, picker_items, video_choices)
from .export import Exports
from .picking import Picking

PARTS = tuple(f.name for f in fields(PipelineConfig))  # the parts of a PipelineConfig file
T = TypeVar("T")


class Tuner(Picking, Exports):
    """Shared machinery of the tuners: image picker, controls, preview Image, readout, save/load.

    Parameters
    ----------
    images : label -> image or video path for the picker (default: ``image_choices()``), or a
        folder: its images and videos at any depth (``folder_choices``). Images of any size
        are shown (the perspective's points are scaled to each). A video
        (``io.VIDEO_SUFFIXES``) shows the frame slider ``frame_slider`` (0 .. n_frames - 1, taken
        when released); the preview follows it. For an image the slider is hidden.
    config : the PipelineConfig to start from.
    calibration : the camera of the bundled images (None: frames are taken as undistorted).
        Images labelled ``"udacity/..."`` use the Udacity camera, calibrated from its
        ``camera_cal/`` the first time one of them is picked (``calibration_for``).
    image : label of the image to show first (default: the first one).
    tile_width_px : width of one view in the preview sheet.
    jpeg_quality : JPEG quality of the preview bytes.

    A subclass sets ``parts`` (the parts of ``PipelineConfig`` it tunes, which ``save`` writes)
    and ``shows`` (the parts its views depend on, which ``load`` reads; they include ``parts``),
    and implements the hooks below. ``__init__`` calls them only after its own state is set up,
    and a hook relies only on what an earlier hook made: ``_build`` once, then on every pick (and
    ``load``) ``_prepare`` and ``_update(None)``, on every control change ``_apply(key)`` and,
    when the value is taken, ``_update(key)``; ``render``/``readout`` after each of those.

    - ``_build()``: make its controls from ``self.config`` with ``self._control(key, widget)``;
      return the rows of widgets laid out between the picker and the preview;
    - ``_prepare(raw, calibration)``: compute what depends only on the picked image (and on
      parts no control changes); ``self._cached`` keeps objects that outlive one image;
    - ``_update(key)``: recompute the views after control ``key`` changed (None: all of them,
      after a pick or a load), and fit controls whose choices follow another control's value;
    - ``_apply(key)``: return the new PipelineConfig after control ``key`` changed, changing
      nothing (raise ``LaneLibError`` to refuse the value: the readout then shows why); what
      ``config_for`` returns;
    - ``_sync()``: set the controls from ``self.config`` (after ``load``);
    - ``render()``: the named views of the preview; ``readout()``: the numbers as text;
    - ``annotated()``: the picked frame with the lane drawn (default: ``LanePipeline.process``,
      as ``python -m lanelib images`` draws it); a tuner of another pipeline overrides it.

    Export, save and load (``export``, ``write_preview``, ``write_annotated``, ``save``,
    ``load``) come from ``export.Exports``, reading the picked item (``_pick``) from
    ``picking.Picking``.
    """

    columns = 3
    default_tile_width_px = 400
    parts: tuple[str, ...] = ()
    shows: tuple[str, ...] = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        unknown = sorted(set(cls.parts + cls.shows) - set(PARTS))
        if unknown:
            raise TypeError(f"{cls.__name__}: {unknown} are not parts of PipelineConfig ({PARTS})")
        if not set(cls.parts) <= set(cls.shows):
            raise TypeError(f"{cls.__name__}: shows {cls.shows} must include the parts it tunes {cls.parts}")

    def __init__(self, images: Mapping[str, str | os.PathLike] | str | os.PathLike | None = None,
                 config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                 image: str | None = None, tile_width_px: int | None = None, jpeg_quality: int = 80):
        self.images = picker_items(images, image_choices)
        if not self.images:
            raise InputError("tuner: no images to show; pass images={label: path} or add test_images/")
        image = image if image is not None else next(iter(self.images))
        if image not in self.images:
            labels = list(self.images)
            more = f", ... ({len(labels)} in all)" if len(labels) > 10 else ""
            raise InputError(f"tuner: image {image!r} is not among the picker's images "
                             f"({', '.join(labels[:10])}{more}); pass one of their labels")
        self._config = config
        self._calibrations: dict[str, Calibration | None] = {"bundled": calibration}
        self._cache: dict[str, tuple[object, object]] = {}
        self.tile_width_px = int(tile_width_px or self.default_tile_width_px)
        self.jpeg_quality = int(jpeg_quality)
        self.controls: dict[str, widgets.Widget] = {}
        self._syncing = False
        self._widget: widgets.Widget | None = None
        self._raw = np.zeros((0, 0, 3), np.uint8)
        self._video_infos: dict[Path, io.VideoInfo] = {}
        self.error = ""
        self.picker = widgets.Dropdown(options=list(self.images), value=image, description="image",
                                       layout=widgets.Layout(width="420px"))
        self.picker.add_class("lanelib-picker")
        self.export_button = widgets.Button(description="export", icon="download",
                                            tooltip="write the preview and the annotated frame "
                                                    "as PNG to out/",
                                            layout=widgets.Layout(width="100px"))
        self.export_button.add_class("lanelib-control-export")
        self.export_button.on_click(self._on_export)
        self.frame_slider = widgets.IntSlider(value=0, min=0, max=0, description="frame",
                                              continuous_update=False,
                                              layout=widgets.Layout(width="640px", display="none"),
                                              style={"description_width": "50px"})
        self.frame_slider.add_class("lanelib-slider-frame")
        self.preview = widgets.Image(format="jpeg", layout=widgets.Layout(max_width="100%"))
        self.preview.add_class("lanelib-preview")
        self.message = widgets.HTML()
        self.message.add_class("lanelib-readout")
        # the base is set up: now the subclass's hooks
        self._rows = self._build()
        self._pick(image)
        self.picker.observe(self._on_pick, names="value")
        self.frame_slider.observe(self._on_frame, names="value")

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
    def is_video(self) -> bool:
        """True when the picked item is a video (the frame slider shows)."""
        return is_video(self.images[self.image])

    @property
    def frame(self) -> int:
        """Index of the video frame shown (0 for an image); setting it shows that frame."""
        return int(self.frame_slider.value) if self.is_video else 0

    @frame.setter
    def frame(self, index: int) -> None:
        path = self.images[self.image]
        if not self.is_video:
            raise InputError(f"{path}: the picked item is an image, it has no frames; "
                             "pick a video to choose a frame")
        n = self._video_info(path).n_frames
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
            raise InputError(f"{path}: frame {index!r} is outside the video (frames 0..{n - 1}); "
                             "pass an index in that range")
        self.frame_slider.value = int(index)

    @property
    def raw(self) -> np.ndarray:
        """The picked image, or the video frame shown, as the file holds it (RGB uint8)."""
        return self._raw

    @property
    def widget(self) -> widgets.VBox:
        """The tuner's widget: picker, frame slider, controls, preview and readout (made once)."""
        if self._widget is None:
            self._widget = widgets.VBox([row(self.picker, self.export_button), self.frame_slider,
                                         *self._rows, self.preview, self.message])
            self._widget.add_class("lanelib-tuner")
        return self._widget

    def preview_sheet(self) -> np.ndarray:
        """Return the preview as an RGB array (what the Image shows, before JPEG encoding)."""
        return sheet(self.render(), self.tile_width_px, self.columns)

    def annotated(self) -> np.ndarray:
        """Return the picked frame with the lane drawn under the tuner's config (RGB uint8).

        What ``python -m lanelib images`` writes for this frame with the tuner's config and
        calibration: ``LanePipeline.process`` of the frame on its own (a video frame too: no
        tracker), the lane and the measurements drawn on the undistorted frame. The Hough and
        video tuners draw their own pipeline's result (``HoughTuner.annotated``,
        ``VideoTuner.annotated``).
        """
        raw = self._raw
        calibration = self.calibration_for(self.image)
        size = (raw.shape[1], raw.shape[0])
        pipe = self._cached("export pipeline", (id(calibration), size, self.config),
                            lambda: LanePipeline(self.config, calibration, size=size))
        return pipe.process(raw).images["result"]

    def set_config(self, config: PipelineConfig) -> None:
        """Show ``config`` in the controls and the preview."""
        self._show(config)
        self._prepare(self._raw, self.calibration_for(self.image))
        self._update(None)
        self._refresh()

    def config_for(self, key: str, value: object) -> PipelineConfig:
        """Return the PipelineConfig that control ``key`` at ``value`` describes, taking nothing.

        Parameters
        ----------
        key : a key of ``controls`` (another raises ``InputError``).
        value : a value of that control. The config is what moving the control there makes it
            (``_apply``); the control keeps its value and the config, views and preview stay the
            same objects. A value the tuner refuses raises ``LaneLibError`` (the readout's reason).
        """
        if key not in self.controls:
            raise InputError(f"config_for: {key!r} is not a control of {type(self).__name__}; "
                             f"pass one of {sorted(self.controls)}")
        control, before = self.controls[key], self.controls[key].value
        with self._quiet():
            control.value = value
            try:
                return self._apply(key)
            finally:
                control.value = before

    def __repr__(self) -> str:
        return f"{type(self).__name__}(image={self.image!r})"

    def _repr_mimebundle_(self, **kwargs) -> dict:
        # the widget for JupyterLab; a short stable text instead of the widget tree's repr
        # (which holds the preview's JPEG bytes) for nbval and plain-text front ends
        bundle = dict(self.widget._repr_mimebundle_(**kwargs) or {})
        bundle["text/plain"] = repr(self)
        return bundle

    # ---- hooks ----------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        raise NotImplementedError

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        raise NotImplementedError

    def _update(self, key: str | None) -> None:
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

    # ---- for subclasses -------------------------------------------------------------------

    def _control(self, key: str, widget: widgets.Widget) -> widgets.Widget:
        """Register ``widget`` under ``key`` (CSS class, ``observe`` wiring); return it."""
        slider = isinstance(widget, (widgets.IntSlider, widgets.FloatSlider, widgets.IntRangeSlider,
                                     widgets.FloatRangeSlider))
        widget.add_class(("lanelib-slider-" if slider else "lanelib-control-") + key.replace(".", "-"))
        widget.observe(lambda change, k=key: self._on_change(k), names="value")
        self.controls[key] = widget
        return widget

    @contextlib.contextmanager
    def _quiet(self) -> Iterator[None]:
        """Set controls inside this block without their changes counting as the user's."""
        self._syncing = True
        try:
            yield
        finally:
            self._syncing = False

    def _show(self, config: PipelineConfig) -> None:
        """Make ``config`` the tuner's config and set the controls from it (no views recomputed)."""
        self._config = config
        with self._quiet():
            self._sync()

    def _cached(self, name: str, key: object, make: Callable[[], T]) -> T:
        """Return the object ``make()`` built for ``key`` under ``name``; rebuilt when ``key`` changes."""
        hit = self._cache.get(name)
        if hit is None or hit[0] != key:
            hit = (key, make())
            self._cache[name] = hit
        return hit[1]

    def _tile_size(self) -> tuple[int, int]:
        """Return (w, h) of one preview tile for the picked image."""
        h, w = self._raw.shape[:2]
        return self.tile_width_px, max(1, round(self.tile_width_px * h / w))

    # ---- wiring ---------------------------------------------------------------------------

    def _on_change(self, key: str) -> None:
        if self._syncing:
            return
        try:
            config = self._apply(key)
        except LaneLibError as e:
            self._show_error(str(e))
            return
        self.error = ""
        self._config = config
        self._update(key)
        self._refresh()

    def _show_error(self, text: str) -> None:
        """Show ``text`` in red in the readout and keep it in ``self.error``."""
        self.error = text
        self.message.value = f'<pre style="color:#c00;margin:0">{html.escape(text)}</pre>'

    def _refresh(self) -> None:
        self.preview.value = io.encode_image(self.preview_sheet(), ".jpg", self.jpeg_quality)
        text = self.readout()
        self.message.value = f'<pre style="margin:0">{html.escape(text)}</pre>' if text else ""


def row(*children: widgets.Widget) -> widgets.HBox:
    """Return the controls as one wrapping row."""
    return widgets.HBox(list(children), layout=widgets.Layout(flex_flow="row wrap",
                                                              align_items="center"))


def sized(width_px: int, label_px: int) -> dict:
    """Return the layout and style keywords of a control ``width_px`` wide with a label of ``label_px``."""
    return dict(layout=widgets.Layout(width=f"{width_px}px"), style={"description_width": f"{label_px}px"})


def fmt(v: float, nd: int = 2, unit: str = "", sign: bool = False) -> str:
    """Return ``v`` rounded to ``nd`` decimals with its unit ("not found" for NaN, no "-0.00")."""
    if math.isnan(v):
        return "not found"
    return f"{round(v, nd) + 0.0:{'+' if sign else ''}.{nd}f}{unit}"
