"""The basic Hough lane-line pipeline: stages with known answers, video tracking, CLI, real data."""
from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from dataclasses import replace

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from lanelib import ConfigError, InputError, LaneLibError, batch, hough, io
from lanelib import config as config_module
from lanelib.batch.video import VideoWriter
from lanelib.cli import main

H, W = 540, 960
WHITE, YELLOW = (255, 255, 255), (240, 200, 20)
# two straight lines (bottom point, point higher up) inside the default region of interest
LEFT_LINE = ((180.0, 539.0), (450.0, 330.0))
RIGHT_LINE = ((860.0, 539.0), (520.0, 330.0))


def x_at(line, y):
    """x (px) of the infinite line through ``line``'s two points at row ``y``."""
    (x0, y0), (x1, y1) = line
    return x0 + (x1 - x0) * (y - y0) / (y1 - y0)


def road(lines=(LEFT_LINE, RIGHT_LINE), colors=(YELLOW, WHITE), shape=(H, W), shift_px=0.0):
    """A dark road frame with thick painted lines; ``shift_px`` moves every line right."""
    rgb = np.full(shape + (3,), 70, np.uint8)
    for ((xb, yb), (xt, yt)), color in zip(lines, colors):
        cv2.line(rgb, (round(xb + shift_px), round(yb)), (round(xt + shift_px), round(yt)), color,
                 12, cv2.LINE_AA)
    return rgb


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "lanelib", *map(str, args)],
                          capture_output=True, text=True)


# --------------------------------------------------------------------------- stages

def test_two_drawn_lines_are_recovered_within_a_few_px():
    result = hough.HoughLaneFinder().process(road())
    top = hough.roi_top_px(H, hough.HoughConfig().roi_frac)
    assert result.reason == ""
    for line, truth in ((result.left, LEFT_LINE), (result.right, RIGHT_LINE)):
        assert line.y_bottom_px == H - 1 and line.y_top_px == pytest.approx(top)
        assert line.x_bottom_px == pytest.approx(x_at(truth, H - 1), abs=3)
        assert line.x_top_px == pytest.approx(x_at(truth, top), abs=3)


def test_all_black_frame_finds_nothing_and_says_why():
    result = hough.HoughLaneFinder().process(np.zeros((H, W, 3), np.uint8))
    assert not result.left_found and not result.right_found
    assert result.n_left_segments == result.n_right_segments == 0
    assert "left: no segments with negative slope" in result.reason
    assert "right: no segments with positive slope" in result.reason


def test_a_missing_side_is_named_and_the_other_is_found():
    result = hough.HoughLaneFinder().process(road(lines=(RIGHT_LINE,), colors=(WHITE,)))
    assert result.right_found and not result.left_found
    assert result.reason.startswith("left: no segments with negative slope")


def test_grey_lines_are_not_paint():
    result = hough.HoughLaneFinder().process(road(colors=((130, 130, 130),) * 2))
    assert not result.left_found and not result.right_found


def test_stages_are_full_frame_masks_and_segments_are_in_frame_pixels():
    stages = hough.HoughLaneFinder().process(road(), keep_stages=True).stages
    for image in (stages.color_mask, stages.gray, stages.blurred, stages.edges, stages.roi_edges):
        assert image.shape == (H, W) and image.dtype == np.uint8
    assert set(np.unique(stages.roi_edges)) <= {0, 255}
    assert not stages.roi_edges[: int(0.6 * H) - 1].any()  # nothing above the region
    assert len(stages.segments) >= len(stages.left_segments) + len(stages.right_segments) > 0
    assert stages.left_segments[:, [0, 2]].max() < W / 2 < stages.right_segments[:, [0, 2]].min()


def test_split_by_slope_uses_the_sign_of_dy_dx_and_drops_flat_and_vertical_segments():
    segs = np.array([[100, 500, 200, 400],   # dy/dx = -1: left
                     [800, 500, 700, 400],   # +1: right
                     [100, 500, 300, 480],   # -0.1: too flat
                     [400, 500, 400, 300]],  # vertical: no sign
                    np.int32)
    left, right = hough.split_by_slope(segs, min_abs_slope=0.5)
    assert left.tolist() == [segs[0].tolist()] and right.tolist() == [segs[1].tolist()]
    assert hough.split_by_slope(np.zeros((0, 4), np.int32), 0.5)[0].shape == (0, 4)


