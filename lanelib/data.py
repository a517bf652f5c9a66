"""Where data lives: the repository's bundled data and the real data beside it.

The only module that reads ``LANELIB_DATA``; notebooks, tuners, benchmarks, scoreboard and tests
ask here instead of building paths of their own.

- The **repository** holds the bundled synthetic data: ``camera_cal/``, ``test_images/`` and
  ``videos/`` (``repo_root``, ``bundled``).
- The **real data** is read in place from the folder ``LANELIB_DATA`` names, by default
  ``../shared/data`` beside the repository (``data_root``): the MIT-licensed Udacity data,
  ``udacity-advanced/`` (``camera_cal/``, ``test_images/``, ``videos/project_video.mp4``,
  ``videos/challenge_video.mp4``) and ``udacity-lanelines-p1/`` (``test_images/``,
  ``test_videos/``); labelled frames in the benchmarks' formats, ``culane-dev/``
  (``driver_161_90frame/...``, ``list.txt``) and ``tusimple-dev/`` (``clips/...``,
  ``label_data.json`` at 512x288, ``label_data_fullres.json`` at 1280x720). ``dataset`` and
  ``require`` find a path in them (``udacity``, ``require_udacity``, ``culane_dev``,
  ``tusimple_dev``, ``challenge_video`` name the usual ones), returning None or raising
  ``InputError`` when it is absent; ``missing_reason`` says how to point at it.
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
CULANE_DEV = "culane-dev"
TUSIMPLE_DEV = "tusimple-dev"
PROJECT_VIDEO = "videos/project_video.mp4"       # in UDACITY_ADVANCED
CHALLENGE_VIDEO = "videos/challenge_video.mp4"   # in UDACITY_ADVANCED
CULANE_DEV_LIST = "list.txt"                     # in CULANE_DEV: CULane's list of its images
TUSIMPLE_DEV_LABELS = "label_data.json"          # in TUSIMPLE_DEV: the labels at 512x288
TUSIMPLE_DEV_FULLRES = "label_data_fullres.json"  # in TUSIMPLE_DEV: the official 1280x720 rows
# the file a data set's folder is used by: without it the set counts as absent
NEEDS = {CULANE_DEV: CULANE_DEV_LIST, TUSIMPLE_DEV: TUSIMPLE_DEV_FULLRES}
PACKAGE_REPO = Path(__file__).resolve().parents[1]
BUNDLED = ("camera_cal", "test_images", "videos")
HOW_TO_POINT = (f"set {ENV} to the folder holding {UDACITY_ADVANCED}/ and {UDACITY_P1}/ (Udacity data), "
                f"{CULANE_DEV}/ and {TUSIMPLE_DEV}/ (real benchmark frames); default: ../shared/data "
                "beside the repository (see docs/guide.md)")


def repo_root(start: str | os.PathLike | None = None) -> Path:
    """Return the repository folder: the first folder holding ``test_images/``, walking up.

    Parameters
    ----------
    start : folder to start from (default: the current folder, e.g. ``notebooks/``); failing it
        and its parents, this package's checkout if it holds ``test_images/``.

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
    """Return the folder of the real data: ``$LANELIB_DATA``, else ``../shared/data`` beside the repo."""
    env = os.environ.get(ENV)
    if env:
        return Path(env).expanduser()
    return PACKAGE_REPO.parent / "shared" / "data"


def _path(name: str, sub: str) -> Path:
    return data_root() / name / sub if sub else data_root() / name


def dataset(name: str, sub: str = "") -> Path | None:
    """Return ``<data_root>/<name>/<sub>`` when it exists, else None.

    Parameters
    ----------
    name : the data set folder: ``UDACITY_ADVANCED``, ``UDACITY_P1``, ``CULANE_DEV`` or
        ``TUSIMPLE_DEV``. A set listed in ``NEEDS`` counts as absent without its file there.
    sub : path inside the data set, e.g. ``PROJECT_VIDEO`` or ``"test_images"``.

    Examples
    --------
    >>> dataset(UDACITY_ADVANCED, "no/such/file.mp4") is None
    True
    """
    if name in NEEDS and not _path(name, NEEDS[name]).is_file():
        return None
    path = _path(name, sub)
    return path if path.exists() else None


def require(name: str, sub: str = "") -> Path:
    """Return ``dataset(name, sub)``; raise ``InputError`` saying how to point at the data if absent."""
    path = dataset(name, sub)
    if path is None:
        raise InputError(missing_reason(sub, name))
    return path


def missing_reason(sub: str = "", name: str = UDACITY_ADVANCED) -> str:
    """Return why ``dataset(name, sub)`` is None and how to fix it (for skip messages), naming the
    path looked for: ``sub``, or the file a set in ``NEEDS`` needs when that is missing.

    Examples
    --------
    >>> "LANELIB_DATA" in missing_reason("no_such_file.txt", CULANE_DEV)
    True
    """
    need = NEEDS.get(name, "")
    missing = _path(name, need) if need and not _path(name, need).is_file() else _path(name, sub)
    return f"{missing} not found: {HOW_TO_POINT}"


def udacity(sub: str = "", name: str = UDACITY_ADVANCED) -> Path | None:
    """Return ``dataset(name, sub)``: a path in the Udacity data (``UDACITY_ADVANCED`` by default)."""
    return dataset(name, sub)


def require_udacity(sub: str = "", name: str = UDACITY_ADVANCED) -> Path:
    """Return ``require(name, sub)``: a path in the Udacity data, or ``InputError`` saying how to point at it."""
    return require(name, sub)


def culane_dev() -> Path | None:
    """Return the root of the real CULane frames (``driver_161_90frame/...``, ``CULANE_DEV_LIST``), or None."""
    return dataset(CULANE_DEV)


def tusimple_dev() -> Path | None:
    """Return the root of the real TuSimple frames (``clips/...``, ``TUSIMPLE_DEV_LABELS`` at
    512x288, ``TUSIMPLE_DEV_FULLRES`` at 1280x720), or None."""
    return dataset(TUSIMPLE_DEV)


def challenge_video() -> Path | None:
    """Return the Udacity challenge video (the highway camera of ``udacity_calibration``), or None."""
    return dataset(UDACITY_ADVANCED, CHALLENGE_VIDEO)


@functools.lru_cache(maxsize=4)
def _calibration_of(folder: Path) -> Calibration:
    return calibrate(folder)


def udacity_calibration() -> Calibration:
    """Return the Udacity highway camera's calibration from its chessboards (computed once); raises
    ``InputError`` saying how to point at the data when it is absent.
    """
    return _calibration_of(require_udacity("camera_cal").resolve())
