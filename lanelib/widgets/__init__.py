"""Interactive tuners for the notebooks: controls that edit a ``PipelineConfig`` and a live preview.

A tuner shows an image picker, its controls, one persistent ``ipywidgets.Image`` holding JPEG bytes
of a downscaled sheet of named views (``draw.sheet``), and a text readout of the numbers that
matter. Controls are plain ipywidgets wired with ``observe`` (no ``interact()``, no matplotlib
re-draw, no debounce): a change rebuilds ``tuner.config``, recomputes only what that control
affects, and replaces the preview's bytes. What does not depend on the controls (the undistorted
frame, the bird's-eye view, colour conversions, the lane mask) is computed once per picked image.

- ``ThresholdTuner`` (``widgets/thresholds.py``): every mask of ``ThresholdConfig`` on the
  bird's-eye view (on/off, colour space and channel, low/high range, Sobel kernel, top-hat width)
  and the rule that combines them, CLAHE, an opening per colour mask, a stacked view of masks.
- ``PerspectiveTuner`` (``widgets/perspective.py``): each src corner and the dst rectangle
  (``src.tl.x``, ..., ``dst.left_x``, ...; ``set_points``), the symmetric shortcut (top y, top
  width, bottom width, centre x, dst margin) and clicks on the preview (``ipyevents``) that place
  the four src corners, and "estimate from this clip/frame" (``estimate``, ``set_geometry``:
  the road geometry of ``lanelib.autogeometry``); the points on the undistorted frame, the
  bird's-eye view and the straight-line check.
- ``FitTuner`` (``widgets/fit.py``): sliding windows (number, margin, minimum pixels), the
  search around a fit and the search's switches (trimming, window histogram, centre side first,
  growing margin).
- ``HoughTuner`` (``widgets/hough.py``): the basic pipeline's white and yellow HLS ranges, Canny
  thresholds, Hough parameters and region of interest (``PipelineConfig.hough``), on the raw
  frame; its picker adds the 960x540 Udacity P1 images.
- ``VideoTuner`` (``widgets/video.py``): the tracker's parameters (``PipelineConfig.tracking``:
  smoothing, recency, hold frames, jump limit) and the lane-width bounds of ``checks`` on a
  clip; the debug composite of the tracked frame under the frame slider, a strip of the
  per-frame confidence and offset, and ``play()``, the tuned clip as an inline video.

Each tuner holds its ``PipelineConfig`` in ``tuner.config`` and declares the parts of it that it
tunes (``parts``: ``("thresholds",)``, ``("perspective",)``, ``("search",)``, ``("hough",)``,
``("tracking", "checks")``).
``tuner.save(path)`` writes those parts into the JSON that ``python -m lanelib images|video
--config`` reads, keeping every other part the file already holds (so thresholds tuned in notebook
03 and the perspective tuned in 04 end up in one file); a new file gets the whole config.
``tuner.load(path)`` reads what the file holds of the parts the tuner shows (``shows``) into the
controls and keeps the rest of its config. Show a tuner by making it the last expression of a cell
(or ``display(tuner)``): the widget appears in JupyterLab and the text output is a short, stable
line for nbval.

Every control is in ``tuner.controls`` under a key (``"white.range1"``, ``"top_y"``, ...). Sliders
carry the CSS class ``lanelib-slider-<key with '.' as '-'>`` (e.g. ``lanelib-slider-top_y``,
``lanelib-slider-white-range1``), other controls ``lanelib-control-<key>``; the preview Image
carries ``lanelib-preview``, the picker ``lanelib-picker`` and the readout ``lanelib-readout``.

A new tuner subclasses ``Tuner`` (``widgets/base.py``), sets ``parts`` and ``shows`` and
implements ``_build``, ``_prepare``, ``_update``, ``_apply``, ``_sync``, ``render`` and
``readout`` (see ``Tuner``).

Every tuner exports what it shows: ``tuner.export(folder=None, name=None)`` writes
``<name>_preview.png`` (the preview sheet, ``preview_sheet()``) and ``<name>_annotated.png`` (the
frame with the lane drawn under the tuner's config as the command line draws it: ``annotated()``)
to ``folder`` (default ``out/`` of the repository) and returns their paths;
``write_preview(path)`` and ``write_annotated(path)`` write one. The name defaults to the picked
file, the video frame and the tuner (``straight_1_threshold``, ``project_frame50_video``); an
export never writes over the picked input. The ``export`` button beside the picker does the same
and lists the files under the preview.

Any tuner also takes videos among its picker's items (``{"clip": "videos/project.mp4"}``, or
``image_choices(videos=True)`` / ``video_choices()`` for the bundled ones as ``"videos/<name>"``):
picking one shows a frame slider (``tuner.frame_slider``, ``tuner.frame``), and the frame it stops
on is read by seeking (``io.read_frame``) and tuned like an image.

Any tuner also opens a folder: ``PerspectiveTuner("path/to/frames")`` picks from the folder's
images and videos at any depth, labelled by their paths inside it (``folder_choices``; other
files such as CULane's ``*.lines.txt`` labels are left out), and ``folder_choices(folder,
"*/*/20.jpg")`` picks the last frame of each clip of a TuSimple ``clips/`` tree. Frames of any
size work (CULane's 1640x590, TuSimple's 1280x720): the perspective's points are scaled to the
picked image, the perspective tuner's sliders span its size and ``save`` writes its points with
that size (``size_px``). An item that cannot be shown (unreadable, or a size the calibration
cannot take) leaves the item picked before and says why in the readout.
"""
from __future__ import annotations

# compatibility: the preview grid lives in lanelib.draw, the straight-line check in
# lanelib.perspective; they are re-exported here for code that imported them from widgets
from ..draw import sheet, shrink
from ..perspective import StraightLineCheck, straight_line_check
from .base import Tuner
from .choices import folder_choices, image_choices, video_choices
from .fit import FitTuner
from .hough import HoughTuner, hough_image_choices
from .perspective import PerspectiveTuner
from .thresholds import ThresholdTuner
from .video import TunedVideo, VideoTuner

__all__ = ["ThresholdTuner", "PerspectiveTuner", "FitTuner", "HoughTuner", "VideoTuner", "TunedVideo",
           "Tuner", "image_choices", "video_choices", "folder_choices",
           "hough_image_choices", "sheet", "shrink", "straight_line_check", "StraightLineCheck"]
