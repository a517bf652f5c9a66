"""The tuners driven without a browser: set a control's ``.value``, check the config and the preview.

Setting ``.value`` in Python runs the same ``observe`` callback a slider drag in JupyterLab runs.
"""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import cv2
import ipywidgets
import numpy as np
import pytest

from lanelib import draw, io, perspective, thresholds, widgets
from lanelib.config import PipelineConfig, load_config, save_config, to_dict
from lanelib.errors import CalibrationError, ConfigError, InputError
from lanelib.hough import HoughConfig
from lanelib.params import SearchConfig
from lanelib.perspective import PerspectiveConfig, implied_focal_px, road_length_m, trapezoid_src
from lanelib.pipeline import LanePipeline

REPO = Path(__file__).resolve().parents[1]

STRAIGHT = "straight_1.jpg"
CURVED = "curve_left_600m.jpg"


@pytest.fixture(scope="module")
def road():
    """Two bundled 1280x720 road images, a straight one first, as the picker's {label: path}."""
    folder = REPO / "test_images"
    return {STRAIGHT: folder / STRAIGHT, CURVED: folder / CURVED}



def _decode(jpeg: bytes) -> np.ndarray:
    return cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)


def _tile(sheet: np.ndarray, index: int, columns: int, tile_w: int) -> np.ndarray:
    th = round(tile_w * 720 / 1280)
    r, c = divmod(index, columns)
    return sheet[r * th:(r + 1) * th, c * tile_w:(c + 1) * tile_w]


# --------------------------------------------------------------------------- thresholds

def test_raising_the_white_low_bound_shrinks_the_white_mask_only(road):
    t = widgets.ThresholdTuner(road)
    names = thresholds.mask_names(t.config.thresholds)
    before = {n: t.mask(n) for n in names}
    sheet0, bytes0 = t.preview_sheet(), t.preview.value
    white0 = cv2.countNonZero(before["white"])
    assert white0 > 1000  # the right line is white

    t.controls["white.range1"].value = (215, 255)  # the L channel of HLS

    assert t.config.thresholds.white.low == (0, 215, 0)
    assert t.config.thresholds.white.high == (179, 255, 255)
    white1 = cv2.countNonZero(t.mask("white"))
    assert 0 < white1 < white0
    expected = thresholds.mask(t.birdseye, t.config.thresholds.white)
    assert np.array_equal(t.mask("white"), expected)
    # only the white mask was recomputed: the others are the very same arrays
    for n in names:
        if n != "white" and before[n] is not None:
            assert t.mask(n) is before[n], n
    assert t.config.thresholds.yellow == PipelineConfig().thresholds.yellow
    # the preview changed where the white tile is, not where the yellow tile is
    assert t.preview.value != bytes0
    sheet1 = t.preview_sheet()
    i_white, i_yellow = 1 + names.index("white"), 1 + names.index("yellow")
    assert not np.array_equal(_tile(sheet1, i_white, 4, 320), _tile(sheet0, i_white, 4, 320))
    assert np.array_equal(_tile(sheet1, i_yellow, 4, 320), _tile(sheet0, i_yellow, 4, 320))
    assert _decode(t.preview.value).shape == sheet1.shape


def test_disabling_a_mask_drops_it_from_the_combination(road):
    base = PipelineConfig()
    rule = "yellow | lab_b | (white & line_tophat)"  # lab_b and yellow both hold the yellow line
    t = widgets.ThresholdTuner(road, config=replace(base, thresholds=replace(base.thresholds, rule=rule)),
                               image=CURVED)
    cfg = t.config.thresholds
    assert cfg.rule == rule
    combined0 = t.combined()
    yellow_only = cv2.bitwise_and(t.mask("yellow"), cv2.bitwise_not(t.mask("lab_b")))
    t.controls["lab_b.enabled"].value = False
    assert t.config.thresholds.lab_b.enabled is False
    assert t.mask("lab_b") is None and t.render()["lab_b"] is None
    combined1 = t.combined()
    # lab_b's pixels that no other term of the rule holds are gone, nothing was added
    assert cv2.countNonZero(cv2.bitwise_and(combined1, cv2.bitwise_not(combined0))) == 0
    assert cv2.countNonZero(combined1) < cv2.countNonZero(combined0)
    expected = thresholds.combine(t.birdseye, replace(cfg, lab_b=replace(cfg.lab_b, enabled=False)))
    assert np.array_equal(combined1, expected)
    # with yellow off as well, the left (yellow) line leaves the combination
    t.controls["yellow.enabled"].value = False
    combined2 = t.combined()
    assert cv2.countNonZero(cv2.bitwise_and(combined2, yellow_only)) < cv2.countNonZero(
        cv2.bitwise_and(combined1, yellow_only))
    assert t.counts()["combined"] == cv2.countNonZero(combined2)
    assert "yellow" not in t.counts()


