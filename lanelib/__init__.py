"""lanelib: camera-based lane finding, stage by stage.

The public API, by what a user does with it (each name is imported from its module on first use,
so ``import lanelib`` stays cheap):

- one frame: ``LanePipeline`` (the advanced pipeline, wired from one ``PipelineConfig``),
  ``HoughLaneFinder`` (the basic Canny + region + Hough pipeline);
- a video: ``LaneTracker`` (the lane across frames over a ``LanePipeline``);
- the camera: ``calibrate`` (chessboards -> ``Calibration``), ``PerspectiveConfig``;
- files: ``read_image``, ``write_image``, ``read_frame``, ``VideoReader``;
- runs: ``process_images``, ``process_video``, ``predict_benchmark``;
- scores against truth: ``evaluate_images``, ``evaluate_video``;
- settings: ``PipelineConfig``, ``load_config_or_preset``, ``override``.

The stages live in their own modules (camera, perspective, thresholds, search, fit, checks,
tracking, draw, hough; the hard-road parts in ``roads``, every line in view in ``lines``,
the geometry from the road in ``autogeometry``); ``docs/architecture.md`` maps them.

Examples
--------
>>> import lanelib
>>> pipe = lanelib.LanePipeline(lanelib.load_config_or_preset("p1"), size=(960, 540))
>>> pipe.size
(960, 540)
"""
from __future__ import annotations

import importlib

from .errors import (CalibrationError, ConfigError, DecodeStoppedError, InputError, LaneLibError,
                     PartialOutputError)

__version__ = "0.3.0"

# public name -> the module that owns it
_PUBLIC = {
    "LanePipeline": "pipeline", "HoughLaneFinder": "hough", "LaneTracker": "tracking",
    "Calibration": "camera", "calibrate": "camera", "PerspectiveConfig": "perspective",
    "read_image": "io", "write_image": "io", "read_frame": "io", "VideoReader": "io",
    "process_images": "batch", "process_video": "batch", "predict_benchmark": "batch",
    "evaluate_images": "evaluate", "evaluate_video": "evaluate",
    "PipelineConfig": "config", "load_config_or_preset": "config", "override": "config",
}

__all__ = sorted(_PUBLIC) + ["LaneLibError", "InputError", "CalibrationError", "ConfigError",
                             "DecodeStoppedError", "PartialOutputError", "__version__"]


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562)."""
    if name not in _PUBLIC:
        raise AttributeError(f"module 'lanelib' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
