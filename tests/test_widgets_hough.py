"""The Hough tuner driven without a browser: set a control's ``.value``, check config and preview.

Setting ``.value`` in Python runs the same ``observe`` callback a slider drag in JupyterLab runs.
The frames are drawn here (two straight lane lines on a grey road), so the test needs no data.
"""
from __future__ import annotations

import json
from dataclasses import replace

import cv2
import numpy as np
import pytest

from lanelib import hough, io, widgets
from lanelib.config import PipelineConfig, load_config, save_config
from lanelib.hough import HoughConfig

W, H = 960, 540
LEFT_BOTTOM, RIGHT_BOTTOM = 170, 860  # x (px) of the drawn lines on the bottom row
TOP_Y = 330


def _road(path) -> str:
    """Write a 960x540 road with a yellow left and a white right line to ``path``; return it.

    The right line's lower part runs over light concrete (grey 200, inside the white colour
    range), where its edges are faint: high Canny thresholds lose them.
    """
    img = np.full((H, W, 3), 90, np.uint8)
    img[:TOP_Y - 20] = (150, 180, 220)  # sky
    img[420:, 600:] = 200  # light concrete
    cv2.line(img, (LEFT_BOTTOM, H - 1), (450, TOP_Y), (230, 190, 40), 12, cv2.LINE_AA)
    cv2.line(img, (RIGHT_BOTTOM, H - 1), (520, TOP_Y), (255, 255, 255), 12, cv2.LINE_AA)
    io.write_image(path, img)
    return str(path)


@pytest.fixture()
def images(tmp_path):
    road = _road(tmp_path / "road.png")
    blank = tmp_path / "blank.png"
    io.write_image(blank, np.full((H, W, 3), 90, np.uint8))
    return {"road.png": road, "blank.png": str(blank)}


def test_the_tuner_finds_both_drawn_lines(images):
    t = widgets.HoughTuner(images)
    assert t.config.hough == HoughConfig()
    assert t.result.left_found and t.result.right_found
    assert abs(t.result.left.x_bottom_px - LEFT_BOTTOM) < 8
    assert abs(t.result.right.x_bottom_px - RIGHT_BOTTOM) < 8
    # the same answer as the pipeline itself
    same = hough.HoughLaneFinder(t.config.hough).process(io.read_image(images["road.png"]))
    assert same.row() == t.result.row()
    assert "left:" in t.readout() and "right:" in t.readout()
    assert bytes(t.preview.value[:2]) == b"\xff\xd8"  # JPEG bytes


def test_canny_slider_changes_config_and_preview(images):
    t = widgets.HoughTuner(images)
    bytes0, edges0 = bytes(t.preview.value), cv2.countNonZero(t.stages.edges)

    t.controls["canny"].value = (200, 400)

    assert (t.config.hough.canny_low, t.config.hough.canny_high) == (200, 400)
    assert bytes(t.preview.value) != bytes0
    assert cv2.countNonZero(t.stages.edges) < edges0
    # every other parameter kept its value
    assert t.config.hough == HoughConfig(canny_low=200, canny_high=400)
    assert t.config.thresholds == PipelineConfig().thresholds


@pytest.mark.parametrize("key, value, field", [
    ("threshold_votes", 120, "threshold_votes"),
    ("min_line_length_px", 150, "min_line_length_px"),
    ("max_line_gap_px", 5, "max_line_gap_px"),
    ("rho_px", 2.0, "rho_px"),
    ("theta_deg", 2.0, "theta_deg"),
    ("min_abs_slope", 1.5, "min_abs_slope"),
    ("blur_kernel_px", 9, "blur_kernel_px"),
])
def test_each_hough_slider_sets_its_field(images, key, value, field):
    t = widgets.HoughTuner(images)
    bytes0 = bytes(t.preview.value)
    t.controls[key].value = value
    assert getattr(t.config.hough, field) == value
    kind = "control" if key == "blur_kernel_px" else "slider"
    assert f"lanelib-{kind}-{key}" in t.controls[key]._dom_classes  # the browser test finds it so
    assert t.error == ""
    # a change that alters what the Hough stage finds alters the preview
    if key in ("threshold_votes", "min_line_length_px", "blur_kernel_px", "min_abs_slope"):
        assert bytes(t.preview.value) != bytes0