def test_fit_side_is_exact_on_collinear_segments_and_length_weighted():
    # x = 0.5 * y + 10 through both segments
    segs = np.array([[260, 500, 210, 400], [160, 300, 135, 250]], np.int32)
    line = hough.fit_side(segs, 539, 300)
    assert (line.x_bottom_px, line.x_top_px) == pytest.approx((279.5, 160.0))
    # a 200 px segment on x = 300 and a 20 px one on x = 340, both centred on y = 400: the fit
    # is vertical at the length-weighted mean x (an unweighted fit would give 320)
    line = hough.fit_side(np.array([[300, 500, 300, 300], [340, 410, 340, 390]], np.int32), 539, 300)
    assert line.x_bottom_px == line.x_top_px == pytest.approx(300 + 40 * 20 / 220)
    assert hough.fit_side(np.zeros((0, 4), np.int32), 539, 300) is None
    assert hough.fit_side(np.array([[10, 400, 90, 400]], np.int32), 539, 300) is None
    assert hough.fit_side(np.array([[10, 400, 10, 400]], np.int32), 539, 300) is None


def test_roi_mask_covers_the_polygon_in_image_fractions():
    mask = hough.roi_mask((100, 200), ((0.0, 1.0), (0.5, 0.0), (1.0, 1.0)))
    assert mask.shape == (100, 200) and mask.dtype == np.uint8
    assert set(np.unique(mask)) == {0, 255}
    assert mask[99, 1] == mask[99, 198] == mask[50, 100] == 255
    assert mask[5, 5] == mask[5, 195] == 0


def test_annotate_blends_the_lines_over_a_copy():
    rgb = road()
    result = hough.HoughLaneFinder().process(rgb)
    out = hough.annotate(rgb, result)
    assert out.shape == rgb.shape and out.dtype == np.uint8 and out is not rgb
    (xl, yl), _ = result.left.points()
    (xr, yr), _ = result.right.points()
    assert out[yl - 2, xl, 0] > out[yl - 2, xl, 2]  # left is red
    assert out[yr - 2, xr, 2] > out[yr - 2, xr, 0]  # right is blue
    overlay = rgb.copy()  # the band blend equals a full-frame blend of the drawn lines
    for line, color in ((result.left, hough.LEFT_COLOR_RGB), (result.right, hough.RIGHT_COLOR_RGB)):
        cv2.line(overlay, *line.points(), color, 10, cv2.LINE_AA)
    assert np.array_equal(out, cv2.addWeighted(overlay, 0.7, rgb, 0.3, 0.0))
    empty = hough.HoughResult(None, None, 0, 0, "none")
    assert np.array_equal(hough.annotate(rgb, empty), rgb)


# --------------------------------------------------------------------------- input and config

@pytest.mark.parametrize("bad", [np.zeros((H, W, 3), np.float32), np.zeros((H, W), np.uint8),
                                 np.zeros((H, W, 4), np.uint8), np.zeros((0, W, 3), np.uint8),
                                 [[0, 0, 0]]])
def test_wrong_arrays_raise_input_error(bad):
    with pytest.raises(InputError, match="expected"):
        hough.HoughLaneFinder().process(bad)


@pytest.mark.parametrize("change", [dict(blur_kernel_px=4), dict(canny_low=200, canny_high=100),
                                    dict(roi_frac=((0, 1), (1, 1))), dict(roi_frac=((0, 1), (0.5, 1.2), (1, 1))),
                                    dict(theta_deg=0), dict(rho_px=0.0), dict(smoothing_alpha=0),
                                    dict(white_hls_lo=(0, 200))])
def test_invalid_config_raises_config_error(change):
    with pytest.raises(ConfigError, match="hough"):
        replace(hough.HoughConfig(), **change)


