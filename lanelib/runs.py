"""Batch runs of every pipeline: a folder of images, or a video, frame by frame.

The same two verbs on the two pipelines, each a thin ``process`` callable on shared machinery:

- the advanced pipeline (``LanePipeline``, ``LaneTracker`` through a video): ``process_images``,
  ``process_video``;
- the basic Hough pipeline (``hough.HoughLaneFinder``, ``hough.HoughTracker`` through a video):
  ``hough_images``, ``hough_video``.

``run_images`` and ``run_video`` take a ``process`` callable that turns one RGB frame into an
output frame and a row of numbers, and do the reading, writing, progress bar, per-frame CSV log
and results file, all written atomically and never over an input; so the two pipelines behave
the same on the command line. A video run returns one ``VideoRun`` record whichever the pipeline.

Bad inputs: in a folder run, a file that cannot be read or processed (a lanelib error) gets its
own row with an ``error`` and the run goes on; a video that breaks off half-way keeps the frames
processed before the break and raises ``PartialOutputError`` once its outputs are in place.
"""
from __future__ import annotations

import csv
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np
from tqdm import tqdm

from . import hough, io
from .camera import Calibration
from .config import PipelineConfig
from .errors import (ConfigError, DecodeStoppedError, InputError, LaneLibError, PartialOutputError,
                     naming_the_file)
from .pipeline import LanePipeline, pipeline_for
from .result import FrameResult
from .tracking import LaneTracker

# process(rgb) -> (output rgb, row of JSON-able values)
ImageFn = Callable[[np.ndarray], tuple[np.ndarray, dict]]
# process(rgb, frame index, time in s) -> (output rgb, row of CSV values, whether the lane was found)
FrameFn = Callable[[np.ndarray, int, float], tuple[np.ndarray, dict, bool]]


def _clean(value):
    """Return ``value`` as a JSON-safe scalar: numpy types unwrapped, NaN and inf as None."""
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


GRAYSCALE_NOTE = ("grayscale image: the colour masks (yellow) find nothing; gradient and "
                  "lightness masks still work")


def image_notes(info: io.ImageFileInfo) -> list[str]:
    """Return what a results row should say about how an image file was read (may be empty).

    A grey image (``GRAYSCALE_NOTE``), 16-bit samples scaled to 8 bits, and what the decoder
    printed about an image it could still decode (e.g. corrupt JPEG data).
    """
    notes = [GRAYSCALE_NOTE] if not info.colour else []
    if info.bit_depth == 16:
        notes.append("16-bit image: scaled to 8 bits (value >> 8)")
    notes += [f"the decoder warned: {m}" for m in info.decoder_messages]
    return notes


def run_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike, process: ImageFn,
               results_name: str = "results.json") -> list[dict]:
    """Process each image, write ``OUT_DIR/<name>`` and ``OUT_DIR/results.json``; return the rows.

    Each row is ``{"file": <input file name>, **row}``, with ``"note"`` when the image was grey,
    16-bit or slightly corrupt (``image_notes``). A file that fails with a lanelib error (unreadable,
    not an image, a size the calibration does not fit, ...) gets the row ``{"file": <name>,
    "error": <one line naming the file, the cause and the fix>}``, no output image, and the run
    goes on. Any other exception is a bug and stops the run, as does a ``ConfigError`` (a bad
    configuration fails every file alike).

    Raises
    ------
    InputError
        If the output folder is the input folder.
    """
    out = Path(out_dir)
    files = [Path(f) for f in files]
    if any(f.parent.resolve() == out.resolve() for f in files):
        raise io.InputError(f"{out}: the output folder is the input folder; choose another -o folder")
    rows = []
    for f in files:
        try:
            rgb, info = io.read_image_info(f)
            image, row = process(rgb)
            io.write_image(out / f.name, image, inputs=files)
        except ConfigError:
            raise
        except LaneLibError as e:
            rows.append({"file": f.name, "error": naming_the_file(str(e), f)})
            continue
        notes = image_notes(info)
        rows.append({"file": f.name, **{k: _clean(v) for k, v in row.items()},
                     **({"note": "; ".join(notes)} if notes else {})})
    io.write_json(out / results_name, rows, inputs=files)
    return rows


@dataclass(frozen=True)
class VideoRun:
    """What a video run did: frames, wall time (s), frames per second, frames with a lane found.

    ``found_frames`` counts the frames whose ``process`` said found: for ``process_video`` a lane
    that passed the checks (tracked, held or inferred included), for ``hough_video`` both lines
    (measured or held). ``first_frame`` is the clip's index of the first frame processed (0
    unless the run started later: ``start_s``); the frames run ``first_frame .. first_frame +
    frames - 1`` of the clip.
    """

    frames: int
    seconds: float
    fps: float
    found_frames: int
    first_frame: int = 0