def test_roi_sliders_move_the_region_and_can_lose_a_line(images):
    t = widgets.HoughTuner(images)
    bytes0 = bytes(t.preview.value)
    t.controls["roi.top_y"].value = 0.7
    assert all(y in (0.7, 1.0) for _, y in t.config.hough.roi_frac)
    assert bytes(t.preview.value) != bytes0
    # the region's right edge moved left of the right line: no right line any more
    t.controls["roi.bottom_right"].value = 0.5
    t.controls["roi.top_right"].value = 0.5
    assert t.config.hough.roi_frac[3] == (0.5, 1.0)
    assert not t.result.right_found
    assert "right" in t.result.reason and "right" in t.readout()
    assert t.result.left_found


def test_collapsed_region_finds_nothing_and_does_not_raise(images):
    t = widgets.HoughTuner(images)
    t.controls["roi.top_y"].value = 1.0  # the region shrinks to the bottom row
    assert t.error == ""
    assert not t.result.left_found and not t.result.right_found
    t.controls["roi.top_y"].value = 0.6
    assert t.result.left_found and t.result.right_found


def test_picker_switches_image_and_reports_missing_lines(images):
    t = widgets.HoughTuner(images)
    t.picker.value = "blank.png"
    assert not t.result.left_found and not t.result.right_found
    assert "no segments" in t.result.reason
    assert "no line" in t.readout()


def test_save_writes_the_hough_part_and_keeps_other_parts(images, tmp_path):
    t = widgets.HoughTuner(images)
    t.controls["canny"].value = (30, 120)
    t.controls["threshold_votes"].value = 40
    # a config file that another tuner wrote: its other parts survive
    path = tmp_path / "tuned.json"
    other = PipelineConfig()
    other = replace(other, search=replace(other.search, margin_px=55))
    save_config(other, path)
    t.save(path)
    saved = load_config(path)
    assert saved.hough.canny_low == 30 and saved.hough.threshold_votes == 40
    assert saved.search.margin_px == 55
    assert json.loads(path.read_text())["hough"]["canny_high"] == 120

    fresh = widgets.HoughTuner(images)
    bytes0 = bytes(fresh.preview.value)
    loaded = fresh.load(path)
    assert loaded.hough == saved.hough
    assert fresh.controls["canny"].value == (30, 120)
    assert fresh.controls["threshold_votes"].value == 40
    assert bytes(fresh.preview.value) != bytes0


def test_load_takes_only_the_hough_part(images, tmp_path):
    path = tmp_path / "other.json"
    other = PipelineConfig()
    save_config(replace(other, hough=HoughConfig(canny_low=20), search=replace(other.search, margin_px=55)),
                path)
    t = widgets.HoughTuner(images)
    t.load(path)
    assert t.config.hough == HoughConfig(canny_low=20)
    assert t.config.search == PipelineConfig().search  # not the Hough tuner's to show


def test_config_for_returns_the_new_config_and_changes_nothing(images):
    t = widgets.HoughTuner(images)
    config, result, preview = t.config, t.result, bytes(t.preview.value)
    shown = t.controls["canny"].value
    new = t.config_for("canny", (200, 400))
    assert (new.hough.canny_low, new.hough.canny_high) == (200, 400)
    assert t.config is config and t.result is result and bytes(t.preview.value) == preview
    assert t.controls["canny"].value == shown
    t.controls["canny"].value = (200, 400)  # the user moves the slider: its observer takes it
    assert t.config == new and t.result is not result


def test_text_output_is_short_and_stable(images):
    t = widgets.HoughTuner(images)
    bundle = t._repr_mimebundle_()
    assert bundle["text/plain"] == "HoughTuner(image='road.png')"
    assert "application/vnd.jupyter.widget-view+json" in bundle


def test_image_choices_list_bundled_then_p1(tmp_path):
    (tmp_path / "repo" / "test_images").mkdir(parents=True)
    _road(tmp_path / "repo" / "test_images" / "a.jpg")
    p1 = tmp_path / "data" / "udacity-lanelines-p1" / "test_images"
    p1.mkdir(parents=True)
    _road(p1 / "solidWhiteRight.jpg")
    choices = widgets.hough_image_choices(tmp_path / "repo", tmp_path / "data")
    assert list(choices) == ["a.jpg", "udacity-p1/solidWhiteRight.jpg"]
    assert widgets.hough_image_choices(tmp_path / "repo", tmp_path / "nothing") == {
        "a.jpg": tmp_path / "repo" / "test_images" / "a.jpg"}


# --------------------------------------------------------------------------- colour ranges

def test_the_colour_ranges_show_the_configs_hls_bounds(images):
    t = widgets.HoughTuner(images)
    hc = t.config.hough
    for color in ("white", "yellow"):
        lo, hi = getattr(hc, f"{color}_hls_lo"), getattr(hc, f"{color}_hls_hi")
        for i, (letter, top) in enumerate(zip("HLS", (179, 255, 255))):
            s = t.controls[f"{color}.range{i}"]
            assert (s.value, s.min, s.max, s.description) == ((lo[i], hi[i]), 0, top, letter)
            assert f"lanelib-slider-{color}-range{i}" in s._dom_classes  # as ThresholdTuner's


