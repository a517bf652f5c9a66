"""The items a tuner's picker offers: the bundled and Udacity images, the bundled videos, and the
images and videos of any folder (``folder_choices``), as label -> path."""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Callable, Mapping

from .. import io
from ..data import UDACITY_ADVANCED, bundled, data_root
from ..errors import InputError

UDACITY_PREFIX = "udacity/"
VIDEO_PREFIX = "videos/"


def image_choices(root: str | os.PathLike | None = None,
                  data: str | os.PathLike | None = None, videos: bool = False) -> dict[str, Path]:
    """Return the picker's images: label -> path, bundled ``test_images/`` first.

    Bundled images are labelled by file name; the Udacity test images, when ``data`` (default
    ``data_root()``) holds ``udacity-advanced/test_images``, follow as ``"udacity/<name>"``; with
    ``videos``, the bundled videos come last as ``"videos/<name>"`` (``video_choices``).
    """
    out = {p.name: p for p in io.list_images(bundled("test_images", root))}
    extra = Path(data if data is not None else data_root()) / UDACITY_ADVANCED / "test_images"
    if extra.is_dir():
        out.update({UDACITY_PREFIX + p.name: p for p in io.list_images(extra)})
    if videos:
        out.update(video_choices(root))
    return out


def video_choices(root: str | os.PathLike | None = None) -> dict[str, Path]:
    """Return the bundled videos (``videos/*.mp4``) as picker items: ``"videos/<name>"`` -> path.

    Give them to a tuner with the images (``{**image_choices(), **video_choices()}``, or
    ``image_choices(videos=True)``): picking one shows a frame slider.
    """
    folder = bundled("videos", root)
    files = sorted(folder.glob("*.mp4")) if folder.is_dir() else []
    return {VIDEO_PREFIX + p.name: p for p in files}


def folder_choices(folder: str | os.PathLike, pattern: str = "**/*") -> dict[str, Path]:
    """Return the images and videos in ``folder`` as picker items: relative path -> path.

    Parameters
    ----------
    folder : the folder to list.
    pattern : which files, as a ``Path.glob`` pattern relative to ``folder``; the default lists
        every file at any depth, ``"*.jpg"`` only those in ``folder`` itself,
        ``"*/*/20.jpg"`` the last frame of each clip of a TuSimple ``clips/`` tree.

    Returns
    -------
    dict
        Every file the pattern matches whose suffix is an image's or a video's
        (``io.IMAGE_SUFFIXES``, ``io.VIDEO_SUFFIXES``), labelled by its path relative to
        ``folder`` with ``/`` between folders (``00090.jpg``, ``0313-1/8260/20.jpg``), in natural
        order (``8260`` before ``14900``). Other files (a CULane frame's ``.lines.txt`` beside it,
        JSON labels) and hidden files and folders are left out.

    Raises
    ------
    InputError
        If ``folder`` is no folder, or holds no image or video the pattern matches.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from lanelib import io
    >>> root = Path(tempfile.mkdtemp())
    >>> frame = np.zeros((59, 164, 3), np.uint8)
    >>> for name in ("clip/10.jpg", "clip/9.jpg", "clip/9.lines.txt", "00000.jpg"):
    ...     (root / name).parent.mkdir(exist_ok=True)
    ...     _ = io.write_image(root / name, frame) if name.endswith(".jpg") else (root / name).write_text("")
    >>> list(folder_choices(root))
    ['00000.jpg', 'clip/9.jpg', 'clip/10.jpg']
    """
    root = Path(folder)
    if not root.is_dir():
        what = "not a folder" if root.exists() else "no such folder"
        raise InputError(f"{root}: {what}; pass a folder of frames (e.g. a CULane "
                         "driver_*/*.MP4/ folder) or {label: path} of the images to pick from")
    suffixes = io.IMAGE_SUFFIXES + io.VIDEO_SUFFIXES
    try:
        found = list(root.glob(pattern))
    except (ValueError, NotImplementedError) as e:
        raise InputError(f"{root}: pattern {pattern!r} cannot be listed ({e}); pass a pattern "
                         "relative to the folder, e.g. '**/*.jpg'") from None
    files = {f.relative_to(root).as_posix(): f for f in found
             if f.suffix.lower() in suffixes and f.is_file()
             and not any(part.startswith(".") for part in f.relative_to(root).parts)}
    if not files:
        raise InputError(f"{root}: holds no images or videos matching {pattern!r} "
                         f"({', '.join(suffixes)}); pass the folder that holds the frames, "
                         "or a pattern that matches them (e.g. '*/*/20.jpg')")
    return {label: files[label] for label in sorted(files, key=_natural)}


def _natural(label: str) -> list:
    """Return the sort key of ``label`` that orders its runs of digits as numbers."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", label)]


def picker_items(images: Mapping[str, str | os.PathLike] | str | os.PathLike | None,
                 default: Callable[[], Mapping[str, str | os.PathLike]]) -> dict[str, Path]:
    """Return a tuner's ``images`` as picker items: label -> path.

    A mapping is taken as it is, a folder is listed (``folder_choices``), None gives
    ``default()``.
    """
    if images is None:
        images = default()
    elif isinstance(images, (str, os.PathLike)):
        images = folder_choices(images)
    return {k: Path(v) for k, v in images.items()}


def is_video(path: str | os.PathLike) -> bool:
    """Return True if ``path`` is named like a video (``io.VIDEO_SUFFIXES``)."""
    return Path(path).suffix.lower() in io.VIDEO_SUFFIXES