# a frame whose time is a hair (float rounding) before a bound counts as at the bound
_BOUND_EPS_FRAMES = 1e-6


def clip_frames(info: io.VideoInfo, start_s: float | None = None, end_s: float | None = None) -> range:
    """Return the clip's frame indices from ``start_s`` to ``end_s`` (seconds; None: the clip's start, end).

    Frame ``i`` shows from ``i / fps`` (``io.exact_fps``): the range holds the frames from the
    first one at or after ``start_s`` to the last one before ``end_s`` (``--start 2 --end 3`` at
    25 fps: frames 50..74). An ``end_s`` beyond the clip's end runs to its last frame.

    Raises
    ------
    InputError
        If a bound is negative or not a number, if ``start_s`` is not before ``end_s``, if
        ``start_s`` is at or beyond the clip's end, or if no frame starts between the two; the
        message names the clip, its duration and the fix.
    """
    n, fps = info.n_frames, io.exact_fps(info.fps)
    duration = n / fps
    clip = f"{info.path}: the clip is {duration:.3f} s long ({n} frames at {info.fps:g} fps)"
    for name, value in (("start", start_s), ("end", end_s)):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise InputError(f"{clip}; --{name} {value:g} s is not a time in it; pass a time in "
                             f"seconds from 0 to {duration:.3f}")
    if start_s is not None and end_s is not None and start_s >= end_s:
        raise InputError(f"{clip}; --start {start_s:g} s is not before --end {end_s:g} s; pass a "
                         "start time before the end time")
    last_s = (n - 1) / fps
    if start_s is not None and start_s * fps > n - 1 + _BOUND_EPS_FRAMES:
        where = ("is at or beyond its end" if start_s * fps >= n - _BOUND_EPS_FRAMES else
                 f"is after its last frame, which starts at {last_s:.3f} s")
        raise InputError(f"{clip}; --start {start_s:g} s {where}; pass a start time from 0 to "
                         f"{last_s:.3f} s")
    first = 0 if start_s is None else max(0, math.ceil(start_s * fps - _BOUND_EPS_FRAMES))
    stop = n if end_s is None else min(n, math.ceil(end_s * fps - _BOUND_EPS_FRAMES))
    if stop <= first:
        raise InputError(f"{clip}; no frame starts from {start_s or 0:g} s to before --end "
                         f"{end_s:g} s (frames are {1 / fps:.3f} s apart); pass a longer span")
    return range(first, stop)


class _CsvLog:
    """A per-frame CSV log written to a temporary file and renamed into place at the end."""

    def __init__(self, path: Path | None, inputs: Iterable[Path]):
        self.path = path
        self._ctx = io.atomic_path(path, inputs=inputs) if path else None
        self._tmp = self._ctx.__enter__() if self._ctx else None
        self._fh = open(self._tmp, "w", newline="") if self._tmp else None
        self._writer = None

    def write(self, row: dict) -> None:
        if self._fh is None:
            return
        if self._writer is None:
            self._writer = csv.DictWriter(self._fh, fieldnames=list(row))
            self._writer.writeheader()
        self._writer.writerow({k: _format_csv(v) for k, v in row.items()})

    def finish(self, ok: bool) -> None:
        if self._fh is None:
            return
        self._fh.close()
        if ok:
            self._ctx.__exit__(None, None, None)
        else:
            try:
                self._ctx.__exit__(RuntimeError, RuntimeError("aborted"), None)
            except RuntimeError:
                pass


