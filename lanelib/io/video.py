"""Video files through imageio-ffmpeg: reading frames (all, a span, or one by seeking), the video's
size and frame rate. Output videos are written by ``batch.video.VideoWriter``.

Frames are RGB ``uint8`` arrays (H x W x 3). A broken or truncated video raises ``InputError`` or
``DecodeStoppedError`` naming the file and ffmpeg's cause.
"""
from __future__ import annotations

import contextlib
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import imageio_ffmpeg
import numpy as np

from ..errors import DecodeStoppedError, InputError

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm")


@dataclass(frozen=True)
class VideoInfo:
    """Size, frame rate and (estimated) frame count of a video file."""

    path: Path
    width: int
    height: int
    fps: float
    n_frames: int

    @property
    def size(self) -> tuple[int, int]:
        return (self.width, self.height)


# A video that ends more than this many frames (or this share of its announced length) before
# the length its container announces is taken as broken off: container durations are rounded,
# so a frame or two of difference is normal.
SHORTFALL_FRAMES = 2
SHORTFALL_SHARE = 0.01
_VIDEO_FIX = "pass a valid video (mp4, H.264)"
_FFMPEG_LINE = re.compile(r"^\[[^\]]*@ 0x[0-9a-f]+\]\s*(.*)$")


def ffmpeg_cause(text: str) -> str:
    """Return the one line of ffmpeg's output (as imageio-ffmpeg reports it) that says what failed."""
    log = text.split("=== stderr ===", 1)[-1]
    lines = [line.strip() for line in log.splitlines() if line.strip()]
    if any(line.startswith("Input #") for line in lines) and not any(
            "Video:" in line for line in lines if line.startswith("Stream #")):
        return "the file holds no video stream"
    for line in lines:
        m = _FFMPEG_LINE.match(line)
        if m and m.group(1) and "misdetection possible" not in m.group(1):
            cause = m.group(1).rstrip(".")
            if cause == "moov atom not found":
                cause += ": the mp4 has no index (truncated, never finished, or not an mp4)"
            return cause
    if "=== stderr ===" in text and lines:
        return lines[-1]
    return text.strip().splitlines()[0] if text.strip() else "no video stream"


class VideoReader:
    """Iterate over a video's frames as RGB uint8 arrays, decoded by imageio-ffmpeg.

    ``info`` (``video_info(path)``; given, it saves opening the file twice) is read when the reader
    is made, so a missing, empty, corrupt or undecodable file raises ``InputError`` there, not
    halfway through a run. A video that breaks off after some frames (a decoding error, or a
    truncated file ending well before its announced length) raises ``DecodeStoppedError`` after the
    frames it could decode, naming the clip's frame index; its ``frames`` counts those this reader
    yielded. One with no frame at all raises ``InputError``.

    ``start`` and ``stop`` (frame indices, as for ``range``; ``stop`` None: to the end) read part of
    the clip: ffmpeg seeks to ``start`` as ``read_frame`` does (decoding from the key frame before
    it) and stops after ``stop - start`` frames, the very frames a reader from the start yields at
    those indices.
    """

    def __init__(self, path: str | os.PathLike, start: int = 0, stop: int | None = None,
                 info: VideoInfo | None = None):
        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"{self.path}: no such video file; check the path")
        if self.path.stat().st_size == 0:
            raise InputError(f"{self.path}: the video file is empty (0 bytes); {_VIDEO_FIX}")
        for name, value in (("start", start), ("stop", stop)):
            if value is not None and (isinstance(value, (bool, np.bool_))
                                      or not isinstance(value, (int, np.integer)) or value < 0):
                raise InputError(f"{self.path}: {name} frame {value!r} is not a frame index; "
                                 "pass a whole number >= 0")
        self.start, self.stop = int(start), (None if stop is None else int(stop))
        if self.stop is not None and self.stop <= self.start:
            raise InputError(f"{self.path}: frames {self.start} to {self.stop} hold no frame; "
                             "pass a stop frame after the start frame")
        input_params = []
        if self.start > 0:
            info = info if info is not None else video_info(self.path)
            if self.start >= info.n_frames:
                raise InputError(f"{self.path}: frame {self.start} is outside the video (frames "
                                 f"0..{info.n_frames - 1}, {info.n_frames} frames at {info.fps:g} "
                                 "fps); pass a start frame in that range")
            # half a frame before the start frame's time, as read_frame seeks
            input_params = ["-ss", f"{max(0.0, (self.start - 0.5) / exact_fps(info.fps)):.6f}"]
        output_params = ["-frames:v", str(self.stop - self.start)] if self.stop is not None else None
        self._gen = imageio_ffmpeg.read_frames(str(self.path), pix_fmt="rgb24",
                                               input_params=input_params, output_params=output_params)
        try:
            meta = next(self._gen)
        except (RuntimeError, OSError, StopIteration) as e:
            self.close()
            raise InputError(f"{self.path}: not a readable video ({ffmpeg_cause(str(e))}); "
                             f"{_VIDEO_FIX}") from None
        w, h = meta.get("size", (0, 0))
        fps = float(meta.get("fps") or 0.0)
        if not w or not h or fps <= 0:
            self.close()
            raise InputError(f"{self.path}: no video stream found; {_VIDEO_FIX}")
        duration = float(meta.get("duration") or 0.0)
        self.info = VideoInfo(self.path, int(w), int(h), fps, int(round(duration * fps)))
        self._frame_bytes = int(w) * int(h) * 3

    def _stopped(self, n: int, cause: str) -> InputError:
        if n == 0:
            at = f" from frame {self.start} on" if self.start else ""
            return InputError(f"{self.path}: no frame could be decoded{at} ({cause}); {_VIDEO_FIX}")
        return DecodeStoppedError(f"{self.path}: decoding stopped at frame {self.start + n}: {cause}",
                                  n, cause)

    def __iter__(self) -> Iterator[np.ndarray]:
        w, h = self.info.size
        n = 0
        try:
            for raw in self._gen:
                if len(raw) != self._frame_bytes:
                    raise self._stopped(n, f"a partial frame ({len(raw)} of {self._frame_bytes} bytes)")
                n += 1
                yield np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)
        except RuntimeError as e:
            raise self._stopped(n, ffmpeg_cause(str(e))) from None
        announced = self.info.n_frames
        end = announced if self.stop is None else min(self.stop, announced)
        if n == 0:
            at = f" from frame {self.start} on" if self.start else ""
            raise InputError(f"{self.path}: the video holds no frames{at}; {_VIDEO_FIX}")
        if end - self.start - n > max(SHORTFALL_FRAMES, SHORTFALL_SHARE * announced):
            raise self._stopped(n, f"the file ends after {self.start + n} of the {announced} frames "
                                   "its container announces (truncated?)")

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._gen.close()

    def __enter__(self) -> "VideoReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def video_info(path: str | os.PathLike) -> VideoInfo:
    """Return the size, frame rate and frame count of the video at ``path`` (nothing is decoded).

    Raises
    ------
    InputError
        If the file is missing, empty, or not a video ffmpeg can read (see ``VideoReader``).
    """
    with VideoReader(path) as reader:
        return reader.info


