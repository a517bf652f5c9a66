"""lanelib: camera-based lane finding, stage by stage.

The stages live in their own modules (camera, perspective, thresholds, search, fit, checks,
tracking, draw, hough; the hard-road parts in ``roads``, every line in view in ``lines``);
``lanelib.pipeline.LanePipeline`` wires them from one ``PipelineConfig``, and
``lanelib.batch`` runs either pipeline over a folder of images or a video.
"""
from .errors import (CalibrationError, ConfigError, DecodeStoppedError, InputError, LaneLibError,
                     PartialOutputError)

__version__ = "0.1.0"

__all__ = ["LaneLibError", "InputError", "CalibrationError", "ConfigError", "DecodeStoppedError",
           "PartialOutputError", "__version__"]
