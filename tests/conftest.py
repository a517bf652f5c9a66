"""Shared test fixtures: where the real data lives (``lanelib.data``), the results tables, a
synthetic clip whose vanishing point the geometry watch refines (``bend_then_straight``), and a
folder of synthetic frames laid out like CULane's (``culane_folder``)."""
from __future__ import annotations

import math
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from lanelib import autogeometry, data, io
from lanelib.camera import calibrate
from lanelib.synth import Camera, CurvatureProfile, GroundGrid, video_sets, write_video

REPO = Path(__file__).resolve().parents[1]


def _data_set(fixture: str, name: str, what: str):
    """Return the session fixture ``fixture``: the path of the real data set ``name`` (``what``
    it holds), or a skip that says how to point at it."""

    def find() -> Path:
        path = data.dataset(name)
        if path is None:
            pytest.skip(data.missing_reason(name=name))
        return path

    find.__doc__ = f"Path of {name}/ ({what}), or skip."
    return pytest.fixture(find, scope="session", name=fixture)


udacity_advanced = _data_set("udacity_advanced", data.UDACITY_ADVANCED, "camera_cal, test_images, videos")
udacity_p1 = _data_set("udacity_p1", data.UDACITY_P1, "test_images, test_videos")
culane_dev = _data_set("culane_dev", data.CULANE_DEV, "driver_161_90frame/..., list.txt: 120 real CULane frames")
tusimple_dev = _data_set("tusimple_dev", data.TUSIMPLE_DEV,
                         "clips/..., label_data.json at 512x288, label_data_fullres.json at 1280x720")


@pytest.fixture(scope="session")
def udacity_calibration(udacity_advanced):
    """The calibration of the Udacity highway camera (computed once per test session)."""
    return data.udacity_calibration()


@pytest.fixture(scope="session")
def faststart(tmp_path_factory) -> Path:
    """videos/project.mp4 remuxed with its index (moov) first, as many cameras write: a cut file still plays."""
    out = tmp_path_factory.mktemp("faststart") / "project.mp4"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(REPO / "videos" / "project.mp4"),
                    "-c", "copy", "-movflags", "+faststart", str(out)], check=True)
    return out


RESULTS = REPO / "docs" / "results.md"  # the results tables the real-data tests recompute


def _cells(line: str) -> list[str]:
    """Return the cells of a Markdown table row (an escaped ``\\|`` stays inside its cell)."""
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip()[1:-1])]


@pytest.fixture(scope="session")
def readme_table():
    """Return a function: the first Markdown table after a heading of ``docs/results.md``, as a
    list of row dicts.

    The tests that guard the published figures read them from the page itself, so it cannot
    drift from what the code measures.
    """

    def table(heading: str) -> list[dict]:
        lines = RESULTS.read_text(encoding="utf-8").splitlines()
        try:
            start = next(i for i, line in enumerate(lines) if line.startswith("#") and heading in line)
        except StopIteration:
            raise AssertionError(f"docs/results.md has no heading with {heading!r}") from None
        block = []
        for line in lines[start + 1:]:
            if line.startswith("#"):
                break
            if line.startswith("|"):
                block.append(line)
            elif block:
                break
        assert len(block) >= 3, f"docs/results.md: no table under {heading!r}"
        head = _cells(block[0])
        return [dict(zip(head, _cells(line))) for line in block[2:]]

    return table


@pytest.fixture(scope="session")
def camera():
    """The calibration of the bundled (synthetic) camera, from ``camera_cal/`` (once per session)."""
    return calibrate(REPO / "camera_cal")


REFINE_CAMERA = Camera.pinhole((960, 540), hfov_deg=40.0, height_m=1.3, pitch_deg=-1.0, yaw_deg=1.5)


@pytest.fixture(scope="session")
def refine_camera() -> Camera:
    """The camera of ``bend_then_straight``: 960x540, 40 deg across, yawed 1.5 deg."""
    return REFINE_CAMERA


@pytest.fixture(scope="session")
def refine_options() -> autogeometry.GeometryOptions:
    """``--auto-geometry`` on ``bend_then_straight``: the first 4 s (12 frames), with the focal
    length as a calibration gives it (no dashes in 4 s)."""
    return autogeometry.GeometryOptions(seconds=4.0, max_frames=12, focal_px=480 / math.tan(math.radians(20.0)))


@pytest.fixture(scope="session")
def bend_then_straight(tmp_path_factory) -> Path:
    """16 s (400 frames) through ``refine_camera``: a gentle left bend (radius 4 km, straight
    enough to pass as straight) for the first 6 s, then straight road; the car weaves across its
    lane over one 16 s period (0.6 m), so that in the first 4 s it heads right of the road."""
    base = video_sets()["project"]
    profile = CurvatureProfile.from_segments(-1 / 4000, ((150, -1 / 4000), (20, 0.0), (600, 0.0)))
    clip = replace(base, name="refine", profile=profile, drift=((0.6, 16.0),))
    return write_video(tmp_path_factory.mktemp("refine") / "clip.mp4", clip, seconds=16.0,
                       grid=GroundGrid.build(REFINE_CAMERA))


def _road_frame(size_px: tuple[int, int], seed: int = 0) -> np.ndarray:
    """A synthetic road frame of ``size_px`` (w, h): grey asphalt, two white lines meeting at a
    vanishing point 35 % down the frame (RGB uint8)."""
    w, h = size_px
    rng = np.random.default_rng(seed)
    frame = np.clip(rng.normal(90, 6, (h, w, 3)), 0, 255).astype(np.uint8)
    vx, vy = w // 2 + 4 * seed, round(0.35 * h)
    for bottom_x in (round(0.15 * w), round(0.85 * w)):
        far = (round(vx + 0.1 * (bottom_x - vx)), round(vy + 0.1 * (h - vy)))
        cv2.line(frame, far, (bottom_x, h - 1), (235, 235, 235), max(2, w // 160), cv2.LINE_AA)
    return frame


@pytest.fixture(scope="session")
def road_frame():
    """Return a function: a synthetic road frame of a size (w, h), for folders of frames made in a
    test (grey asphalt, two white lines meeting at a vanishing point 35 % down the frame)."""
    return _road_frame


@pytest.fixture()
def culane_folder(tmp_path) -> Path:
    """A folder laid out like a CULane clip: three synthetic 1640x590 ``.jpg`` frames, each with
    its ``.lines.txt`` labels beside it, and a README that is no image."""
    folder = tmp_path / "driver_1_90frame" / "06030819_0755.MP4"
    folder.mkdir(parents=True)
    for i, stem in enumerate(("00000", "00030", "00060")):
        io.write_image(folder / f"{stem}.jpg", _road_frame((1640, 590), i))
        (folder / f"{stem}.lines.txt").write_text("300.5 580 420.2 560 \n1300.1 580 1200.7 560 \n")
    (folder / "README.txt").write_text("not an image\n")
    return folder
