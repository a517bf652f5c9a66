"""``PerspectiveTuner``'s four points: per-corner controls, the symmetric shortcut, ``set_points``
and clicks on the preview (synthetic ``ipyevents`` event dicts, as the browser sends them); folders
of frames of other sizes (CULane-like 1640x590, a TuSimple-like tree)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import ipyevents
import numpy as np
import pytest

from lanelib import io, widgets
from lanelib.camera import Calibration, Lens
from lanelib.config import PipelineConfig, load_config, save_config
from lanelib.errors import InputError
from lanelib.perspective import Perspective, PerspectiveConfig, scaled
from lanelib.widgets.perspective import FastBirdseye, click_to_frame

REPO = Path(__file__).resolve().parents[1]
STRAIGHT = "straight_1.jpg"

# published point sets for the 1280x720 Udacity camera, in lanelib's order (tl, bl, br, tr),
# with their dst lines' x (dst rows 0..720); both are off-centre
PUBLISHED = [
    (((595, 450), (216, 720), (1115, 720), (690, 450)), (450, 830)),
    (((579, 460), (203, 720), (1127, 720), (711, 460)), (350, 940)),
]


def _dst(left_x: float, right_x: float) -> tuple:
    return ((left_x, 0), (left_x, 720), (right_x, 720), (right_x, 0))


@pytest.fixture()
def tuner(camera):
    return widgets.PerspectiveTuner({STRAIGHT: REPO / "test_images" / STRAIGHT}, calibration=camera)


@pytest.mark.parametrize("src, dst_x", PUBLISHED)
def test_published_points_are_taken_exactly_and_checked(tuner, src, dst_x):
    bird0 = tuner.birdseye.copy()
    tuner.set_points(src, _dst(*dst_x))
    pc = tuner.config.perspective
    assert pc.src_px == src and pc.dst_px == _dst(*dst_x)
    assert pc.size_px == (1280, 720) and pc.lane_width_m == 3.7
    assert not (tuner.birdseye == bird0).all()
    # the check reads these points: both lines found (the numbers are off for the synthetic camera)
    c = tuner.check
    assert all(math.isfinite(v) for v in (c.left_slope, c.right_slope, c.lane_width_m))
    assert c.left_fit is not None and c.right_fit is not None
    assert "not found" not in tuner.readout()
    # every per-corner control shows the exact points
    for corner, (x, y) in zip(("tl", "bl", "br", "tr"), src):
        assert (tuner.controls[f"src.{corner}.x"].value, tuner.controls[f"src.{corner}.y"].value) == (x, y)
    assert tuner.controls["dst.left_x"].value == dst_x[0]
    assert tuner.controls["dst.right_x"].value == dst_x[1]
    assert (tuner.controls["dst.top_y"].value, tuner.controls["dst.bottom_y"].value) == (0, 720)


def test_the_symmetric_sliders_show_the_least_squares_summary(tuner):
    tuner.set_points(PUBLISHED[0][0], _dst(450, 830))
    v = {k: tuner.controls[k].value for k in ("top_y", "top_width", "bottom_width", "centre_x", "dst_margin")}
    assert v == {"top_y": 450.0, "top_width": 95.0, "bottom_width": 899.0,
                 "centre_x": (595 + 690 + 216 + 1115) / 4, "dst_margin": 450.0}
    # points kept exactly: showing the summary changed nothing
    assert tuner.config.perspective.src_px == PUBLISHED[0][0]


def test_a_per_corner_control_moves_only_its_corner(tuner):
    before = tuner.config.perspective
    tuner.controls["src.tl.x"].value = 570.0
    pc = tuner.config.perspective
    assert pc.src_px == ((570.0, 470.0),) + before.src_px[1:]
    assert pc.dst_px == before.dst_px
    assert tuner.error == ""
    tuner.controls["src.br.y"].value = 710.0
    assert tuner.config.perspective.src_px == ((570.0, 470.0), before.src_px[1], (1087.0, 710.0),
                                               before.src_px[3])
    # the symmetric sliders follow as the summary
    assert tuner.controls["top_width"].value == pytest.approx(715.7 - 570.0)
    # (on the sliders' 0.1 px step)
    assert tuner.controls["centre_x"].value == pytest.approx((570.0 + 715.7 + 193.0 + 1087.0) / 4, abs=0.05)
    # a dst side moves that side only
    tuner.controls["dst.left_x"].value = 300.0
    assert tuner.config.perspective.dst_px == ((300.0, 0.0), (300.0, 720.0), (960.0, 720.0), (960.0, 0.0))
    tuner.controls["dst.top_y"].value = 20.0
    assert tuner.config.perspective.dst_px == ((300.0, 20.0), (300.0, 720.0), (960.0, 720.0), (960.0, 20.0))
    assert tuner.controls["dst_margin"].value == 310.0


def _src_controls(tuner) -> tuple:
    return tuple((tuner.controls[f"src.{c}.x"].value, tuner.controls[f"src.{c}.y"].value)
                 for c in ("tl", "bl", "br", "tr"))


def test_a_symmetric_slider_moves_the_corners_by_its_change_only(tuner):
    tuner.set_points(PUBLISHED[1][0], _dst(350, 940))  # off-centre: top centre 645, bottom 665
    set_ = tuner.config.perspective
    tuner.controls["top_y"].value = 470.0
    assert tuner.config.perspective.src_px == ((579, 470), (203, 720), (1127, 720), (711, 470))
    assert _src_controls(tuner) == tuner.config.perspective.src_px
    assert tuner.config.perspective.dst_px == _dst(350, 940)  # a src slider leaves the dst alone
    tuner.controls["top_width"].value = 142.0
    tuner.controls["bottom_width"].value = 904.0
    tuner.controls["centre_x"].value = 650.0
    assert tuner.config.perspective.src_px == ((569, 470), (208, 720), (1112, 720), (711, 470))
    assert tuner.error == ""
    # the other sliders keep their values; the per-corner controls follow
    assert {k: tuner.controls[k].value for k in ("top_y", "top_width", "bottom_width", "centre_x")} == {
        "top_y": 470.0, "top_width": 142.0, "bottom_width": 904.0, "centre_x": 650.0}
    assert _src_controls(tuner) == tuner.config.perspective.src_px
    # dst_margin moves both dst lines inwards by its change (the margins were 350 and 340)
    assert tuner.controls["dst_margin"].value == 345.0
    tuner.controls["dst_margin"].value = 320.0
    assert tuner.config.perspective.dst_px == _dst(325, 965)
    assert (tuner.controls["dst.left_x"].value, tuner.controls["dst.right_x"].value) == (325.0, 965.0)
    # every slider back: the points as they were set, exactly
    for key, value in (("centre_x", 655.0), ("top_y", 460.0), ("dst_margin", 345.0),
                       ("bottom_width", 924.0), ("top_width", 132.0)):
        tuner.controls[key].value = value
    assert tuner.config.perspective == set_


# off-centre, tilted point sets with their own lengths and car lines, as files hold them
LOADED = {
    "1280x720": PerspectiveConfig(((601.37, 452.81), (188.05, 717.3), (1121.6, 712.94), (704.19, 455.02)),
                                  ((333.3, 0.0), (318.7, 720.0), (947.1, 720.0), (951.9, 4.5)),
                                  (1280, 720), 3.6, 31.234, 651.25),
    "1640x590": PerspectiveConfig(((771.234, 361.5), (301.2, 588.0), (1452.875, 583.1), (902.6, 360.25)),
                                  ((430.0, 0.0), (430.0, 590.0), (1190.0, 590.0), (1190.0, 0.0)),
                                  (1640, 590), 3.75, 27.5),
}


@pytest.mark.parametrize("size", LOADED)
def test_sliders_moved_away_and_back_restore_the_loaded_points_exactly(size, camera, culane_folder,
                                                                       tmp_path):
    if size == "1280x720":
        tuner = widgets.PerspectiveTuner({STRAIGHT: REPO / "test_images" / STRAIGHT}, calibration=camera)
    else:
        tuner = widgets.PerspectiveTuner(culane_folder)
    loaded = LOADED[size]
    path = tmp_path / "loaded.json"
    save_config(PipelineConfig(perspective=loaded), path)
    tuner.load(path)
    assert tuner.config.perspective == loaded
    for key in ("top_y", "top_width", "bottom_width", "centre_x", "dst_margin"):
        shown = tuner.controls[key].value
        tuner.controls[key].value = shown + 7.3
        moved = tuner.config.perspective
        assert moved != loaded and tuner.error == "", key
        # only what the slider means changed: the other corners, or the other part, stay exact
        if key == "top_y":
            assert [p[0] for p in moved.src_px] == [p[0] for p in loaded.src_px]
            assert moved.src_px[1:3] == loaded.src_px[1:3]
        if key == "dst_margin":
            assert moved.src_px == loaded.src_px and moved.visible_length_m == loaded.visible_length_m
        else:
            assert moved.dst_px == loaded.dst_px
        tuner.controls[key].value = shown
        assert tuner.config.perspective == loaded, key
        assert _src_controls(tuner) == loaded.src_px
    # several sliders away at once, and back in another order
    values = {k: tuner.controls[k].value for k in ("top_y", "centre_x", "top_width", "dst_margin")}
    for key, value in values.items():
        tuner.controls[key].value = value - 4.2
    for key in reversed(values):
        tuner.controls[key].value = values[key]
    assert tuner.config.perspective == loaded
    assert load_config(tuner.save(tmp_path / "again.json")).perspective == loaded


# --------------------------------------------------------------------------- frames of any size

SLIDERS = ("top_y", "centre_x", "top_width", "bottom_width", "dst_margin")


def test_a_folder_of_culane_frames_opens_with_the_sliders_spanning_1640x590(culane_folder, tmp_path):
    tuner = widgets.PerspectiveTuner(culane_folder)  # no calibration: the frames as recorded
    assert list(tuner.images) == ["00000.jpg", "00030.jpg", "00060.jpg"]  # no .lines.txt, no README
    assert tuner.raw.shape == (590, 1640, 3)
    assert tuner.config.perspective == scaled(PerspectiveConfig(), (1640, 590))
    c = tuner.controls
    assert {k: c[k].max for k in SLIDERS} == {"top_y": 589, "centre_x": 1640, "top_width": 1640,
                                              "bottom_width": 3280, "dst_margin": 819}
    assert all(0 < c[k].value < c[k].max for k in SLIDERS)
    assert (c["src.tl.x"].min, c["src.tl.x"].max, c["dst.top_y"].min, c["dst.top_y"].max) == (
        -1640, 3280, -590, 1180)
    # the preview: three tiles of the frame's shape (400 px wide, 590/1640 of that high)
    sheet = cv2.imdecode(np.frombuffer(tuner.preview.value, np.uint8), cv2.IMREAD_COLOR)
    assert sheet.shape == (144, 1200, 3)
    assert tuner.birdseye.shape == (590, 1640, 3) and tuner.check.left_fit is not None
    tuner.controls["top_y"].value = 300.0
    tuner.picker.value = "00060.jpg"
    assert tuner.error == "" and tuner.image == "00060.jpg" and tuner.raw.shape == (590, 1640, 3)
    path = tuner.save(tmp_path / "culane.json")
    assert json.loads(path.read_text())["perspective"]["size_px"] == [1640, 590]
    assert load_config(path).perspective == tuner.config.perspective
    assert [y for _, y in tuner.config.perspective.src_px] == pytest.approx([300.0, 590.0, 590.0, 300.0],
                                                                            abs=0.05)


def test_a_nested_folder_of_clips_opens_labelled_by_path(tmp_path, road_frame):
    clips = tmp_path / "clips"  # laid out like TuSimple's: clips/<date>/<clip>/<n>.jpg
    for clip, size in (("0313-1/8260", (1280, 720)), ("0313-1/14900", (1280, 720)), ("0313-2/520", (512, 288))):
        (clips / clip).mkdir(parents=True)
        for n in (19, 20):
            io.write_image(clips / clip / f"{n}.jpg", road_frame(size, n))
    (clips / ".thumbs").mkdir()
    io.write_image(clips / ".thumbs" / "20.jpg", road_frame((64, 36)))  # hidden: left out
    (clips / "0313-1" / "label_data.json").write_text("{}")
    everything = widgets.PerspectiveTuner(clips)
    assert list(everything.images) == ["0313-1/8260/19.jpg", "0313-1/8260/20.jpg", "0313-1/14900/19.jpg",
                                       "0313-1/14900/20.jpg", "0313-2/520/19.jpg", "0313-2/520/20.jpg"]
    last = widgets.folder_choices(clips, "*/*/20.jpg")
    assert list(last) == ["0313-1/8260/20.jpg", "0313-1/14900/20.jpg", "0313-2/520/20.jpg"]
    tuner = widgets.PerspectiveTuner(last)
    assert tuner.raw.shape == (720, 1280, 3) and tuner.config.perspective == PerspectiveConfig()
    # a frame of another size: the points are scaled to it and the sliders span it
    tuner.picker.value = "0313-2/520/20.jpg"
    assert tuner.raw.shape == (288, 512, 3) and tuner.config.perspective.size_px == (512, 288)
    assert (tuner.controls["top_y"].max, tuner.controls["centre_x"].max) == (287, 512)
    assert tuner.error == ""
    with pytest.raises(InputError, match=r"holds no images or videos matching '\*/\*/21\.jpg'"):
        widgets.folder_choices(clips, "*/*/21.jpg")


def test_four_clicks_place_the_four_corners(tuner):
    assert isinstance(tuner._events, ipyevents.Event)
    assert tuner._events.source is tuner.preview and tuner._events.watched_events == ["click"]
    before = tuner.config
    tuner.click(181, 144)  # not armed: ignored
    assert tuner.config == before
    tuner.place.value = True
    assert "top left corner" in tuner.readout()
    # preview tiles are 400x225 for a 1280x720 frame: 3.2 frame px per preview px
    tuner.click(181, 144)
    tuner.click(650, 100)  # on the bird's-eye tile: ignored
    tuner.click(63, 224)
    tuner.click(352, 224)
    assert tuner.config == before and "top right corner" in tuner.readout()
    tuner.click(222, 144)
    assert tuner.config.perspective.src_px == ((579.2, 460.8), (201.6, 716.8), (1126.4, 716.8),
                                               (710.4, 460.8))
    assert tuner.config.perspective.dst_px == before.perspective.dst_px
    assert tuner.place.value is False and "placing" not in tuner.readout()
    assert tuner.controls["src.tr.x"].value == 710.4


def test_clicks_that_make_no_trapezoid_are_refused(tuner):
    before = tuner.config
    tuner.place.value = True
    for x, y in ((50, 100), (150, 200), (250, 200), (350, 100)):  # top wider than the bottom
        tuner.click(x, y)
    assert tuner.config == before
    assert "narrower than the bottom" in tuner.error and tuner.place.value is False


def test_click_to_frame_maps_the_first_tile_only():
    tile, frame = (400, 225), (1280, 720)
    assert click_to_frame({"dataX": 100, "dataY": 50}, tile, 3, frame) == (320.0, 160.0)
    # without dataX/dataY: the position in the displayed box, scaled to the sheet (3 tiles wide)
    event = {"relativeX": 50, "relativeY": 25, "boundingRectWidth": 600, "boundingRectHeight": 112.5}
    assert click_to_frame(event, tile, 3, frame) == (320.0, 160.0)
    assert click_to_frame({"dataX": 400, "dataY": 10}, tile, 3, frame) is None
    assert click_to_frame({"type": "click"}, tile, 3, frame) is None


def test_save_and_load_round_trip_the_asymmetric_points(tuner, camera, tmp_path):
    src, dst_x = PUBLISHED[0]
    tuner.set_points(src, _dst(*dst_x))
    path = tuner.save(tmp_path / "config.json")
    fresh = widgets.PerspectiveTuner({STRAIGHT: REPO / "test_images" / STRAIGHT}, calibration=camera)
    assert fresh.config.perspective == PerspectiveConfig()
    fresh.load(path)
    assert fresh.config.perspective == tuner.config.perspective
    assert fresh.config.perspective.src_px == src
    assert fresh.controls["src.tr.x"].value == 690.0 and fresh.controls["dst.right_x"].value == 830.0
    assert fresh.check == tuner.check


def test_fast_birdseye_takes_the_lens_and_the_perspective():
    cal = Calibration(np.array([[1000.0, 0, 640.0], [0, 1000.0, 360.0], [0, 0, 1]]),
                      np.array([-0.25, 0.05, 0.001, -0.0005, 0.0]), (1280, 720))
    rng = np.random.default_rng(4)
    raw = cv2.resize(rng.integers(0, 255, (90, 160, 3), dtype=np.uint8), (1280, 720),
                     interpolation=cv2.INTER_CUBIC)
    lens = Lens(cal)
    persp = Perspective()
    fast = FastBirdseye(lens)
    assert fast.pad == (320, 180)
    maps = (lens.inverse + persp).remap_maps((1280, 720))
    exact = cv2.remap(raw, maps[0], maps[1], cv2.INTER_LINEAR)
    diff = np.abs(fast.birdseye(raw, persp).astype(int) - exact)[:680]  # above the raw frame's edge
    assert diff.max() <= 2
