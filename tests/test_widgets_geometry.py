"""``PerspectiveTuner``'s "estimate from this clip/frame" (issue 15, point 5): the road geometry
estimated from the road itself fills the points, the readout shows it (and flags a low
confidence), and a failed estimate shows its reason and changes nothing."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from lanelib import batch, io, widgets
from lanelib.errors import GeometryError, InputError
from lanelib.autogeometry import estimate_geometry
from lanelib.perspective import Perspective, PerspectiveConfig
from lanelib.widgets.perspective import ESTIMATE_LABELS, _values, carried_car_x

REPO = Path(__file__).resolve().parents[1]
CLIP = "videos/project.mp4"
STRAIGHT = "straight_1.jpg"



@pytest.fixture(scope="module")
def clip_geometry(camera):
    """What ``python -m lanelib geometry videos/project.mp4 --calibration ...`` estimates."""
    return batch.estimate_road_geometry(REPO / CLIP, camera)


@pytest.fixture(scope="module")
def clicked(camera):
    """A tuner on the bundled clip whose estimate button was pressed once."""
    tuner = widgets.PerspectiveTuner({CLIP: REPO / CLIP, STRAIGHT: REPO / "test_images" / STRAIGHT},
                                     calibration=camera)
    before = tuner.config
    assert tuner.estimate_button.description == ESTIMATE_LABELS[True] == "estimate from this clip"
    tuner.estimate_button.click()
    return tuner, before


def test_the_button_sets_exactly_the_estimated_points(clicked, clip_geometry):
    tuner, before = clicked
    assert tuner.error == "" and not tuner.estimate_button.disabled
    expected = clip_geometry.perspective_config()
    pc = tuner.config.perspective
    assert pc == expected != before.perspective
    assert pc.car_x_px == expected.car_x_px is not None
    assert pc.visible_length_m == clip_geometry.visible_length_m
    assert tuner.config.thresholds == before.thresholds and tuner.config.search == before.search
    assert tuner.geometry.to_dict() == clip_geometry.to_dict()
    # every control shows the points: the per-corner boxes exactly, the sliders their summary
    values = _values(expected)
    for key, value in values.items():
        assert tuner.controls[key].value == value, key
    for corner, (x, y) in zip(("tl", "bl", "br", "tr"), expected.src_px):
        assert (tuner.controls[f"src.{corner}.x"].value, tuner.controls[f"src.{corner}.y"].value) == (x, y)
    # the view and the check follow
    assert tuner.perspective.car_x_px == expected.car_x_px
    assert tuner.check.lane_width_m == pytest.approx(3.7, abs=0.15)


def test_the_readout_shows_the_estimate_and_its_confidence(clicked, clip_geometry):
    tuner, _ = clicked
    text = tuner.readout()
    assert "road geometry estimated from the clip videos/project.mp4, 20 s from 0 s:" in text
    for line in clip_geometry.summary().splitlines():
        assert line in text
    assert f"confidence {clip_geometry.confidence:.2f}" in text and clip_geometry.confidence >= 0.5
    assert "low confidence" not in text and "changed since" not in text
    assert "lanes 3.7 m wide" in text
    assert "vanishing point" in tuner.message.value and "color:#c00" not in tuner.message.value


def test_the_preview_draws_the_horizon_and_the_vanishing_point(clicked, clip_geometry):
    tuner, _ = clicked
    tile = tuner.render()["undistorted + src"]
    th, tw = tile.shape[:2]
    row = round(clip_geometry.horizon_row_px * th / clip_geometry.size_px[1])
    cyan = (tile[row, :, 0] < 80) & (tile[row, :, 1] > 200) & (tile[row, :, 2] > 200)
    assert cyan.mean() > 0.8
    # another frame of the same clip keeps the estimate; another item drops it
    config = tuner.config
    tuner.frame = 100
    assert tuner.geometry is not None and tuner.config == config
    assert "road geometry estimated" in tuner.readout()
    tuner.picker.value = STRAIGHT
    try:
        assert tuner.geometry is None and "road geometry" not in tuner.readout()
        assert tuner.estimate_button.description == "estimate from this frame"
    finally:
        tuner.picker.value = CLIP
        tuner.set_geometry(clip_geometry, "the clip videos/project.mp4, 20 s from 0 s")


def test_moving_a_point_keeps_the_car_line_and_says_the_points_changed(camera, clip_geometry):
    tuner = widgets.PerspectiveTuner({CLIP: REPO / CLIP}, calibration=camera)
    tuner.set_geometry(clip_geometry)
    geo_pc = clip_geometry.perspective_config()
    assert tuner.config.perspective == geo_pc
    assert "road geometry estimated:" in tuner.readout()
    tuner.controls["dst.left_x"].value = 300.0
    pc = tuner.config.perspective
    assert pc.src_px == geo_pc.src_px and pc.dst_px[0] == (300.0, 0.0)
    # the car's line stays the same line on the road: 640 was the centre of 320..960, now 300..960
    assert pc.car_x_px == pytest.approx(300 + (geo_pc.car_x_px - 320) * 660 / 640, abs=1e-3)
    assert "(the points have been changed since this estimate)" in tuner.readout()
    tuner.controls["top_y"].value = 480.0
    assert tuner.config.perspective.car_x_px is not None
    assert tuner.config.perspective.car_x_px == pytest.approx(pc.car_x_px, abs=2.0)
    tuner.set_geometry(clip_geometry)
    assert tuner.config.perspective == geo_pc and "changed since" not in tuner.readout()


def test_carried_car_x():
    pc = PerspectiveConfig(car_x_px=700.0)
    assert carried_car_x(PerspectiveConfig(), Perspective(pc)) is None  # no car line: stays None
    assert carried_car_x(pc, Perspective(pc)) == 700.0
    wider = replace(pc, dst_px=((300.0, 0.0), (300.0, 720.0), (960.0, 720.0), (960.0, 0.0)))
    assert carried_car_x(pc, Perspective(wider)) == pytest.approx(300 + 380 * 660 / 640, abs=1e-3)


def test_a_frame_with_no_road_shows_the_reason_and_changes_nothing(camera, tmp_path):
    grey = tmp_path / "grey.png"
    io.write_image(grey, np.full((720, 1280, 3), 118, np.uint8))
    tuner = widgets.PerspectiveTuner({"grey.png": grey}, calibration=camera)
    assert tuner.estimate_button.description == "estimate from this frame"
    before = tuner.config
    with pytest.raises(GeometryError) as e:
        estimate_geometry([io.read_image(grey)], camera)
    tuner.estimate_button.click()
    assert tuner.config == before and tuner.geometry is None
    assert str(e.value) in tuner.error and tuner.error.startswith("grey.png: ")
    assert "no road" in tuner.error
    assert "color:#c00" in tuner.message.value and "no road" in tuner.message.value
    assert not tuner.estimate_button.disabled
    with pytest.raises(GeometryError, match="no road"):
        tuner.estimate()
    assert tuner.config == before


def test_one_frame_is_applied_with_a_low_confidence_flag(camera):
    tuner = widgets.PerspectiveTuner({STRAIGHT: REPO / "test_images" / STRAIGHT}, calibration=camera)
    before = tuner.config
    with pytest.raises(GeometryError, match="below 0.5"):
        tuner.estimate(accept_low_confidence=False)  # refused when asked to: nothing changes
    assert tuner.config == before and tuner.geometry is None
    tuner.estimate_button.click()
    geo = tuner.geometry
    assert geo.low_confidence and len(geo.frames_used) == 1
    assert tuner.config.perspective == geo.perspective_config()
    text = tuner.readout()
    assert ("low confidence: 0.04, below 0.5 (1 frame on straight road) - check the points before "
            "saving") in text
    assert "road geometry estimated from this frame alone (straight_1.jpg):" in text
    assert '<b style="color:#c60">low confidence' in tuner.message.value
    # options pass through: a longer look-ahead
    far = tuner.estimate(look_ahead_m=30.0)
    assert far.look_ahead_m == 30.0 and tuner.config.perspective == far.perspective_config()


def test_bad_options_are_refused(camera):
    tuner = widgets.PerspectiveTuner({STRAIGHT: REPO / "test_images" / STRAIGHT}, calibration=camera)
    with pytest.raises(InputError, match="unknown options"):
        tuner.estimate(lane_width=3.5)
    with pytest.raises(InputError, match="start_s is for a video"):
        tuner.estimate(start_s=2.0)
    assert tuner.geometry is None and "lanelib-control-estimate" in tuner.estimate_button._dom_classes
