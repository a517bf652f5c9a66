"""A video, run frame by frame in one process: ``run_video``, the span of a clip, the CSV log, and
the H.264 writer of every output video (``VideoWriter``, ``H264_PARAMS``).

``run_video`` takes a ``process`` callable that turns one RGB frame into an output frame, a row of
the per-frame CSV log and whether the lane was found, and does the reading, writing, progress bar
and log, all written atomically and never over an input; a video that breaks off half-way keeps
the frames processed before the break and raises ``PartialOutputError`` once its outputs are in
place. A video run returns one ``VideoRun`` record whichever the pipeline.
"""
from __future__ import annotations

import contextlib
import csv
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

import imageio_ffmpeg
import numpy as np
from tqdm import tqdm

from .. import cluster, io
from ..errors import DecodeStoppedError, InputError, PartialOutputError
from .images import json_value

# process(rgb, frame index, time in s) -> (output rgb, row of CSV values, whether the lane was found)
FrameFn = Callable[[np.ndarray, int, float], tuple[np.ndarray, dict, bool]]


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
    notes: tuple[str, ...] = ()  # what happened on the way (e.g. the road geometry re-estimated)
    joints: cluster.Joints | None = None  # on Dask: how the segments' joints were made exact


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


# The H.264 settings every lanelib video is written with (the codec benchmark uses the same).
H264_PARAMS = dict(codec="libx264", pix_fmt_out="yuv420p", quality=None, bitrate=None,
                   macro_block_size=1, output_params=["-preset", "veryfast", "-crf", "20"])


class VideoWriter:
    """Write RGB uint8 frames to an H.264 mp4 through imageio-ffmpeg, atomically: frames go to a
    temporary file beside ``path`` that ``close()`` renames into place, and leaving the ``with``
    block by an exception (Ctrl-C included) removes it.
    """

    def __init__(self, path: str | os.PathLike, fps: float, size: tuple[int, int] | None = None,
                 inputs: Iterable[str | os.PathLike] = (), threads: int | None = None):
        self.path = Path(path)
        self.fps = float(fps)
        self.size = size
        self._inputs = list(inputs)
        self._threads = threads
        self._ctx = io.atomic_path(self.path, inputs=self._inputs)
        self._tmp = self._ctx.__enter__()
        self._gen = None
        self.frames_written = 0

    def _start(self, size: tuple[int, int]) -> None:
        params = dict(H264_PARAMS)
        out = list(params.pop("output_params"))
        if self._threads is not None:
            out += ["-threads", str(self._threads)]
        self._gen = imageio_ffmpeg.write_frames(str(self._tmp), size, fps=self.fps,
                                                output_params=out, **params)
        self._gen.send(None)

    def write(self, rgb: np.ndarray) -> None:
        """Append one RGB uint8 frame; every frame must have the size of the first."""
        h, w = rgb.shape[:2]
        if self._gen is None:
            self.size = self.size or (w, h)
            self._start(self.size)
        if (w, h) != tuple(self.size):
            raise InputError(f"{self.path}: frame {self.frames_written} is {w}x{h}, "
                             f"the video is {self.size[0]}x{self.size[1]}")
        self._gen.send(np.ascontiguousarray(rgb))
        self.frames_written += 1

    def close(self) -> Path:
        """Finish the file and move it into place under its name; return the path."""
        if self._gen is not None:
            self._gen.close()
            self._gen = None
        if self.frames_written == 0:
            self._ctx.__exit__(InputError, InputError("no frames"), None)
            raise InputError(f"{self.path}: no frames were written; nothing to save")
        self._ctx.__exit__(None, None, None)
        return self.path

    def abort(self) -> None:
        """Stop writing and remove the temporary file; nothing is left under ``path``."""
        if self._gen is not None:
            with contextlib.suppress(Exception):
                self._gen.close()
            self._gen = None
        with contextlib.suppress(OSError):
            self._tmp.unlink()

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


class CsvLog:
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
    v = json_value(v)
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
    log = CsvLog(Path(log_path) if log_path else None, inputs)
    writer = VideoWriter(out_path, reader.info.fps, inputs=inputs, threads=threads)
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
