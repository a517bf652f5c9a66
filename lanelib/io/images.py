"""Image files: reading them as RGB uint8 arrays, checking frames, encoding and writing them.

Images are RGB ``uint8`` arrays (H x W x 3) everywhere in lanelib; BGR exists only here, at
OpenCV's decoder and encoder. What a decoder prints on stderr while reading a file is kept as
that file's note, so a batch run prints one line per problem. ``write_image`` goes through
``files.atomic_path``.
"""
from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import cv2
import numpy as np

from ..errors import InputError
from .files import atomic_path

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")


@dataclass(frozen=True)
class ImageFileInfo:
    """What an image file held before ``read_image_info`` made it an RGB uint8 array.

    Parameters
    ----------
    path : the file.
    width, height : size in pixels.
    channels : 1 (grey) or 3 (colour) as decoded; an alpha channel is dropped.
    bit_depth : 8 or 16 bits per sample as stored; 16-bit samples keep their high byte
        (``value >> 8``: 65535 -> 255, 257 -> 1, 255 -> 0).
    colour : False when every pixel has R == G == B (a grey image, whatever its format).
    decoder_messages : what the decoder printed while reading an image it could still decode
        (e.g. libjpeg's "Corrupt JPEG data: ..."), one line each.
    """

    path: Path
    width: int
    height: int
    channels: int
    bit_depth: int
    colour: bool
    decoder_messages: tuple[str, ...] = ()


_IMAGE_FIX = "replace it with a valid jpg or png"
# "[ WARN:0@0.067] global grfmt_png.cpp:834 read_chunk " -> ""  (OpenCV's log prefix)
_CV_LOG_PREFIX = re.compile(r"^\[\s*(?:WARN|ERROR|INFO|FATAL)[^\]]*\]\s*(?:global\s+)?\S+:\d+\s+\S+\s+")


@contextlib.contextmanager
def captured_native_stderr() -> Iterator[list[str]]:
    """Yield a list that, when the block ends, holds the lines C code wrote to stderr inside it.

    libjpeg, libpng and OpenCV's log write to file descriptor 2, past ``sys.stderr``; captured, they
    become a file's note or error instead of breaking a run's one-line-per-problem output. Not
    thread-safe: another thread's writes to fd 2 during the block are captured too.
    """
    lines: list[str] = []
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to redirect: nothing to capture
        yield lines
        return
    try:
        with tempfile.TemporaryFile() as tmp:
            os.dup2(tmp.fileno(), 2)
            try:
                yield lines
            finally:
                os.dup2(saved, 2)
                tmp.seek(0)
                text = tmp.read().decode("utf-8", "replace")
                lines += [line.strip() for line in text.splitlines() if line.strip()]
    finally:
        os.close(saved)


def _decoder_message(line: str, limit: int = 160) -> str:
    """Return one decoder line without OpenCV's log prefix, cut to ``limit`` characters."""
    line = _CV_LOG_PREFIX.sub("", line.strip())
    return line if len(line) <= limit else line[:limit - 3] + "..."