# read_frame's index -> time: a frame's index is floor(t * fps + this), so a time that float
# rounding puts a hair before a frame's start still picks that frame
_TIME_EPS_FRAMES = 1e-6
_NTSC_RATES = (24, 30, 48, 60, 120)  # n * 1000 / 1001 fps, which ffmpeg prints as 23.98, 29.97, ...


def exact_fps(fps: float) -> float:
    """Return the frame rate ``fps`` stands for: an NTSC rate printed rounded (29.97) as n*1000/1001.
    The rounding moves ``t * fps`` by 3e-5 of a frame at frame 30, enough to pick the frame before.
    """
    n = round(fps * 1.001)
    return n * 1000 / 1001 if n in _NTSC_RATES and abs(fps - n * 1000 / 1001) < 0.006 else fps


def read_frame(path: str | os.PathLike, index: int | None = None, time_s: float | None = None,
               info: VideoInfo | None = None) -> np.ndarray:
    """Return one frame of the video at ``path`` as an RGB uint8 array (H x W x 3), found by seeking.

    Exactly one of ``index`` and ``time_s`` chooses the frame (by time: frame
    ``floor(time_s * fps + 1e-6)``). ffmpeg seeks to the key frame before it and decodes from
    there, so frame 240 costs a few frames' decoding, not 240, and the frame is the very one a
    ``VideoReader`` yields at that index (checked by ``tests/test_io.py``).

    Parameters
    ----------
    path : the video file.
    index : the frame's index, counted from 0.
    time_s : the frame's time in seconds from the video's start.
    info : the video's ``VideoInfo`` when the caller has it (``video_info(path)``); saves
        opening the file twice when reading many frames.

    Raises
    ------
    InputError
        If the file is missing or not a readable video, if neither or both of ``index`` and
        ``time_s`` are given, if the frame is outside the video, or if it cannot be decoded. The
        message names the file, the valid range and the fix.
    """
    p = Path(path)
    if (index is None) == (time_s is None):
        got = "both" if index is not None else "neither"
        raise InputError(f"{p}: read_frame needs a frame index or a time in seconds (got {got}); "
                         "pass index=N or time_s=T")
    info = info if info is not None else video_info(p)
    n, fps = info.n_frames, exact_fps(info.fps)
    if time_s is not None:
        t = float(time_s)
        end_s = n / fps
        if not (math.isfinite(t) and 0.0 <= t < end_s):
            raise InputError(f"{p}: time {time_s} s is outside the video (0 to {end_s:.3f} s, "
                             f"{n} frames at {info.fps:g} fps); pass a time in that range")
        index = min(math.floor(t * fps + _TIME_EPS_FRAMES), n - 1)
    if isinstance(index, (bool, np.bool_)) or not isinstance(index, (int, np.integer)):
        raise InputError(f"{p}: frame index {index!r} is not an integer; pass an index 0..{n - 1}")
    index = int(index)
    if not 0 <= index < n:
        raise InputError(f"{p}: frame {index} is outside the video (frames 0..{n - 1}, "
                         f"{n} frames at {info.fps:g} fps); pass an index in that range")
    # seek half a frame before the frame's time: ffmpeg drops the frames decoded before that
    # time and the first one it keeps is ``index``, whatever the rounding of its timestamp
    seek_s = max(0.0, (index - 0.5) / fps)
    w, h = info.size
    gen = imageio_ffmpeg.read_frames(str(p), pix_fmt="rgb24", input_params=["-ss", f"{seek_s:.6f}"],
                                     output_params=["-frames:v", "1"])
    try:
        next(gen)  # the meta data
        raw = next(gen, b"")
    except (RuntimeError, OSError, StopIteration) as e:
        raise InputError(f"{p}: frame {index} could not be decoded ({ffmpeg_cause(str(e))}); "
                         f"{_VIDEO_FIX}") from None
    finally:
        with contextlib.suppress(Exception):
            gen.close()
    if len(raw) != w * h * 3:
        got = "no frame" if not raw else f"a partial frame ({len(raw)} of {w * h * 3} bytes)"
        raise InputError(f"{p}: frame {index} could not be decoded ({got}: the file ends before "
                         f"the {n} frames its container announces?); pass an earlier frame or "
                         f"{_VIDEO_FIX}")
    return np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3).copy()