def test_changing_a_colour_space_updates_the_channel_choices_and_the_hue_range(road):
    t = widgets.ThresholdTuner(road)
    t.controls["s_channel.space"].value = "lab"
    assert t.controls["s_channel.channel"].options == ("l", "a", "b")
    assert t.config.thresholds.s_channel.space == "lab"
    assert t.config.thresholds.s_channel.channel == "l"  # "s" is not a Lab channel
    t.controls["s_channel.space"].value = "hsv"
    t.controls["s_channel.channel"].value = "h"
    assert t.controls["s_channel.range"].max == 179
    assert t.config.thresholds.s_channel == thresholds.ChannelMask("hsv", "h", 170, 179)
    assert np.array_equal(t.mask("s_channel"),
                          thresholds.mask(t.birdseye, t.config.thresholds.s_channel))
    t.controls["s_channel.channel"].value = "v"  # same space, another channel: back to 0-255
    assert t.controls["s_channel.range"].max == 255
    assert t.controls["s_channel.range"].description == "v"
    t.controls["s_channel.range"].value = (200, 255)
    assert t.config.thresholds.s_channel == thresholds.ChannelMask("hsv", "v", 200, 255)
    t.controls["yellow.space"].value = "lab"
    assert [t.controls[f"yellow.range{i}"].description for i in range(3)] == ["l", "a", "b"]
    assert t.controls["yellow.range0"].max == 255


def test_sobel_kernel_and_rule_controls(road):
    t = widgets.ThresholdTuner(road)
    t.controls["sobel_x.kernel_px"].value = 5
    assert t.config.thresholds.sobel_x.kernel_px == 5
    assert np.array_equal(t.mask("sobel_x"), thresholds.mask(t.birdseye, t.config.thresholds.sobel_x))
    t.controls["rule"].value = "yellow | white"
    assert t.config.thresholds.rule == "yellow | white"
    assert np.array_equal(t.combined(), cv2.bitwise_or(t.mask("yellow"), t.mask("white")))


def test_a_bad_rule_is_refused_and_said_why(road):
    t = widgets.ThresholdTuner(road)
    before, preview = t.config, t.preview.value
    t.controls["rule"].value = "yellow | nope"
    assert t.config == before
    assert t.preview.value == preview
    assert "unknown mask 'nope'" in t.error
    assert "unknown mask" in t.message.value
    t.controls["rule"].value = "yellow"
    assert t.error == "" and t.config.thresholds.rule == "yellow"


def test_save_and_load_round_trip(road, tmp_path):
    t = widgets.ThresholdTuner(road)
    t.controls["white.range1"].value = (215, 255)
    t.controls["sobel_x.range"].value = (35.0, 200.0)
    t.controls["lab_b.enabled"].value = False
    t.controls["line_tophat.width_px"].value = 41
    path = t.save(tmp_path / "tuned.json")
    assert load_config(path) == t.config
    assert json.loads(path.read_text())["thresholds"]["white"]["low"] == [0, 215, 0]

    fresh = widgets.ThresholdTuner(road)
    assert fresh.config == PipelineConfig()
    assert fresh.load(path) == t.config
    assert fresh.config == t.config
    assert fresh.controls["white.range1"].value == (215, 255)
    assert fresh.controls["lab_b.enabled"].value is False
    assert fresh.controls["line_tophat.width_px"].value == 41
    assert fresh.preview.value == t.preview.value
    # the perspective and fit tuners read the same file, and the fit tuner's search part
    p = widgets.PerspectiveTuner(road)
    p.load(path)
    assert p.config == t.config
    f = widgets.FitTuner(road)
    f.load(path)
    f.controls["n_windows"].value = 7
    f.save(path)
    g = widgets.FitTuner(road)
    g.load(path)
    assert g.config == f.config and g.config.thresholds == t.config.thresholds
    assert g.controls["n_windows"].value == 7 and len(g.windows.windows) == 2 * 7
    assert np.array_equal(g.binary, f.binary)