def test_config_from_json_lists_becomes_tuples_and_round_trips():
    config = hough.HoughConfig(roi_frac=[[0, 1], [0.5, 0.5], [1, 1]], white_hls_lo=[0, 190, 0])
    assert config.roi_frac == ((0, 1), (0.5, 0.5), (1, 1)) and config.white_hls_lo == (0, 190, 0)
    assert hash(config) == hash(replace(config))
    pipeline = config_module.PipelineConfig(hough=config)
    assert config_module.from_dict(config_module.PipelineConfig,
                                   json.loads(json.dumps(config_module.to_dict(pipeline)))) == pipeline


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(
    arrays(np.uint8, st.tuples(st.integers(1, 64), st.integers(1, 64), st.just(3))),
    arrays(st.sampled_from([np.uint8, np.float32, np.int16, np.bool_]),
           st.lists(st.integers(0, 5), min_size=0, max_size=4).map(tuple))))
def test_random_arrays_never_raise_anything_but_lanelib_errors(frame):
    tracker = hough.HoughTracker()
    try:
        for _ in range(2):
            result = tracker.process(frame)
            hough.annotate(frame, result)
    except LaneLibError:
        return
    assert isinstance(result, hough.HoughResult)
    assert result.left_found == (result.left is not None)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blur=st.integers(0, 10).map(lambda k: 2 * k + 1), low=st.integers(0, 300), extra=st.integers(0, 300),
       rho=st.floats(0.5, 10), theta=st.floats(0.2, 90), votes=st.integers(1, 200),
       length=st.integers(0, 200), gap=st.integers(0, 400), slope=st.floats(0, 10),
       roi=st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=3, max_size=6),
       seed=st.integers(0, 2 ** 16))
def test_any_valid_config_runs_on_noise(blur, low, extra, rho, theta, votes, length, gap, slope, roi, seed):
    config = hough.HoughConfig(blur_kernel_px=blur, canny_low=low, canny_high=low + extra, rho_px=rho,
                               theta_deg=theta, threshold_votes=votes, min_line_length_px=length,
                               max_line_gap_px=gap, min_abs_slope=slope, roi_frac=tuple(roi))
    frame = np.random.default_rng(seed).integers(0, 256, (90, 160, 3), dtype=np.uint8)
    result = hough.HoughLaneFinder(config).process(frame)
    assert hough.annotate(frame, result).shape == frame.shape
    for line in (result.left, result.right):
        assert line is None or all(math.isfinite(v) for v in (line.x_bottom_px, line.x_top_px))


# --------------------------------------------------------------------------- video tracking

def test_tracker_smooths_line_endpoints_exponentially():
    config = hough.HoughConfig(smoothing_alpha=0.25)
    tracker, finder = hough.HoughTracker(config), hough.HoughLaneFinder(config)
    first, moved = finder.process(road()), finder.process(road(shift_px=20))
    tracker.process(road())
    result = tracker.process(road(shift_px=20))
    expected = 0.25 * moved.left.x_bottom_px + 0.75 * first.left.x_bottom_px
    assert result.left.x_bottom_px == pytest.approx(expected)
    assert not result.left_held and result.reason == ""


def test_tracker_holds_a_lost_line_for_hold_frames_then_drops_it():
    tracker = hough.HoughTracker(hough.HoughConfig(hold_frames=3))
    good = tracker.process(road())
    black = np.zeros((H, W, 3), np.uint8)
    for missed in range(1, 4):
        held = tracker.process(black)
        assert held.left_held and held.right_held and held.left == good.left
        assert f"left line held from the last good frame ({missed} missed)" in held.reason
    dropped = tracker.process(black)
    assert not dropped.left_found and not dropped.right_found and not dropped.left_held
    again = tracker.process(road(shift_px=30))  # found again: starts afresh, not blended
    assert again.left == hough.HoughLaneFinder().process(road(shift_px=30)).left


def test_tracker_starts_afresh_when_the_frame_size_changes():
    tracker = hough.HoughTracker(hough.HoughConfig(smoothing_alpha=0.1))
    tracker.process(road())
    small = road(lines=(((90, 269), (225, 165)), ((430, 269), (260, 165))), shape=(270, 480))
    assert tracker.process(small).left == hough.HoughLaneFinder().process(small).left


# --------------------------------------------------------------------------- CLI

