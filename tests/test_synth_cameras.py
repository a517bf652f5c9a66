"""Tests of lanelib.synth with other cameras than the bundled one (issue 15, point 3): sizes,
focal lengths, mountings and roll; the renderer and the ground truth agree on each."""
from __future__ import annotations

import math

import numpy as np
import pytest

from lanelib.synth import (Camera, CarPose, CurvatureProfile, GroundGrid, Layout, Look, Renderer, Scene,
                           camera_truth, lane_truth, load_video_truth, video_sets, write_video)
from lanelib.synth.sets import METER_ROWS, meter_rows
from lanelib.synth.truth import NOT_VISIBLE, H_SAMPLES_PX, _camera_from_json, _camera_json, h_samples_px

ROLLED = Camera.pinhole((960, 540), hfov_deg=80.0, height_m=1.4, pitch_deg=1.0, yaw_deg=-2.0, roll_deg=1.5)


@pytest.fixture(scope="module")
def rolled_grid() -> GroundGrid:
    return GroundGrid.build(ROLLED)


def test_truth_rows_and_meter_rows_follow_the_image_height():
    assert h_samples_px((1280, 720)) == H_SAMPLES_PX
    assert h_samples_px((960, 540)) == tuple(range(320, 540, 10))
    assert h_samples_px((1920, 1080)) == tuple(range(630, 1080, 10))
    assert meter_rows(720) == METER_ROWS
    assert meter_rows(1080) == slice(660, 1020)


def test_the_hood_is_as_high_in_proportion(rolled_grid):
    bundled = GroundGrid.build(Camera())
    assert bundled.hood_top.min() == pytest.approx(694.0)
    assert rolled_grid.hood_top.min() == pytest.approx(540 - 26 * 540 / 720, abs=1e-3)


def test_camera_truth_round_trips_the_roll():
    truth = camera_truth(ROLLED)
    obj = _camera_json(truth)
    assert obj["roll_deg"] == 1.5
    back = _camera_from_json(obj, None)
    assert back.roll_deg == 1.5 and back.camera() == ROLLED
    assert back.horizon_px() == pytest.approx(ROLLED.horizon_px())
    # the bundled camera's truth does not hold the key: its files stay as they were
    assert "roll_deg" not in _camera_json(camera_truth(Camera()))


def test_rendered_lines_lie_on_their_truth_through_a_rolled_camera(rolled_grid):
    scene = Scene(CurvatureProfile(((0.0, -1 / 400),)), Layout(3.6), Look(), -20.0, 260.0, seed=31)
    renderer = Renderer(scene, rolled_grid)
    pose = CarPose(12.0, 0.2, 0.01)
    image = renderer.render(pose).astype(np.float64)
    lane = lane_truth(renderer, pose)
    assert lane.h_samples_px == h_samples_px((960, 540))
    yellow = image[..., 0] + image[..., 1] - 2 * image[..., 2]
    errors = []
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or row < 340:
            continue
        lo = int(round(x)) - 10
        if lo < 40 or lo + 61 > 960:
            continue
        profile = np.clip(yellow[row, lo:lo + 21] - np.median(yellow[row, lo - 40:lo + 61]), 0, None)
        errors.append((profile * np.arange(lo, lo + 21)).sum() / profile.sum() - x)
    assert len(errors) >= 10 and np.abs(errors).max() < 1.0


def test_a_video_through_another_camera_carries_its_truth(rolled_grid, tmp_path):
    path = write_video(tmp_path / "clip.mp4", video_sets()["project"], seconds=0.2, grid=rolled_grid)
    truth = load_video_truth(path)
    assert len(truth.frames) == 5 and truth.camera.size_px == (960, 540)
    assert truth.camera.roll_deg == 1.5 and truth.camera.camera() == ROLLED
    assert truth.frames[0].h_samples_px == h_samples_px((960, 540))
    left = truth.frames[0].points("left")
    assert len(left) >= 5 and np.all((left[:, 0] >= 0) & (left[:, 0] < 960))
    # the truth's perspective points are a lane centred on the car, 28.25 m ahead at the top
    p = truth.camera.perspective
    assert p.size_px == (960, 540) and p.dst_px[2] == (720.0, 540.0)
    assert p.visible_length_m == pytest.approx(28.25 - ROLLED.ground_z_on_line(540.0, 0.0), abs=0.2)
    assert math.isfinite(p.xm_per_px) and p.xm_per_px > 0
