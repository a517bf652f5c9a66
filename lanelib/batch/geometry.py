"""The road geometry of a run's input: frames sampled from a video or a folder, the estimate
checked (``autogeometry.checked_geometry``), and a config with its bird's-eye points."""
from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np

from .. import io
from ..autogeometry import GeometryOptions, RoadGeometry, checked_geometry, geometry_calibration
from ..camera import Calibration
from ..config import PipelineConfig
from ..errors import InputError
from .video import clip_frames


def sample_frames(source: str | os.PathLike, seconds: float | None = None, max_frames: int = 50,
                  start_s: float | None = None) -> list[np.ndarray]:
    """Return up to ``max_frames`` frames of a video (from ``start_s``, over ``seconds``) or of a
    folder of images (by name), evenly spread.

    Raises
    ------
    InputError
        If the source is missing, unreadable, or holds no frame; an image that cannot be read
        names itself.
    """
    path = Path(source)
    if path.is_dir():
        files = io.list_images(path)
        step = max(1, math.ceil(len(files) / max_frames))
        return [io.read_image(f) for f in files[::step]]
    if not path.exists():
        raise InputError(f"{path}: no such file or folder; check the path")
    info = io.video_info(path)
    end = None if seconds is None else (start_s or 0.0) + seconds
    span = clip_frames(info, start_s, end if end is None or end * info.fps < info.n_frames else None)
    step = max(1, math.ceil(len(span) / max_frames))
    out = []
    with io.VideoReader(path, span.start, span.stop, info) as reader:
        for i, frame in enumerate(reader):
            if i % step == 0:
                out.append(frame)
    return out


def estimate_road_geometry(source: str | os.PathLike, calibration: Calibration | None = None,
                           options: GeometryOptions = GeometryOptions(),
                           start_s: float | None = None, lens_from_road: bool = True) -> RoadGeometry:
    """Return the road geometry estimated from a video's first ``options.seconds`` or a folder
    (``lens_from_road``: as for ``GeometryOptions.estimate``).

    Raises
    ------
    GeometryError
        If the frames give no consistent vanishing point (the reason: no road, too few
        segments, inconsistent, road not straight), or if the estimate's confidence is below
        ``autogeometry.LOW_CONFIDENCE`` and ``options.accept_low_confidence`` is off: a low
        confidence result is never used silently.
    """
    frames = sample_frames(source, options.seconds, options.max_frames, start_s)
    return checked_geometry(frames, source, calibration, options, lens_from_road)


def with_geometry(config: PipelineConfig, geo: RoadGeometry) -> PipelineConfig:
    """Return ``config`` with the bird's-eye points and scale of ``geo``."""
    return replace(config, perspective=geo.perspective_config())


def road_geometry_run(source: str | os.PathLike, config: PipelineConfig, calibration: Calibration | None,
                      options: GeometryOptions,
                      on_geometry: Callable[[RoadGeometry], None] | None = None
                      ) -> tuple[PipelineConfig, Calibration | None]:
    """Return ``config`` with the bird's-eye points and scale estimated from ``source`` (a video's
    first ``options.seconds`` or a folder, ``estimate_road_geometry``) and the calibration to run
    with them (``autogeometry.geometry_calibration``); ``on_geometry`` is called with the estimate.

    Raises
    ------
    GeometryError
        As ``estimate_road_geometry``: the estimate fails or is not confident.
    """
    geo = estimate_road_geometry(source, calibration, options)
    if on_geometry is not None:
        on_geometry(geo)
    return with_geometry(config, geo), geometry_calibration(calibration, geo)

