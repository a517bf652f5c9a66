"""Tests of the multi-line search ``lines.trace.find_lines`` (issue 17, every line in view): known
answers on synthetic lines-view masks (lines.view.LinesView's default size); and of the lines view
itself (``lines.view.LinesView``)."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lanelib.errors import ConfigError
from lanelib.lines.detect import scaled_thresholds
from lanelib.lines.trace import find_lines
from lanelib.lines.view import LinesView
from lanelib.params import LinesConfig, ThresholdConfig, TopHatMask
from lanelib.perspective import Perspective


# --------------------------------------------------------------------------- every line (find_lines)

LINES_SIZE = (1750, 755)  # lines.view.LinesView's default: 28 m x 151 m at 0.016 x 0.2 m/px


def _lines_mask(lines, dashed, size=LINES_SIZE, width_px=9):
    """Return a lines-view mask of lines x = f(y) (callables), each dashed (3 m on, 9 m off) or solid."""
    w, h = size
    mask = np.zeros((h, w), np.uint8)
    ys = np.arange(h, dtype=np.float64)
    for f, dash in zip(lines, dashed):
        on = ((h - ys) % 60) < 15 if dash else np.ones(h, bool)
        for y in ys[on].astype(int):
            x = f(float(y))
            cv2.line(mask, (int(round(x - width_px / 2)), y), (int(round(x + width_px / 2)), y), 255, 1)
    return mask


@pytest.mark.parametrize("a", [0.0, 1.5e-4, -1.5e-4])
def test_find_lines_known_answer(a):
    # four lines of one road 3.7 m (231 px) apart, straight or bent alike, two solid, two dashed
    h = LINES_SIZE[1]
    bases = (420.0, 651.0, 882.0, 1113.0)
    fs = [lambda y, b=b: b + a * (h - y) ** 2 for b in bases]
    mask = _lines_mask(fs, (False, True, True, False))
    found = find_lines(mask, LinesConfig(extend_m=0.0))
    assert len(found) == 4
    for line, f, dashed in zip(found, fs, (False, True, True, False)):  # left to right
        rows = np.arange(line.y_top_px, line.y_bottom_px + 1)
        truth = np.array([f(y) for y in rows])
        assert np.abs(line.x_at(rows) - truth).max() < 2.0
        assert line.y_bottom_px >= h - 15 and line.y_top_px <= 60  # seen over the whole view
        assert line.scatter_px < 5  # a 10 px band: 1.4826 x its median distance, 3.7 px


def test_find_lines_spans_merge_and_noise():
    h = LINES_SIZE[1]
    # a line seen only far ahead, one only near, a repeated trace of one line (two dashes 2 px
    # apart are one line), and specks of noise: three lines, each with the span where it is seen
    far = lambda y: 300.0  # noqa: E731
    near = lambda y: 900.0  # noqa: E731
    mask = _lines_mask([far, near], (False, True))
    mask[h - 250:, 280:320] = 0  # the far line is seen from 50 m on (bands start lines to 60 m)
    mask[:h - 200, 880:920] = 0  # the near line on the lowest 200 rows (40 m) only
    mask = np.maximum(mask, _lines_mask([lambda y: 1400.0, lambda y: 1402.0], (True, True)))
    rng = np.random.default_rng(0)
    mask[rng.integers(0, h, 300), rng.integers(0, LINES_SIZE[0], 300)] = 255
    found = find_lines(mask, LinesConfig(extend_m=0.0))
    assert [round(float(line.x_at(line.y_bottom_px))) for line in found] == [300, 900, 1401]
    assert found[0].y_bottom_px < h - 249 and found[0].y_top_px < 5
    assert found[1].y_top_px > h - 215
    extended = find_lines(mask, LinesConfig(extend_m=9.0))
    assert extended[0].y_bottom_px == pytest.approx(found[0].y_bottom_px + 45)


def test_find_lines_empty_and_config():
    assert find_lines(np.zeros(LINES_SIZE[::-1], np.uint8)) == []
    with pytest.raises(ConfigError):
        LinesConfig(bands=0)


# --------------------------------------------------------------------------- the lines view

def test_lines_view_round_trip_and_scale():
    ego = Perspective()
    view = LinesView(ego)
    assert view.size == (1750, 755) and view.xm_per_px == 0.016 and view.ym_per_px == 0.2
    pts = np.array([[640.0, 700.0], [300.0, 719.0], [900.0, 500.0], [640.0, 440.0], [100.0, 600.0]])
    back = view.inverse(view(pts))
    assert np.abs(back - pts).max() < 1e-6
    # the same road as the ego view: ego points go to the view by the affine ego_to_view
    assert np.abs(view.ego_to_view(ego(pts)) - view(pts)).max() < 1e-6
    # the car's centre line is the view's centre column; the ego bottom row is 1 m above the bottom
    car = ego.inverse([[ego.car_x_px, 720.0]])
    assert view(car)[0] == pytest.approx([875.0, 750.0])
    # metres: the ego lines 3.7 m apart are 231 px apart; 23.5 m of ego view is 117.5 rows
    left, right = view.ego_to_view([[320.0, 720.0], [960.0, 0.0]])
    assert right[0] - left[0] == pytest.approx(3.7 / 0.016)
    assert left[1] - right[1] == pytest.approx(23.5 / 0.2)
    assert view.scale_from_ego == pytest.approx(ego.xm_per_px / 0.016)
    with pytest.raises(ConfigError):
        LinesView(ego, xm_per_px=0.0)


def test_lines_view_remap_keeps_a_road_point():
    # a white dot on the undistorted image lands where the view maps it
    ego = Perspective()
    view = LinesView(ego)
    img = np.zeros((720, 1280, 3), np.uint8)
    cv2.circle(img, (700, 560), 6, (255, 255, 255), -1)
    maps = view.remap_maps(view.size)
    out = cv2.remap(img, maps[0], maps[1], cv2.INTER_LINEAR)
    ys, xs = np.nonzero(out[:, :, 0] > 128)
    x, y = view([[700.0, 560.0]])[0]
    assert abs(xs.mean() - x) < 3 and abs(ys.mean() - y) < 3


def test_scaled_thresholds_for_a_coarser_view():
    c = ThresholdConfig()
    s = scaled_thresholds(c, 0.36)  # the lines view: 0.016 m/px against the ego view's 0.0058
    assert s.line_tophat.width_px == 22 and s.line_tophat.min_width_px == 4
    assert s.shade_tophat.width_px == 22 and s.shade_tophat.ratio == c.shade_tophat.ratio
    assert s.white == c.white and s.yellow == c.yellow and s.sobel_x == c.sobel_x and s.rule == c.rule
    assert s.open_px == 0 and s.close_px == 0  # off stays off
    assert s.clahe_tile_px == 58
    assert scaled_thresholds(c, 1.0) == c
    t = scaled_thresholds(ThresholdConfig(close_px=5, line_tophat=TopHatMask(width_px=10, min_width_px=8)), 0.1)
    # a least width scaled below 2 px is 1: off (a 1-px opening keeps everything)
    assert t.close_px == 1 and t.line_tophat.width_px == 3 and t.line_tophat.min_width_px == 1
    with pytest.raises(ConfigError):
        scaled_thresholds(c, 0.0)
