"""The items a tuner's picker offers, as label -> path: the bundled and Udacity images and the
bundled videos."""
from __future__ import annotations

import os
from pathlib import Path

from .. import io
from ..data import UDACITY_ADVANCED, bundled, data_root

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


def is_video(path: str | os.PathLike) -> bool:
    """Return True if ``path`` is named like a video (``io.VIDEO_SUFFIXES``)."""
    return Path(path).suffix.lower() in io.VIDEO_SUFFIXES