def write_clip(path, frames=8):
    with VideoWriter(path, 25) as writer:
        for i in range(frames):
            writer.write(road(shift_px=i))


def test_cli_help_names_the_outputs(capsys):
    with pytest.raises(SystemExit) as e:
        main(["hough", "--help"])
    out = capsys.readouterr().out
    assert e.value.code == 0 and "usage: python -m lanelib hough" in out and "results.json" in out


@pytest.mark.parametrize("name", ["nope", "nope.mp4"])
def test_cli_missing_input_is_one_line_and_exit_2(tmp_path, name):
    p = run_cli("hough", tmp_path / name, "-o", tmp_path / "out")
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{name}: no such file or folder" in lines[0], p.stderr
    assert not (tmp_path / "out").exists()


def test_cli_unreadable_inputs_exit_2(tmp_path):
    (tmp_path / "notes.txt").write_text("x")
    (tmp_path / "broken.mp4").write_bytes(b"not a video")
    for name in ("notes.txt", "broken.mp4"):
        p = run_cli("hough", tmp_path / name, "-o", tmp_path / "out.mp4")
        assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "out.mp4").exists()


def test_cli_images_write_annotated_images_and_results_json(tmp_path):
    io.write_image(tmp_path / "in" / "road.png", road())
    io.write_image(tmp_path / "in" / "black.png", np.zeros((H, W, 3), np.uint8))
    before = {f.name: f.read_bytes() for f in (tmp_path / "in").iterdir()}
    assert main(["hough", str(tmp_path / "in"), "-o", str(tmp_path / "out")]) == 0
    rows = {r["file"]: r for r in json.loads((tmp_path / "out" / "results.json").read_text())}
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == ["black.png", "results.json", "road.png"]
    assert {f.name: f.read_bytes() for f in (tmp_path / "in").iterdir()} == before
    good, black = rows["road.png"], rows["black.png"]
    assert good["left_found"] and good["right_found"] and good["reason"] == ""
    assert good["left_x_bottom"] == pytest.approx(x_at(LEFT_LINE, H - 1), abs=3)
    assert good["right_x_bottom"] == pytest.approx(x_at(RIGHT_LINE, H - 1), abs=3)
    assert good["left_x_top"] > good["left_x_bottom"] and good["right_x_top"] < good["right_x_bottom"]
    assert black["left_found"] is black["right_found"] is False
    assert black["left_x_bottom"] is black["right_x_top"] is None and black["reason"]


def test_cli_never_writes_over_its_input(tmp_path):
    io.write_image(tmp_path / "a.png", road())
    p = run_cli("hough", tmp_path, "-o", tmp_path)
    assert p.returncode == 2 and "output folder is the input folder" in p.stderr
    write_clip(tmp_path / "clip.mp4")
    before = (tmp_path / "clip.mp4").read_bytes()
    p = run_cli("hough", tmp_path / "clip.mp4", "-o", tmp_path / "clip.mp4")
    assert p.returncode == 2 and "overwrite an input" in p.stderr
    assert (tmp_path / "clip.mp4").read_bytes() == before
    assert sorted(f.name for f in tmp_path.iterdir()) == ["a.png", "clip.mp4"]


def test_cli_log_is_for_videos_only(tmp_path):
    io.write_image(tmp_path / "in" / "a.png", road())
    p = run_cli("hough", tmp_path / "in", "-o", tmp_path / "out", "--log", tmp_path / "log.csv")
    assert p.returncode == 2 and "--log is for videos" in p.stderr


def test_cli_video_writes_video_and_per_frame_log(tmp_path):
    write_clip(tmp_path / "clip.mp4", frames=8)
    assert main(["hough", str(tmp_path / "clip.mp4"), "-o", str(tmp_path / "out.mp4"),
                 "--log", str(tmp_path / "log.csv"), "--no-progress"]) == 0
    assert io.VideoReader(tmp_path / "out.mp4").info.size == (W, H)
    rows = list(csv.DictReader((tmp_path / "log.csv").open()))
    assert [r["frame"] for r in rows] == [str(i) for i in range(8)]
    assert list(rows[0])[:8] == ["frame", "time_s", "left_found", "right_found", "left_x_bottom",
                                 "left_x_top", "right_x_bottom", "right_x_top"]
    assert all(r["left_found"] == r["right_found"] == "True" for r in rows)
    assert float(rows[1]["time_s"]) == pytest.approx(0.04)