def test_load_rebuilds_the_birdseye_view_when_the_perspective_changes(road, tmp_path):
    t = widgets.ThresholdTuner(road)
    bird0 = t.birdseye.copy()
    pc = PerspectiveConfig(dst_px=((200.0, 0.0), (200.0, 720.0), (1080.0, 720.0), (1080.0, 0.0)))
    path = tmp_path / "wide.json"
    path.write_text(json.dumps({"perspective": to_dict(pc)}))
    t.load(path)
    assert t.config.perspective == pc
    assert not np.array_equal(t.birdseye, bird0)
    assert np.array_equal(t.birdseye, LanePipeline(t.config).birdseye(io.read_image(road[STRAIGHT])))


def test_threshold_tuner_opens_a_folder_of_culane_frames(culane_folder):
    t = widgets.ThresholdTuner(str(culane_folder))  # 1640x590 frames, their .lines.txt beside them
    assert list(t.images) == ["00000.jpg", "00030.jpg", "00060.jpg"]
    raw = io.read_image(culane_folder / "00000.jpg")
    # the bird's-eye view and every mask at the frame's size, as the pipeline makes them for it
    assert np.array_equal(t.birdseye, LanePipeline(t.config, size=(1640, 590)).birdseye(raw))
    assert {v.shape[:2] for v in t.render().values() if v is not None} == {(590, 1640)}
    assert t.counts()["combined"] > 0
    rows = -(-len(t.render()) // 4)  # four tiles a row, 320 px wide and 590/1640 of that high
    assert _decode(t.preview.value).shape[:2] == (rows * round(320 * 590 / 1640), 4 * 320)
    bytes0 = t.preview.value
    t.controls["white.range1"].value = (250, 255)
    assert t.preview.value != bytes0 and t.error == ""
    t.picker.value = "00060.jpg"
    assert t.image == "00060.jpg" and t.error == "" and t.birdseye.shape == (590, 1640, 3)


# --------------------------------------------------------------------------- perspective

def test_straight_line_check_with_default_points_on_a_straight_road(road, camera):
    t = widgets.PerspectiveTuner(road, calibration=camera, image=STRAIGHT)
    c = t.check
    assert abs(c.left_slope) < 2.0 and abs(c.right_slope) < 2.0  # px per 100 px
    assert c.lane_width_m == pytest.approx(3.7, abs=0.15)
    assert "straight-line check: left" in t.readout()
    # a trapezoid whose top is too narrow stretches the far road: the lines spread apart
    # towards the top (x falls upwards on the left, rises on the right), and the check shows it
    t.controls["top_width"].value = 130.0
    assert t.check.left_slope > 3.0 and t.check.right_slope < -3.0
    assert t.check.lane_width_m == pytest.approx(3.7, abs=0.3)  # the bottom row stays put


def test_moving_the_trapezoid_changes_the_src_points_and_the_birdseye_preview(road):
    t = widgets.PerspectiveTuner(road)
    default = PerspectiveConfig()
    focal = implied_focal_px(default)
    bytes0, bird0 = t.preview.value, t.birdseye.copy()
    t.controls["top_y"].value = 480.0
    assert t.config.perspective.src_px == trapezoid_src(480.0, 720.0, 151.4, 894.0, 640.0)
    assert t.config.perspective.dst_px == default.dst_px
    assert t.preview.value != bytes0
    assert not np.array_equal(t.birdseye, bird0)
    # the visible road length follows the trapezoid's widths for the same camera
    t.controls["top_width"].value = 140.0
    src = t.config.perspective.src_px
    assert src[0] == (570.0, 480.0) and src[3] == (710.0, 480.0)
    assert t.config.perspective.visible_length_m == pytest.approx(
        road_length_m(src, 3.7, focal), abs=1e-3)
    assert t.config.perspective.visible_length_m > default.visible_length_m
    assert t.config.perspective.lane_width_m == 3.7
    t.controls["centre_x"].value = 650.0
    assert t.config.perspective.src_px[1] == (203.0, 720.0)


def test_the_perspective_tuner_sees_what_the_pipeline_sees(road, camera):
    t = widgets.PerspectiveTuner(road, calibration=camera, image=CURVED)
    raw = io.read_image(road[CURVED])
    for top_y in (470.0, 490.0):
        t.controls["top_y"].value = top_y
        expected = LanePipeline(t.config, camera).birdseye(raw)
        diff = cv2.absdiff(t.birdseye, expected)
        assert diff.max() <= 3, top_y
        assert diff.mean() < 0.1, top_y


def test_the_dst_margin_changes_the_scale_not_the_lane_width(road, camera):
    t = widgets.PerspectiveTuner(road, calibration=camera, image=STRAIGHT)
    width0 = t.check.lane_width_m
    t.controls["dst_margin"].value = 400.0
    pc = t.config.perspective
    assert pc.dst_px == ((400.0, 0.0), (400.0, 720.0), (880.0, 720.0), (880.0, 0.0))
    assert pc.xm_per_px == pytest.approx(3.7 / 480)
    assert t.check.lane_width_m == pytest.approx(width0, abs=0.05)


def test_an_impossible_trapezoid_is_refused(road):
    t = widgets.PerspectiveTuner(road)
    before = t.config
    t.controls["top_width"].value = 1000.0  # wider than the bottom
    assert t.config == before
    assert "narrower than the bottom" in t.error
    t.controls["top_width"].value = 160.0
    assert t.error == "" and t.config.perspective.src_px[3][0] == 720.0


# --------------------------------------------------------------------------- fits

def test_fit_controls_change_the_windows_and_the_preview(road):
    t = widgets.FitTuner(road, image=CURVED)
    assert len(t.windows.windows) == 2 * 9
    bytes0 = t.preview.value
    t.controls["n_windows"].value = 12
    assert t.config.search.n_windows == 12
    assert len(t.windows.windows) == 2 * 12
    assert t.preview.value != bytes0
    t.controls["margin_px"].value = 50
    assert t.config.search.margin_px == 50
    assert {w.x_high - w.x_low for w in t.windows.windows} == {100}  # no growing margin (default)
    t.controls["grow_margin_px"].value = 15
    assert {w.x_high - w.x_low for w in t.windows.windows} > {100}  # wider over a gap in the dashes
    t.controls["grow_margin_px"].value = 0  # no growing margin: every window is 2 x margin_px wide
    assert {w.x_high - w.x_low for w in t.windows.windows} == {100}
    t.controls["minpix"].value = 5000  # more line pixels than any window holds on this image
    # with minpix that high no window recentres: each side's windows stay over its base
    for side, base in zip(("left", "right"), t.windows.bases_px):
        assert {w.x_low for w in t.windows.windows if w.side == side} == {int(base - 50)}
    t.controls["prior_margin_px"].value = 30
    assert t.config.search == replace(SearchConfig(), n_windows=12, margin_px=50, minpix=5000,
                                      prior_margin_px=30, grow_margin_px=0)


def test_fit_tuner_fits_are_what_the_pipeline_finds(road):
    t = widgets.FitTuner(road, image=CURVED)
    t.controls["margin_px"].value = 100
    result = LanePipeline(t.config).detect(io.read_image(road[CURVED]))
    assert t.windows.left.coeffs_px == result.left.coeffs_px
    assert t.windows.right.coeffs_px == result.right.coeffs_px
    assert t.measurement == result.measurement
    assert "radius" in t.readout()


def test_fit_tuner_switches_are_the_search_configs_tricks(road):
    t = widgets.FitTuner(road, image=CURVED)
    peaks = t.windows.base_confidence
    assert all(c is not None and c > 1 for c in peaks)  # two clear lines: peaks stand out
    assert f"left {peaks[0]:.1f}, right {peaks[1]:.1f}" in t.readout()
    t.controls["trim_outliers_pct"].value = 90.0
    t.controls["centre_first"].value = True
    t.controls["window_histogram"].value = True
    t.controls["grow_margin_px"].value = 20
    want = replace(SearchConfig(), trim_outliers_pct=90.0, centre_first=True, window_histogram=True,
                   grow_margin_px=20)
    assert t.config.search == want
    result = LanePipeline(t.config).detect(io.read_image(road[CURVED]))
    assert t.windows.left.coeffs_px == result.left.coeffs_px  # the preview is the pipeline's search
    assert t.windows.right.coeffs_px == result.right.coeffs_px
    # trimming keeps 90 % of each line's pixels for the fit
    plain = LanePipeline(PipelineConfig()).detect(io.read_image(road[CURVED]))
    assert 0 < t.windows.left.n_pixels < plain.search.left.n_pixels


def test_threshold_tuner_clahe_and_per_mask_opening_match_the_pipeline(road):
    t = widgets.ThresholdTuner(road, image=STRAIGHT)
    view0 = t.mask_view
    t.controls["clahe"].value = True
    t.controls["clahe_clip_limit"].value = 3.0
    t.controls["clahe_tile_px"].value = 96
    t.controls["yellow.open_px"].value = 5
    t.controls["lab_b.open_px"].value = 3
    cfg = t.config.thresholds
    assert (cfg.clahe, cfg.clahe_clip_limit, cfg.clahe_tile_px) == (True, 3.0, 96)
    assert (cfg.yellow.open_px, cfg.lab_b.open_px, cfg.white.open_px) == (5, 3, 0)
    assert not np.array_equal(t.mask_view, view0)  # the masks see the equalised view
    assert "bird's-eye (CLAHE)" in t.render() and "CLAHE clip 3" in t.readout()
    pipe = LanePipeline(t.config)
    bird = pipe.birdseye(io.read_image(road[STRAIGHT]))
    np.testing.assert_array_equal(t.combined(), pipe.binary(bird))
    np.testing.assert_array_equal(t.mask("yellow"), thresholds.masks(bird, cfg, ("yellow",))["yellow"])
    t.controls["clahe"].value = False  # back off: the plain view again
    np.testing.assert_array_equal(t.mask_view, view0)


def test_threshold_tuner_stacked_view_puts_the_picked_masks_in_red_green_blue(road):
    t = widgets.ThresholdTuner(road, image=STRAIGHT)
    assert t.stacked_names() == thresholds.rule_masks(t.config.thresholds)[:3]
    t.controls["stack.r"].value = "yellow"
    t.controls["stack.g"].value = "(none)"
    t.controls["stack.b"].value = "sobel_y"  # off: its channel stays black
    view = t.stacked()
    np.testing.assert_array_equal(view[..., 0], t.mask("yellow"))
    assert not view[..., 1:].any()
    assert "stacked yellow - sobel_y" in t.render()
    config = t.config
    t.controls["stack.g"].value = "white"  # a view choice, not part of the config
    assert t.config == config
    np.testing.assert_array_equal(t.stacked()[..., 1], t.mask("white"))


# --------------------------------------------------------------------------- shared machinery

def test_picking_an_image_updates_the_preview(road):
    t = widgets.FitTuner(road)
    bytes0, binary0 = t.preview.value, t.binary.copy()
    t.picker.value = CURVED
    assert t.image == CURVED
    assert t.preview.value != bytes0
    assert not np.array_equal(t.binary, binary0)


def test_udacity_images_use_the_udacity_camera(road, udacity_advanced):
    images = dict(road)
    images["udacity/straight_lines1.jpg"] = udacity_advanced / "test_images" / "straight_lines1.jpg"
    t = widgets.PerspectiveTuner(images, image="udacity/straight_lines1.jpg")
    cal = t.calibration_for("udacity/straight_lines1.jpg")
    assert "calibration2.jpg" in cal.used  # the Udacity boards, calibrated on first pick
    assert t.calibration_for(STRAIGHT) is None  # no calibration was given for the bundled images
    assert abs(t.check.left_slope) < 2.0 and abs(t.check.right_slope) < 2.0
    assert t.check.lane_width_m == pytest.approx(3.7, abs=0.15)


def test_the_text_output_is_short_and_stable(road):
    t = widgets.PerspectiveTuner(road)
    bundle = t._repr_mimebundle_()
    assert bundle["text/plain"] == f"PerspectiveTuner(image='{STRAIGHT}')"
    assert "model_id" in bundle["application/vnd.jupyter.widget-view+json"]
    assert t.widget is t.widget
    assert t.preview in t.widget.children
    assert "lanelib-preview" in t.preview._dom_classes
    assert "lanelib-slider-top_y" in t.controls["top_y"]._dom_classes


def test_css_classes_mark_sliders_and_other_controls(road):
    t = widgets.ThresholdTuner(road)
    assert "lanelib-slider-white-range1" in t.controls["white.range1"]._dom_classes
    assert "lanelib-slider-sobel_x-range" in t.controls["sobel_x.range"]._dom_classes
    assert "lanelib-control-white-enabled" in t.controls["white.enabled"]._dom_classes
    assert not any(c.startswith("lanelib-slider") for c in t.controls["white.space"]._dom_classes)


def test_bad_images_raise_clear_errors(road, tmp_path):
    with pytest.raises(InputError, match="not among the picker's images"):
        widgets.ThresholdTuner(road, image="nope.jpg")
    with pytest.raises(InputError, match="no images"):
        widgets.ThresholdTuner({})


def test_a_folder_that_cannot_be_shown_says_which_and_what_to_do(culane_folder, tmp_path, camera):
    with pytest.raises(InputError, match=f"{tmp_path / 'nope'}: no such folder; pass a folder of frames"):
        widgets.ThresholdTuner(tmp_path / "nope")
    with pytest.raises(InputError, match="00000.lines.txt: not a folder"):
        widgets.PerspectiveTuner(culane_folder / "00000.lines.txt")
    labels = tmp_path / "labels"
    labels.mkdir()
    (labels / "00000.lines.txt").write_text("1 2 3 4\n")
    with pytest.raises(InputError, match=f"{labels}: holds no images or videos"):
        widgets.ThresholdTuner(labels)
    with pytest.raises(InputError, match=r"VideoTuner: 00000.jpg \(00000.jpg\), 00030.jpg .* not a video"):
        widgets.VideoTuner(culane_folder)
    # the bundled camera's calibration cannot take 1640x590 frames: which frame, and the way out
    with pytest.raises(CalibrationError, match=r"00000.jpg: frame is 1640x590 .*calibration=None"):
        widgets.PerspectiveTuner(culane_folder, calibration=camera)
    # an unreadable frame picked: the frame shown stays, picked again, and the readout says why
    (culane_folder / "00045.jpg").write_bytes(b"not a jpeg")
    for kind in (widgets.ThresholdTuner, widgets.PerspectiveTuner):
        t = kind(culane_folder, image="00030.jpg")
        config, bytes0 = t.config, t.preview.value
        t.picker.value = "00045.jpg"
        assert t.image == "00030.jpg" and t.config == config and t.preview.value == bytes0
        assert "00045.jpg: not a readable image" in t.error and "color:#c00" in t.message.value
        t.picker.value = "00060.jpg"
        assert t.error == "" and "color:#c00" not in t.message.value
    with pytest.raises(InputError, match=r"'01234.jpg' is not among .*00045.jpg, 00060.jpg\); pass one"):
        widgets.ThresholdTuner(culane_folder, image="01234.jpg")


def test_image_choices_lists_bundled_then_udacity(tmp_path):
    root = tmp_path / "repo"
    (root / "test_images").mkdir(parents=True)
    (root / "notebooks").mkdir()
    data = tmp_path / "data"
    (data / "udacity-advanced" / "test_images").mkdir(parents=True)
    img = np.zeros((8, 8, 3), np.uint8)
    io.write_image(root / "test_images" / "b.jpg", img)
    io.write_image(root / "test_images" / "a.jpg", img)
    io.write_image(data / "udacity-advanced" / "test_images" / "u.jpg", img)
    choices = widgets.image_choices(root, data)
    assert list(choices) == ["a.jpg", "b.jpg", "udacity/u.jpg"]
    assert choices["udacity/u.jpg"] == data / "udacity-advanced" / "test_images" / "u.jpg"
    assert list(widgets.image_choices(root, tmp_path / "nothing")) == ["a.jpg", "b.jpg"]


def test_the_preview_grid_and_the_check_are_still_importable_from_widgets():
    # they live in lanelib.draw and lanelib.perspective now
    assert widgets.sheet is draw.sheet and widgets.shrink is draw.shrink
    assert widgets.straight_line_check is perspective.straight_line_check
    assert widgets.StraightLineCheck is perspective.StraightLineCheck
    assert {"ThresholdTuner", "PerspectiveTuner", "FitTuner", "HoughTuner", "Tuner", "image_choices",
            "hough_image_choices"} <= set(widgets.__all__)


# --------------------------------------------------------------------------- save and load: the parts

def test_each_tuner_saves_its_own_part_and_shows_what_its_views_use():
    assert widgets.ThresholdTuner.parts == ("thresholds",)
    assert widgets.PerspectiveTuner.parts == ("perspective",)
    assert widgets.FitTuner.parts == ("search",)
    assert widgets.HoughTuner.parts == ("hough",)
    for cls in (widgets.ThresholdTuner, widgets.PerspectiveTuner, widgets.FitTuner, widgets.HoughTuner):
        assert set(cls.parts) <= set(cls.shows), cls.__name__
    with pytest.raises(TypeError, match="not parts of PipelineConfig"):
        type("Bad", (widgets.Tuner,), {"parts": ("nope",), "shows": ("nope",)})


def test_save_merges_the_tuners_parts_into_one_file(road, tmp_path):
    path = tmp_path / "tuned.json"
    # a file that already holds a tuned Hough part (notebook 00)
    hough = HoughConfig(canny_low=30, canny_high=120)
    save_config(replace(PipelineConfig(), hough=hough), path)
    # notebook 04: the perspective
    p = widgets.PerspectiveTuner(road)
    p.controls["top_y"].value = 480.0
    assert p.save(path) == path
    # notebook 03, with the default perspective in its own config: the thresholds
    t = widgets.ThresholdTuner(road)
    t.controls["white.range1"].value = (215, 255)
    assert t.config.perspective == PerspectiveConfig()
    t.save(path)

    saved = load_config(path)
    assert saved.perspective == p.config.perspective != PerspectiveConfig()
    assert saved.thresholds == t.config.thresholds != PipelineConfig().thresholds
    assert saved.hough == hough
    assert saved.search == SearchConfig()

    # a fresh tuner restores both; its bird's-eye view is the tuned perspective's
    fresh = widgets.ThresholdTuner(road)
    fresh.load(path)
    assert fresh.config.perspective == p.config.perspective
    assert fresh.config.thresholds == t.config.thresholds
    assert fresh.controls["white.range1"].value == (215, 255)
    assert np.array_equal(fresh.birdseye,
                          LanePipeline(fresh.config).birdseye(io.read_image(road[STRAIGHT])))
    fit = widgets.FitTuner(road)
    fit.load(path)
    assert (fit.config.perspective, fit.config.thresholds) == (saved.perspective, saved.thresholds)
    # the fit tuner's search joins them, the others stay
    fit.controls["n_windows"].value = 7
    fit.save(path)
    again = load_config(path)
    assert again == replace(saved, search=replace(SearchConfig(), n_windows=7))


def test_save_keeps_only_what_the_file_holds(road, tmp_path):
    path = tmp_path / "partial.json"
    path.write_text(json.dumps({"perspective": to_dict(PerspectiveConfig(lane_width_m=3.5)),
                                "tracking": {"min_width_m": 2.9}}))  # an older file's key, kept
    t = widgets.ThresholdTuner(road)
    t.controls["rule"].value = "yellow | white"
    t.save(path)
    held = json.loads(path.read_text())
    assert set(held) == {"perspective", "tracking", "thresholds"}
    assert held["tracking"] == {"min_width_m": 2.9}
    assert held["thresholds"]["rule"] == "yellow | white"
    assert load_config(path).perspective.lane_width_m == 3.5
    # a new file gets the whole config: the one the CLI's --config reads
    whole = t.save(tmp_path / "new.json")
    assert set(json.loads(whole.read_text())) == set(to_dict(PipelineConfig()))
    assert load_config(whole) == t.config


def test_save_refuses_to_merge_into_a_file_that_is_not_a_config(road, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"thresholds": {"rule": 3}}')
    t = widgets.ThresholdTuner(road)
    with pytest.raises(ConfigError, match="thresholds.rule"):
        t.save(path)
    assert path.read_text() == '{"thresholds": {"rule": 3}}'


def test_load_reads_what_the_file_holds_of_the_parts_shown_and_keeps_the_rest(road, tmp_path):
    t = widgets.ThresholdTuner(road)
    t.controls["white.range1"].value = (215, 255)
    mine = replace(t.config, hough=HoughConfig(canny_low=10))
    t.set_config(mine)
    path = tmp_path / "rule_only.json"
    path.write_text(json.dumps({"thresholds": {"rule": "yellow | white"},
                                "hough": {"canny_low": 99}, "search": {"n_windows": 5}}))
    loaded = t.load(path)
    assert loaded == t.config
    assert t.config.thresholds.rule == "yellow | white"                   # what the file holds
    assert t.config.thresholds.white.low == (0, 215, 0)                   # the rest of the part
    assert t.controls["white.range1"].value == (215, 255)
    assert t.config.hough == mine.hough and t.config.search == mine.search  # parts not shown
    assert t.controls["rule"].value == "yellow | white"
    # a fit tuner shows the search: it takes that
    f = widgets.FitTuner(road)
    f.load(path)
    assert f.config.search.n_windows == 5 and f.controls["n_windows"].value == 5
    assert len(f.windows.windows) == 2 * 5
    assert f.config.hough == HoughConfig()


def test_config_for_returns_the_new_config_and_changes_nothing(road):
    moves = [(widgets.ThresholdTuner, "white.range1", (215, 255)),
             (widgets.ThresholdTuner, "s_channel.space", "lab"),
             (widgets.PerspectiveTuner, "top_y", 480.0),
             (widgets.FitTuner, "n_windows", 12)]
    for cls, key, value in moves:
        t = cls(road)
        config, preview, views = t.config, t.preview.value, dict(vars(t))
        options = {k: getattr(c, "options", None) for k, c in t.controls.items()}
        shown = t.controls[key].value
        new = t.config_for(key, value)
        assert new != config, key
        assert t.config is config and t.preview.value == preview, key
        assert all(vars(t)[k] is v for k, v in views.items()), key  # no view was recomputed
        assert {k: getattr(c, "options", None) for k, c in t.controls.items()} == options, key
        assert t.controls[key].value == shown, key
        t.controls[key].value = value  # the user moves the control: its observer takes the value
        assert t.config == new and t.preview.value != preview, key
    with pytest.raises(InputError, match="'no_such' is not a control of FitTuner"):
        t.config_for("no_such", 1)


# --------------------------------------------------------------------------- the base class

class _Probe(widgets.Tuner):
    """A minimal tuner: one slider that sets a brightness threshold (``search.minpix``, for want of
    a field of its own); it notes each hook call and each attribute asked for before it exists."""

    parts = ("search",)
    shows = ("search",)

    def __init__(self, *args, **kwargs):
        self.__dict__["calls"] = []
        self.__dict__["missing"] = []
        super().__init__(*args, **kwargs)

    def __getattr__(self, name):  # only for attributes that do not exist (yet)
        self.__dict__["missing"].append(name)
        raise AttributeError(name)

    def _build(self):
        self.calls.append("build")
        return [self._control("level", ipywidgets.IntSlider(value=self.config.search.minpix,
                                                             min=0, max=255))]

    def _prepare(self, raw, calibration):
        self.calls.append("prepare")
        self.gray = cv2.cvtColor(raw, cv2.COLOR_RGB2GRAY)

    def _update(self, key):
        self.calls.append(("update", key))
        self.bright = np.where(self.gray > self.config.search.minpix, 255, 0).astype(np.uint8)

    def _apply(self, key):
        self.calls.append(("apply", key))
        return replace(self.config, search=replace(self.config.search,
                                                   minpix=int(self.controls["level"].value)))

    def _sync(self):
        self.controls["level"].value = self.config.search.minpix

    def render(self):
        return {"bright": self.bright}


def test_a_minimal_tuner_needs_nothing_of_its_subclass_before_the_hooks_make_it(road, tmp_path):
    t = _Probe(road)
    assert t.missing == []  # the base asked for no attribute the subclass had not made
    assert t.calls == ["build", "prepare", ("update", None)]
    assert t.preview_sheet().shape == (225, 400, 3)
    t.calls.clear()
    t.controls["level"].value = 200
    assert t.calls == [("apply", "level"), ("update", "level")]
    assert t.config.search.minpix == 200
    assert cv2.countNonZero(t.bright) == int((t.gray > 200).sum())
    path = t.save(tmp_path / "probe.json")
    t.calls.clear()
    t.picker.value = CURVED
    assert t.calls == ["prepare", ("update", None)]
    other = _Probe(road)
    other.load(path)
    assert other.config.search.minpix == 200 and other.controls["level"].value == 200
    assert other.missing == [] and t.missing == []

