"""Reading and writing images and videos, and atomic output files.

Images are RGB ``uint8`` arrays (H x W x 3) everywhere in lanelib; BGR exists only inside this
module. Videos go through imageio-ffmpeg. Every output is written to a temporary file beside its
target and renamed into place, so an interrupted run never leaves a half-written file under the
output name, and no output may be written over one of the run's inputs.
"""
from __future__ import annotations

import contextlib
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import cv2
import numpy as np

from .errors import InputError

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm")


# --------------------------------------------------------------------------- images

def read_image(path: str | os.PathLike) -> np.ndarray:
    """Return the image at ``path`` as an RGB uint8 array (H x W x 3).

    Raises
    ------
    InputError
        If the file does not exist, is not a file, or cannot be decoded as an image.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file; check the path")
    if not p.is_file():
        raise InputError(f"{p}: not a file; pass an image file (jpg or png)")
    data = np.fromfile(str(p), dtype=np.uint8)
    bgr = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if bgr is None:
        raise InputError(f"{p}: not a readable image (empty, corrupt or not an image); "
                         "replace it with a valid jpg or png")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def encode_image(rgb: np.ndarray, suffix: str = ".png", jpeg_quality: int = 90) -> bytes:
    """Return ``rgb`` (or a single-channel mask) encoded as PNG or JPEG bytes."""
    arr = np.asarray(rgb)
    if arr.ndim == 3:
        arr = cv2.cvtColor(arr, cv2.COLOR_RGB2BGR)
    params = [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)] if suffix.lower() in (".jpg", ".jpeg") else []
    ok, buf = cv2.imencode(suffix, arr, params)
    if not ok:
        raise InputError(f"could not encode an image of shape {arr.shape} as {suffix}")
    return buf.tobytes()


def write_image(path: str | os.PathLike, rgb: np.ndarray, jpeg_quality: int = 95,
                inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``rgb`` to ``path`` atomically and return the path; the format follows the suffix."""
    p = Path(path)
    suffix = p.suffix.lower() or ".png"
    data = encode_image(rgb, suffix, jpeg_quality)
    with atomic_path(p, inputs=inputs) as tmp:
        tmp.write_bytes(data)
    return p


def list_images(folder: str | os.PathLike) -> list[Path]:
    """Return the image files directly in ``folder``, sorted by name.

    Raises
    ------
    InputError
        If the folder does not exist or holds no image files.
    """
    d = Path(folder)
    if not d.exists():
        raise InputError(f"{d}: no such folder; check the path")
    if not d.is_dir():
        raise InputError(f"{d}: not a folder; pass a folder of images")
    files = sorted(f for f in d.iterdir() if f.suffix.lower() in IMAGE_SUFFIXES and f.is_file())
    if not files:
        raise InputError(f"{d}: holds no images ({', '.join(IMAGE_SUFFIXES)}); "
                         "pass a folder that contains images")
    return files


# --------------------------------------------------------------------------- atomic output

def check_not_input(target: str | os.PathLike, inputs: Iterable[str | os.PathLike]) -> None:
    """Raise InputError if ``target`` is the same file as one of ``inputs``."""
    t = Path(target).resolve()
    for i in inputs:
        if Path(i).resolve() == t:
            raise InputError(f"{target}: output would overwrite an input; choose another output path")


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` when the block succeeds.

    The temporary file keeps ``target``'s suffix (ffmpeg chooses the container by it). On any
    exception, KeyboardInterrupt included, the temporary file is removed and ``target`` is left
    as it was.
    """
    t = Path(target)
    check_not_input(t, inputs)
    t.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{t.stem}.", suffix=f".part{t.suffix}", dir=t.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; outputs get the usual permissions
    try:
        yield tmp
        os.replace(tmp, t)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def write_text(path: str | os.PathLike, text: str, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``text`` to ``path`` atomically and return the path."""
    with atomic_path(path, inputs=inputs) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_json(path: str | os.PathLike, obj, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``obj`` as indented JSON to ``path`` atomically and return the path."""
    return write_text(path, json.dumps(obj, indent=2) + "\n", inputs=inputs)


def read_json(path: str | os.PathLike, what: str = "JSON file"):
    """Return the parsed JSON at ``path``; a missing or malformed file raises InputError."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such {what}; check the path")
    try:
        return json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: not valid JSON ({e}); fix or regenerate the {what}") from None


# --------------------------------------------------------------------------- video

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


class VideoReader:
    """Iterate over a video's frames as RGB uint8 arrays, decoded by imageio-ffmpeg.

    ``info`` is read when the reader is made, so an empty, corrupt or missing file raises
    ``InputError`` there, with the file's name, not halfway through a run.
    """

    def __init__(self, path: str | os.PathLike):
        import imageio_ffmpeg

        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"{self.path}: no such video file; check the path")
        if self.path.stat().st_size == 0:
            raise InputError(f"{self.path}: the video file is empty; pass a valid video (mp4)")
        self._gen = imageio_ffmpeg.read_frames(str(self.path), pix_fmt="rgb24")
        try:
            meta = next(self._gen)
        except (RuntimeError, OSError, StopIteration) as e:
            self.close()
            raise InputError(f"{self.path}: not a readable video ({str(e).splitlines()[0] if str(e) else 'no stream'}); "
                             "pass a valid video (mp4, H.264)") from None
        w, h = meta.get("size", (0, 0))
        fps = float(meta.get("fps") or 0.0)
        if not w or not h or fps <= 0:
            self.close()
            raise InputError(f"{self.path}: no video stream found; pass a valid video (mp4, H.264)")
        duration = float(meta.get("duration") or 0.0)
        self.info = VideoInfo(self.path, int(w), int(h), fps, int(round(duration * fps)))
        self._frame_bytes = int(w) * int(h) * 3

    def __iter__(self) -> Iterator[np.ndarray]:
        w, h = self.info.size
        n = 0
        try:
            for raw in self._gen:
                if len(raw) != self._frame_bytes:
                    break
                n += 1
                yield np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)
        except RuntimeError as e:
            raise InputError(f"{self.path}: decoding failed after {n} frames ({e}); "
                             "the video may be truncated or corrupt") from None
        if n == 0:
            raise InputError(f"{self.path}: the video holds no frames; pass a valid video")

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._gen.close()

    def __enter__(self) -> "VideoReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# The H.264 settings every lanelib video is written with (the codec benchmark uses the same).
H264_PARAMS = dict(codec="libx264", pix_fmt_out="yuv420p", quality=None, bitrate=None,
                   macro_block_size=1, output_params=["-preset", "veryfast", "-crf", "20"])


class VideoWriter:
    """Write RGB uint8 frames to an H.264 mp4 through imageio-ffmpeg, atomically.

    Frames go to a temporary file beside ``path``; ``close()`` renames it into place. Leaving the
    ``with`` block by an exception (Ctrl-C included) removes the temporary file, so no
    half-written video ever stands under the output name.
    """

    def __init__(self, path: str | os.PathLike, fps: float, size: tuple[int, int] | None = None,
                 inputs: Iterable[str | os.PathLike] = (), threads: int | None = None):
        self.path = Path(path)
        self.fps = float(fps)
        self.size = size
        self._inputs = list(inputs)
        self._threads = threads
        self._ctx = atomic_path(self.path, inputs=self._inputs)
        self._tmp = self._ctx.__enter__()
        self._gen = None
        self.frames_written = 0

    def _start(self, size: tuple[int, int]) -> None:
        import imageio_ffmpeg

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