def _format_csv(v) -> str:
    v = _clean(v)
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def run_video(in_path: str | os.PathLike, out_path: str | os.PathLike, process: FrameFn,
              log_path: str | os.PathLike | None = None, progress: bool = True,
              desc: str = "frames", threads: int | None = None, start_s: float | None = None,
              end_s: float | None = None) -> VideoRun:
    """Return what a run did after processing every frame and writing the output video (and log).

    ``process(frame, index, time_s)`` returns the output frame, the row of the per-frame CSV log
    and whether the lane was found in the frame (counted in ``VideoRun.found_frames``). The
    output keeps the input's size and frame rate (H.264). A tqdm bar shows fps and ETA when
    ``progress`` is true. An empty, corrupt or missing input, or one in a codec ffmpeg cannot
    decode, raises ``InputError`` with nothing written; an exception or Ctrl-C mid-run removes the
    partial output and log.

    ``start_s``, ``end_s`` (seconds, either may be None) run on part of the clip: the frames
    ``clip_frames`` gives, from the first at or after ``start_s`` to the last before ``end_s``.
    Decoding seeks to the first one (``io.VideoReader(start=...)``) and stops after the last.
    ``index`` and ``time_s`` stay those of the source clip (``index / fps``: frame 50 of a 25 fps
    clip is 2.0 s whatever the start), so a log row names the source frame it came from; the
    output video holds only the part, from its own time 0. Bad bounds raise ``InputError``
    (``clip_frames``) before anything is written.

    Raises
    ------
    PartialOutputError
        If the input stops decoding after some frames (``DecodeStoppedError``: truncated or
        corrupt): the output video and the log are finished and moved into place with the frames
        processed before the break, then this error says where decoding stopped and why, and
        what was written.
    """
    in_path = Path(in_path)
    if start_s is None and end_s is None:
        reader = io.VideoReader(in_path)
        frames = range(reader.info.n_frames)
    else:
        info = io.video_info(in_path)
        frames = clip_frames(info, start_s, end_s)
        reader = io.VideoReader(in_path, frames.start, frames.stop if end_s is not None else None, info)
    inputs = [in_path]
    log = _CsvLog(Path(log_path) if log_path else None, inputs)
    writer = io.VideoWriter(out_path, reader.info.fps, inputs=inputs, threads=threads)
    ok = False
    stopped: DecodeStoppedError | None = None
    n = found = 0
    first = frames.start
    t0 = time.perf_counter()
    try:
        bar = tqdm(total=len(frames) or None, desc=desc, unit="frame", disable=not progress,
                   dynamic_ncols=True)
        with bar:
            try:
                for frame in reader:
                    index = first + n
                    image, row, lane = process(frame, index, index / reader.info.fps)
                    found += bool(lane)
                    writer.write(image)
                    log.write(row)
                    bar.update(1)
                    n += 1
            except DecodeStoppedError as e:  # raised only after at least one frame
                stopped = e
        writer.close()
        ok = True
    finally:
        reader.close()
        if not ok:
            writer.abort()
        log.finish(ok)
    seconds = time.perf_counter() - t0
    if stopped is not None:
        wrote = f"wrote {n} frames to {writer.path}" + (f" and {n} rows to {log.path}" if log.path else "")
        raise PartialOutputError(f"{stopped}; {wrote}", n)
    return VideoRun(n, seconds, n / seconds if seconds > 0 else float("nan"), found, first)


# --------------------------------------------------------------------------- the advanced pipeline

