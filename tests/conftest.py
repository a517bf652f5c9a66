"""Shared test fixtures: where the Udacity data lives, and small synthetic frames."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def data_root() -> Path:
    """Return the folder holding the Udacity data (LANELIB_DATA, default ../shared/data)."""
    return Path(os.environ.get("LANELIB_DATA", REPO.parent / "shared" / "data"))


def _need(sub: str) -> Path:
    path = data_root() / sub
    if not path.exists():
        pytest.skip(f"{path} not found: set LANELIB_DATA to the folder holding {sub.split('/')[0]}/ "
                    "(see README, 'Using the Udacity data')")
    return path


@pytest.fixture(scope="session")
def udacity_advanced() -> Path:
    """Path of udacity-advanced/ (camera_cal, test_images, videos), or skip."""
    return _need("udacity-advanced")


@pytest.fixture(scope="session")
def udacity_p1() -> Path:
    """Path of udacity-lanelines-p1/ (test_images, test_videos), or skip."""
    return _need("udacity-lanelines-p1")


@pytest.fixture(scope="session")
def udacity_calibration(udacity_advanced):
    """The calibration of the Udacity highway camera (computed once per test session)."""
    import warnings

    from lanelib.camera import calibrate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(udacity_advanced / "camera_cal")