@pytest.mark.parametrize("key, value, color, lo, hi", [
    ("yellow.range2", (250, 255), "yellow", (10, 0, 250), (40, 255, 255)),  # the yellow line is too pale
    ("yellow.range0", (30, 40), "yellow", (30, 0, 100), (40, 255, 255)),  # the line's hue is 24
    ("white.range1", (150, 255), "white", (0, 150, 0), (179, 255, 255)),  # the grey road is not white...
    ("white.range1", (150, 180), "white", (0, 150, 0), (179, 180, 255)),  # ... nor the white line
])
def test_a_colour_range_sets_its_bounds_and_the_preview_is_the_pipelines(images, key, value, color,
                                                                         lo, hi):
    t = widgets.HoughTuner(images)
    bytes0, color0 = bytes(t.preview.value), t.stages.color_mask.copy()
    t.controls[key].value = value
    assert t.error == ""
    # the moved paint's bounds, every other parameter as it was
    assert t.config.hough == replace(HoughConfig(), **{f"{color}_hls_lo": lo, f"{color}_hls_hi": hi})
    # exactly what the pipeline does with the new config, stage by stage and drawn
    rgb = io.read_image(images["road.png"])
    fresh = hough.HoughLaneFinder(t.config.hough).process(rgb, keep_stages=True)
    assert fresh.row() == t.result.row()
    for stage in ("color_mask", "edges", "roi_edges"):
        assert np.array_equal(getattr(t.stages, stage), getattr(fresh.stages, stage)), stage
    assert np.array_equal(t.stages.segments, fresh.stages.segments)
    assert not np.array_equal(t.stages.color_mask, color0)
    assert np.array_equal(t.annotated(), hough.annotate(rgb, fresh))
    assert np.array_equal(t.preview_sheet(), widgets.HoughTuner(images, config=t.config).preview_sheet())
    assert bytes(t.preview.value) != bytes0
    if color == "yellow":  # the left line is the yellow one
        assert not t.result.left_found and t.result.right_found
        assert "left: no segments" in t.result.reason


def test_the_colour_ranges_round_trip_through_save_and_load(images, tmp_path):
    t = widgets.HoughTuner(images)
    t.controls["white.range1"].value = (190, 250)
    t.controls["yellow.range0"].value = (15, 35)
    t.controls["yellow.range2"].value = (90, 255)
    path = t.save(tmp_path / "tuned.json")
    held = json.loads(path.read_text())["hough"]
    assert (held["white_hls_lo"], held["white_hls_hi"]) == ([0, 190, 0], [179, 250, 255])
    assert (held["yellow_hls_lo"], held["yellow_hls_hi"]) == ([15, 0, 90], [35, 255, 255])
    assert load_config(path).hough == t.config.hough

    fresh = widgets.HoughTuner(images)
    assert fresh.load(path).hough == t.config.hough
    assert fresh.controls["white.range1"].value == (190, 250)
    assert fresh.controls["yellow.range0"].value == (15, 35)
    assert fresh.controls["yellow.range2"].value == (90, 255)
    assert np.array_equal(fresh.preview_sheet(), t.preview_sheet())


def test_a_loaded_low_bound_above_the_high_one_is_kept_until_its_paint_moves(images, tmp_path):
    # a yellow range that selects nothing (H low 40 > high 10) is valid in a config file
    odd = HoughConfig(yellow_hls_lo=(40, 0, 100), yellow_hls_hi=(10, 255, 255))
    path = save_config(replace(PipelineConfig(), hough=odd), tmp_path / "odd.json")
    t = widgets.HoughTuner(images)
    t.load(path)
    assert t.error == "" and t.config.hough == odd
    assert t.controls["yellow.range0"].value == (10, 40)  # shown sorted
    assert not t.result.left_found  # nothing is yellow
    t.controls["white.range1"].value = (190, 255)  # another paint: yellow stays as loaded
    assert t.config.hough.yellow_hls_lo == (40, 0, 100) and t.config.hough.yellow_hls_hi == (10, 255, 255)
    t.controls["yellow.range1"].value = (0, 250)  # yellow moved: its bounds are what it shows
    assert t.config.hough.yellow_hls_lo == (10, 0, 100)
    assert t.config.hough.yellow_hls_hi == (40, 250, 255)
    assert t.result.left_found