def process_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                   config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                   debug: bool = False) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lane in each image and writing it annotated.

    Each row is the image's ``FrameResult.summary``. Frames of several sizes are allowed: one
    pipeline is built per size (the calibration is rescaled or refused per
    ``Calibration.for_size``). A file that cannot be read, an image too small for the bird's-eye
    view, or one whose size the calibration does not fit gets a row with an ``error``
    (``run_images``), and the run goes on. ``debug`` writes the 2x2 debug composite
    (``LanePipeline.debug_composite``) instead of the annotated frame.
    """
    cache: dict[tuple[int, int], LanePipeline] = {}

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        size = (rgb.shape[1], rgb.shape[0])
        if size not in cache:
            try:
                cache[size] = LanePipeline(config, calibration, size=size)
            except ConfigError:
                LanePipeline(config)  # a bad config raises here again: it fails every image alike
                w, h = config.perspective.size_px
                raise InputError(f"the image is {size[0]}x{size[1]} px, too small for the bird's-eye "
                                 "view (the perspective points collapse when scaled to it); pass "
                                 f"larger images (the config's points are for {w}x{h})") from None
        pipe = cache[size]
        result = pipe.process(rgb, keep_images=debug)
        image = pipe.debug_composite(result) if debug else result.images["result"]
        return image, result.summary()

    return run_images([Path(f) for f in files], out_dir, process)


VIDEO_LOG_COLUMNS = ("frame", "time_s", "found", "left_conf", "right_conf", "radius_m", "offset_m",
                     "lane_width_m", "left_a", "left_b", "left_c", "right_a", "right_b", "right_c")


def video_log_row(frame: int, time_s: float, result: FrameResult) -> dict:
    """Return one row of the per-frame video log (``VIDEO_LOG_COLUMNS``; NaN where not found).

    The fit coefficients are the tracked bird's-eye pixel fits x = a*y**2 + b*y + c.
    """
    nan = float("nan")
    row = {"frame": frame, "time_s": round(time_s, 4), "found": int(result.found),
           "left_conf": result.left_conf, "right_conf": result.right_conf,
           "radius_m": result.radius_m, "offset_m": result.offset_m,
           "lane_width_m": result.lane_width_m}
    for side, fit in (("left", result.left), ("right", result.right)):
        coeffs = fit.coeffs_px if fit.found else (nan, nan, nan)
        row.update({f"{side}_{k}": v for k, v in zip("abc", coeffs)})
    return row


def process_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                  config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                  debug: bool = False, log_path: str | os.PathLike | None = None,
                  progress: bool = True, threads: int | None = None, start_s: float | None = None,
                  end_s: float | None = None) -> VideoRun:
    """Return what the run did after tracking the lane through a video and writing it annotated.

    The lane is drawn on the RAW frames, mapped through the lens model (``config.draw.
    video_undistorted`` draws on undistorted frames instead, at one more remap per frame).

    Parameters
    ----------
    in_path, out_path : input video and output mp4 (H.264, the input's size and frame rate).
    config, calibration : as for ``LanePipeline``; the pipeline is made for the video's frame size.
    debug : write the 2x2 debug composite (undistorted, binary, search, result) instead.
    log_path : per-frame CSV with ``VIDEO_LOG_COLUMNS`` (optional).
    progress : show a tqdm bar with fps and ETA.
    threads : encoder threads (None: ffmpeg's choice).
    start_s, end_s : run on part of the clip (seconds; None: from its start, to its end): the
        frames from the first at or after ``start_s`` to the last before ``end_s``
        (``clip_frames``). The tracker starts fresh on the first of them; the log's ``frame``
        and ``time_s`` are the source clip's (``run_video``).

    Every output is written atomically by ``run_video``: an error or Ctrl-C leaves nothing under
    ``out_path`` or ``log_path``, except a video that stops decoding half-way: its outputs keep
    the frames before the break, and ``PartialOutputError`` says so.
    """
    trackers: list[LaneTracker] = []  # made on the first frame, for the video's frame size

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        if not trackers:
            trackers.append(LaneTracker(pipeline_for(frame, config, calibration)))
        tracker = trackers[0]
        pipe = tracker.pipeline
        result = tracker.update(frame, keep_images=debug)
        if debug:
            image = pipe.debug_composite(result, raw=frame)
        elif config.draw.video_undistorted:
            image = pipe.annotate(pipe.undistort(frame), result)
        else:
            image = pipe.annotate(frame, result, raw=True)
        return image, video_log_row(index, time_s, result), result.found

    return run_video(in_path, out_path, process, log_path=log_path, progress=progress,
                     desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)


# --------------------------------------------------------------------------- the basic Hough pipeline

def hough_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                 config: hough.HoughConfig = hough.HoughConfig()) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lines in each image and writing it annotated.

    Each row holds ``file``, ``left_found``, ``right_found``, each line's x (px) at the bottom
    row and at the top of the region (None when not found), and ``reason``
    (``HoughResult.row``); a file that cannot be read holds ``file`` and ``error`` instead, and
    the run goes on (``run_images``).
    """
    finder = hough.HoughLaneFinder(config)

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        result = finder.process(rgb)
        return hough.annotate(rgb, result), result.row()

    return run_images(files, out_dir, process)


def hough_log_row(frame: int, time_s: float, result: hough.HoughResult) -> dict:
    """Return one row of the per-frame Hough video log: ``frame``, ``time_s`` and ``HoughResult.row``."""
    return {"frame": frame, "time_s": time_s, **result.row()}


def hough_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                config: hough.HoughConfig = hough.HoughConfig(),
                log_path: str | os.PathLike | None = None, progress: bool = True,
                threads: int | None = None, start_s: float | None = None,
                end_s: float | None = None) -> VideoRun:
    """Return what the run did after tracking both lines through a video and writing it annotated.

    ``out_path`` is an H.264 video with the input's size and frame rate; the optional per-frame
    CSV at ``log_path`` holds ``hough_log_row``. ``found_frames`` counts frames with both lines
    (measured or held). ``start_s``, ``end_s`` run on part of the clip, as for
    ``process_video``. Outputs are written atomically by ``run_video``: an error or Ctrl-C
    leaves nothing behind, except a video that stops decoding half-way: its outputs keep the
    frames before the break, and ``PartialOutputError`` says so.
    """
    if Path(out_path).suffix.lower() not in io.VIDEO_SUFFIXES:
        raise InputError(f"{out_path}: the output video needs a video suffix "
                         f"({', '.join(io.VIDEO_SUFFIXES)}); e.g. out.mp4")
    tracker = hough.HoughTracker(config)

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        result = tracker.process(frame)
        return (hough.annotate(frame, result), hough_log_row(index, time_s, result),
                result.left_found and result.right_found)

    return run_video(in_path, out_path, process, log_path=log_path, progress=progress,
                     desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)
