"""Where data lives: the repository's bundled data and the Udacity data beside it.

The only module that reads ``LANELIB_DATA``. The notebooks, the tuners, the benchmarks and the
tests ask here instead of building paths of their own.

- The **repository** holds the bundled synthetic data: ``camera_cal/``, ``test_images/`` and
  ``videos/`` (``repo_root``, ``bundled``).
- The **Udacity data** (MIT-licensed lane-finding images, chessboards and clips) is read in place
  from the folder ``LANELIB_DATA`` names, by default ``../shared/data`` beside the repository. It
  holds ``udacity-advanced/`` (``camera_cal/``, ``test_images/``, ``videos/project_video.mp4``)
  and ``udacity-lanelines-p1/`` (``test_images/``, ``test_videos/``). Where it is absent, the
  functions below return None or raise ``InputError`` saying how to point at it.
"""
from __future__ import annotations

import functools
import os
from pathlib import Path

from .camera import Calibration, calibrate
from .errors import InputError

ENV = "LANELIB_DATA"
UDACITY_ADVANCED = "udacity-advanced"
UDACITY_P1 = "udacity-lanelines-p1"
PACKAGE_REPO = Path(__file__).resolve().parents[1]
BUNDLED = ("camera_cal", "test_images", "videos")
HOW_TO_POINT = (f"set {ENV} to the folder holding {UDACITY_ADVANCED}/ and {UDACITY_P1}/ "
                "(default: ../shared/data beside the repository; see the README, 'The Udacity dataset')")


def repo_root(start: str | os.PathLike | None = None) -> Path:
    """Return the repository folder: the first folder holding ``test_images/``, walking up.

    Parameters
    ----------
    start : folder to start from (default: the current folder, e.g. ``notebooks/``); when
        neither it nor a folder above holds ``test_images/``, the folder of this package's
        checkout is used if it holds them.

    Raises
    ------
    InputError
        If no such folder is found.
    """
    here = Path(start if start is not None else os.getcwd()).resolve()
    for folder in (here, *here.parents):
        if (folder / "test_images").is_dir():
            return folder
    if start is None and (PACKAGE_REPO / "test_images").is_dir():
        return PACKAGE_REPO
    raise InputError(f"{here}: no folder holding test_images/ here or above; run from inside the "
                     "lanelib repository or pass the repository folder")


def bundled(kind: str, root: str | os.PathLike | None = None) -> Path:
    """Return the bundled data folder ``kind`` (camera_cal, test_images or videos) of the repository."""
    if kind not in BUNDLED:
        raise InputError(f"{kind!r}: the bundled data folders are {', '.join(BUNDLED)}")
    return repo_root(root) / kind


def data_root() -> Path:
    """Return the folder of the Udacity data: ``$LANELIB_DATA``, else ``../shared/data`` beside the repo."""
    env = os.environ.get(ENV)
    if env:
        return Path(env).expanduser()
    return PACKAGE_REPO.parent / "shared" / "data"


def udacity(sub: str = "", name: str = UDACITY_ADVANCED) -> Path | None:
    """Return ``<data_root>/<name>/<sub>`` when it exists, else None.

    Parameters
    ----------
    sub : path inside the data set, e.g. ``"videos/project_video.mp4"`` or ``"test_images"``.
    name : the data set folder: ``UDACITY_ADVANCED`` (default) or ``UDACITY_P1``.
    """
    path = data_root() / name / sub if sub else data_root() / name
    return path if path.exists() else None


def require_udacity(sub: str = "", name: str = UDACITY_ADVANCED) -> Path:
    """Return ``udacity(sub, name)``; raise ``InputError`` saying how to point at the data if absent."""
    path = udacity(sub, name)
    if path is None:
        missing = data_root() / name / sub if sub else data_root() / name
        raise InputError(f"{missing} not found: {HOW_TO_POINT}")
    return path


def missing_reason(sub: str = "", name: str = UDACITY_ADVANCED) -> str:
    """Return why ``udacity(sub, name)`` is None and how to fix it (for skip messages)."""
    missing = data_root() / name / sub if sub else data_root() / name
    return f"{missing} not found: {HOW_TO_POINT}"


@functools.lru_cache(maxsize=4)
def _calibration_of(folder: Path) -> Calibration:
    return calibrate(folder)


def udacity_calibration() -> Calibration:
    """Return the Udacity highway camera's calibration from its chessboards (computed once).

    Raises ``InputError`` saying how to point at the data when it is absent.
    """
    return _calibration_of(require_udacity("camera_cal").resolve())