def test_cli_config_file_uses_its_hough_part(tmp_path):
    io.write_image(tmp_path / "in" / "road.png", road())
    # a region of interest that holds only the left line
    (tmp_path / "c.json").write_text(json.dumps({"hough": {"roi_frac": [[0, 1], [0, 0.6], [0.45, 0.6],
                                                                         [0.45, 1]]}}))
    p = run_cli("hough", tmp_path / "in", "-o", tmp_path / "out", "--config", tmp_path / "c.json")
    assert p.returncode == 0, p.stderr
    row = json.loads((tmp_path / "out" / "results.json").read_text())[0]
    assert row["left_found"] and not row["right_found"]
    (tmp_path / "bad.json").write_text(json.dumps({"hough": {"blur_kernel_px": 4}}))
    p = run_cli("hough", tmp_path / "in", "-o", tmp_path / "out2", "--config", tmp_path / "bad.json")
    assert p.returncode == 2 and "blur_kernel_px" in p.stderr


# --------------------------------------------------------------------------- real data

# Where the painted lines cross the bottom row (y = 539) of the six 960x540 P1 test images,
# measured once, independently of this pipeline: in each row from y = 400 down to the bottom,
# the centroid of the paint pixels (white: min(R, G, B) >= 190; yellow: R, G >= 150 and
# B <= R - 60) inside a generous lane triangle on each half of the image; a straight line
# x(y) fitted to those centroids (over at least two dashes where the line is dashed) and
# evaluated at y = 539. Checked against raw pixel rows where the paint reaches the bottom
# (e.g. solidYellowLeft row 537: yellow from x = 141 to 158) and by eye on a marked crop.
P1_BOTTOM_X = {  # file: (left x, right x) in px
    "solidWhiteCurve.jpg": (191.6, 888.3),
    "solidWhiteRight.jpg": (150.5, 843.6),
    "solidYellowCurve.jpg": (163.0, 863.1),
    "solidYellowCurve2.jpg": (168.7, 863.8),
    "solidYellowLeft.jpg": (147.5, 850.0),
    "whiteCarLaneSwitch.jpg": (185.9, 874.0),
}


@pytest.mark.udacity
@pytest.mark.parametrize("name", sorted(P1_BOTTOM_X))
def test_p1_images_both_lines_within_15_px_at_the_bottom_row(udacity_p1, name):
    result = hough.HoughLaneFinder().process(io.read_image(udacity_p1 / "test_images" / name))
    assert result.left_found and result.right_found, result.reason
    left_x, right_x = P1_BOTTOM_X[name]
    assert result.left.y_bottom_px == result.right.y_bottom_px == 539
    assert abs(result.left.x_bottom_px - left_x) <= 15
    assert abs(result.right.x_bottom_px - right_x) <= 15


def both_found_share(log_csv):
    rows = list(csv.DictReader(open(log_csv)))
    return len(rows), sum(r["left_found"] == r["right_found"] == "True" for r in rows) / len(rows)


@pytest.mark.udacity
@pytest.mark.slow
def test_p1_videos_end_to_end_find_both_lines_in_95_percent_of_frames(udacity_p1, tmp_path):
    videos = udacity_p1 / "test_videos"
    assert main(["hough", str(videos / "solidWhiteRight.mp4"), "-o", str(tmp_path / "white.mp4"),
                 "--log", str(tmp_path / "white.csv"), "--no-progress"]) == 0
    run = batch.hough_video(videos / "solidYellowLeft.mp4", tmp_path / "yellow.mp4",
                            log_path=tmp_path / "yellow.csv", progress=False)
    assert run.frames == 681 and run.found_frames >= 0.95 * 681
    for name, frames in (("white", 221), ("yellow", 681)):
        n, share = both_found_share(tmp_path / f"{name}.csv")
        assert n == frames and share >= 0.95, (name, share)
        assert io.VideoReader(tmp_path / f"{name}.mp4").info.size == (W, H)