def read_image_info(path: str | os.PathLike) -> tuple[np.ndarray, ImageFileInfo]:
    """Return the image at ``path`` as an RGB uint8 array (H x W x 3), and what the file held.

    Grey images get three equal channels, alpha is dropped, 16-bit samples keep their high byte
    (``value >> 8``); a JPEG's EXIF orientation is applied, as OpenCV does by default.

    Raises
    ------
    InputError
        If the file does not exist, is not a file, cannot be read, is empty, cannot be decoded,
        or holds samples other than 8- or 16-bit integers; the one-line message names the file,
        the cause and the fix.
    """
    p = Path(path)
    if not p.exists():
        if p.is_symlink():
            raise InputError(f"{p}: a broken symbolic link (its target is gone); fix or remove it")
        raise InputError(f"{p}: no such file; check the path")
    if not p.is_file():
        raise InputError(f"{p}: not a file; pass an image file (jpg or png)")
    try:
        data = p.read_bytes()
    except OSError as e:
        raise InputError(f"{p}: cannot be read ({e.strerror or e}); check its permissions") from None
    if not data:
        raise InputError(f"{p}: the file is empty (0 bytes); {_IMAGE_FIX}")
    failure = ""
    with captured_native_stderr() as printed:
        try:
            img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_ANYCOLOR | cv2.IMREAD_ANYDEPTH)
        except cv2.error as e:  # e.g. a header announcing more pixels than OpenCV allows
            img, failure = None, str(e).strip().splitlines()[-1] if str(e).strip() else "cv2.error"
    messages = tuple(dict.fromkeys(_decoder_message(m) for m in printed))  # distinct, in order
    if img is None or img.size == 0:
        cause = failure or (messages[0] if messages else
                            "no image format OpenCV can decode: not an image, or truncated")
        raise InputError(f"{p}: not a readable image ({_decoder_message(cause)}); {_IMAGE_FIX}")
    if img.dtype == np.uint16:
        bit_depth, img = 16, (img >> 8).astype(np.uint8)
    elif img.dtype == np.uint8:
        bit_depth = 8
    else:
        raise InputError(f"{p}: {img.dtype} samples are not supported; save the image with 8- or "
                         "16-bit integer samples (jpg or png)")
    if img.ndim == 2:
        channels, rgb = 1, cv2.cvtColor(img, cv2.COLOR_GRAY2RGB)
    elif img.ndim == 3 and img.shape[2] in (3, 4):
        channels = 3
        rgb = cv2.cvtColor(img, cv2.COLOR_BGR2RGB if img.shape[2] == 3 else cv2.COLOR_BGRA2RGB)
    else:
        raise InputError(f"{p}: an image of shape {img.shape} is not supported; {_IMAGE_FIX}")
    colour = channels == 3 and not (np.array_equal(rgb[..., 0], rgb[..., 1])
                                    and np.array_equal(rgb[..., 1], rgb[..., 2]))
    h, w = rgb.shape[:2]
    return rgb, ImageFileInfo(p, w, h, channels, bit_depth, colour, messages)


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Return the image at ``path`` as an RGB uint8 array (H x W x 3), converted as
    ``read_image_info`` says (grey, RGBA, 16-bit).

    Raises
    ------
    InputError
        If the file does not exist, is not a file, or cannot be decoded as an image.

    Examples
    --------
    >>> from lanelib import data
    >>> image = read_image(data.bundled("test_images") / "straight_1.jpg")
    >>> image.shape, image.dtype
    ((720, 1280, 3), dtype('uint8'))
    """
    return read_image_info(path)[0]


PIPELINE_SIZE_FIX = ("make a pipeline for this size (LanePipeline(config, calibration, size=...)) "
                     "or resize the frames")


def check_rgb(image, name: str = "image", size: tuple[int, int] | None = None, *,
              owner: str = "the pipeline", fix: str = PIPELINE_SIZE_FIX,
              mask_ok: bool = False) -> np.ndarray:
    """Return ``image`` as a C-contiguous RGB uint8 array (H x W x 3), without a copy when it is one:
    the one input check of every stage that takes a frame.

    Parameters
    ----------
    image : the array to check.
    name : what the array is, to lead the message ("frame", "image").
    size : (width, height) in px the image must have; None: any non-empty size.
    owner : what the size was set up for, for the message ("the pipeline", "the perspective").
    fix : what to do about a wrong size, for the message.
    mask_ok : also accept an H x W uint8 mask (e.g. a 0/255 binary to warp).

    Raises
    ------
    InputError
        If ``image`` is not an H x W x 3 uint8 array (or, with ``mask_ok``, H x W), is empty,
        or is not ``size``.
    """
    shape_ok = isinstance(image, np.ndarray) and image.dtype == np.uint8 and (
        (image.ndim == 3 and image.shape[2] == 3) or (mask_ok and image.ndim == 2))
    if not shape_ok:
        what = (f"shape {image.shape}, dtype {image.dtype}" if isinstance(image, np.ndarray)
                else type(image).__name__)
        mask = " or a uint8 mask (H x W)" if mask_ok else ""
        raise InputError(f"{name}: expected an RGB uint8 image array (H x W x 3){mask}, got {what}; "
                         "read frames with lanelib.io.read_image or VideoReader")
    h, w = image.shape[:2]
    if h < 1 or w < 1:
        raise InputError(f"{name}: expected a non-empty RGB image, got shape {image.shape}")
    if size is not None and (w, h) != (size[0], size[1]):
        raise InputError(f"{name}: is {w}x{h} but {owner} is set up for {size[0]}x{size[1]}; {fix}")
    return np.ascontiguousarray(image)


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
    """Return the entries of ``folder`` named like images (``IMAGE_SUFFIXES``), sorted by name; also
    one that is not a readable file (a folder ``x.jpg``, a broken link), so that a batch run
    reports it as an error rather than skip it silently.

    Raises
    ------
    InputError
        If the folder does not exist, cannot be listed, or holds no image files.
    """
    d = Path(folder)
    if not d.exists():
        raise InputError(f"{d}: no such folder; check the path")
    if not d.is_dir():
        raise InputError(f"{d}: not a folder; pass a folder of images")
    try:
        files = sorted(f for f in d.iterdir() if f.suffix.lower() in IMAGE_SUFFIXES)
    except OSError as e:
        raise InputError(f"{d}: cannot be listed ({e.strerror or e}); check its permissions") from None
    if not files:
        raise InputError(f"{d}: holds no images ({', '.join(IMAGE_SUFFIXES)}); "
                         "pass a folder that contains images")
    return files
