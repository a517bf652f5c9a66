"""Lane-pixel search (``search``): histogram bases, sliding windows and the search around a prior,
on masks drawn from known geometry."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from lanelib.errors import ConfigError
from lanelib.fit import measure
from lanelib.params import SearchConfig
from lanelib.records import LineFit
from lanelib.search import (base_peak_confidence, find_bases, histogram, lane_pixels, search_around,
                            sliding_windows)

H, W = 720, 1280


def draw_curve(mask, coeffs, thickness=20):
    ys = np.arange(H)
    pts = np.column_stack([np.polyval(coeffs, ys), ys]).round().astype(np.int32)
    cv2.polylines(mask, [pts.reshape(-1, 1, 2)], False, 255, thickness)
    return mask


def lane_mask(left, right, thickness=20):
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, left, thickness)
    draw_curve(m, right, thickness)
    return m


def test_parabolas_drawn_into_a_mask_are_recovered():
    left, right = (2e-4, -0.1, 340.0), (2e-4, -0.1, 980.0)
    search = sliding_windows(lane_mask(left, right))
    ys = np.arange(0, H, 40)
    for fit, truth in ((search.left, left), (search.right, right)):
        assert fit.found
        assert np.abs(fit.x_at(ys) - np.polyval(truth, ys)).max() < 1.5
    assert search.method == "windows" and len(search.windows) == 18


def test_search_around_previous_fit_follows_a_moved_lane():
    old = (LineFit((1e-4, 0.0, 300.0)), LineFit((1e-4, 0.0, 950.0)))
    moved = lane_mask((1e-4, 0.0, 330.0), (1e-4, 0.0, 980.0))
    search = search_around(moved, *old, SearchConfig(prior_margin_px=60))
    assert search.method == "prior"
    assert search.left.x_at(H - 1) == pytest.approx(330 + 1e-4 * (H - 1) ** 2, abs=1.5)
    assert search.right.x_at(0) == pytest.approx(980, abs=1.5)


def test_missing_line_is_reported_not_raised():
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 350.0))
    search = sliding_windows(m)
    assert search.left.found and not search.right.found
    assert "no lane pixels right of the car" in search.right.reason
    meas = measure(search.left, search.right, H, 640.0, 0.005, 0.03)
    assert math.isnan(meas.offset_m) and math.isnan(meas.radius_m) and not math.isnan(meas.left_curvature_per_m)


def test_empty_mask_finds_nothing_and_says_why():
    search = sliding_windows(np.zeros((H, W), np.uint8))
    assert not search.left.found and not search.right.found
    assert search.bases_px == (None, None)


def test_histogram_and_bases():
    m = lane_mask((0, 0, 300.0), (0, 0, 1000.0), thickness=1)
    hist = histogram(m, 0.5)
    assert hist[300] == H // 2 and hist[1000] == H // 2
    assert find_bases(hist, 640) == (300.0, 1000.0)


def test_a_line_with_no_pixels_in_the_lower_half_is_searched_from_the_whole_histogram():
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 320.0))
    cv2.line(m, (960, 100), (960, 300), 255, 24)  # one far dash, nothing below row 300
    search = sliding_windows(m)
    assert search.bases_px[1] == pytest.approx(960, abs=12)
    assert search.right.found and search.right.x_at(200) == pytest.approx(960, abs=2)


# --------------------------------------------------------------------------- the seeds' switches


def test_window_histogram_recentres_on_the_line_not_on_clutter_beside_it():
    m = np.zeros((H, W), np.uint8)
    m[:, 398:402] = 255          # a thin line
    m[::4, 440:471] = 255        # sparse clutter beside it, more pixels than the line
    m[:, 992:1008] = 255

    def centres(cfg):
        search = sliding_windows(m, cfg, bases=(400.0, 1000.0))
        return [(w.x_low + w.x_high) // 2 for w in search.windows if w.side == "left"]

    assert centres(SearchConfig())[1:] == [436] * 8                     # the mean x of line + clutter
    assert centres(SearchConfig(window_histogram=True))[1:] == [398] * 8  # the fullest column


def gap_mask():
    """A slanted left line with 3 empty windows (rows 240-479), a kerb beyond it up the road."""
    m = np.zeros((H, W), np.uint8)
    for y in range(H):
        if not 240 <= y < 480:
            x = int(round(300 + 0.6 * (H - 1 - y)))
            m[y, x - 8:x + 8] = 255
    m[0:240, 196:206] = 255   # a kerb left of the line (away from the lane centre)
    m[:, 992:1008] = 255      # the right line
    return m


def test_centre_first_and_a_growing_margin_recover_a_line_after_a_gap():
    m = gap_mask()

    def upper(cfg):  # the left line's pixels found above the gap
        search = sliding_windows(m, cfg, bases=(300.0, 1000.0))
        ys, xs = search.left_pixels
        return search, ys[ys < 240], xs[ys < 240]

    search, ys, xs = upper(SearchConfig(grow_margin_px=0))
    assert len(ys) == 0  # the plain windows stay where the line left off and lose it
    search, ys, xs = upper(SearchConfig(grow_margin_px=60))
    assert np.any(xs < 250)  # a grown window alone takes the kerb with the line
    search, ys, xs = upper(SearchConfig(centre_first=True, grow_margin_px=0))
    assert len(ys) == 0
    search, ys, xs = upper(SearchConfig(centre_first=True, grow_margin_px=60))
    assert len(ys) > 2000 and np.all(np.abs(xs - (300 + 0.6 * (H - 1 - ys))) <= 9)
    widths = [w.x_high - w.x_low for w in search.windows if w.side == "left"]
    assert widths == [160, 160, 160, 160, 280, 400, 520, 160, 160]  # grows per empty window, then resets


def test_centre_first_takes_the_cluster_nearest_the_lane_centre():
    m = np.zeros((H, W), np.uint8)
    m[:, 290:300] = 255        # left line
    m[:, 240:250] = 255        # a kerb further out, inside the same windows
    m[:, 980:990] = 255        # right line
    m[:, 1030:1040] = 255      # a kerb further out
    search = sliding_windows(m, SearchConfig(centre_first=True), bases=(280.0, 1000.0))
    assert set(np.unique(search.left_pixels[1])) == set(range(290, 300))
    assert set(np.unique(search.right_pixels[1])) == set(range(980, 990))
    plain = sliding_windows(m, SearchConfig(double_line_px=0), bases=(280.0, 1000.0))
    assert set(np.unique(plain.left_pixels[1])) == set(range(240, 250)) | set(range(290, 300))
    # two stripes 50 px apart on every row also pass for a double line: with the inner stripe of
    # a double line switched on (off by default) its inner stripe is kept
    double = sliding_windows(m, SearchConfig(double_line_px=38.0), bases=(280.0, 1000.0))
    assert set(np.unique(double.left_pixels[1])) == set(range(290, 300))


def test_base_peak_confidence():
    hist = np.zeros(10, np.int32)
    hist[2] = 10
    assert base_peak_confidence(hist, 2.0) == pytest.approx(9.0)  # mean 1: (10 - 1) / 1
    assert base_peak_confidence(hist, 5.0) == pytest.approx(-1.0)
    assert base_peak_confidence(hist, None) is None
    assert base_peak_confidence(np.zeros(10), 3.0) == 0.0
    m = lane_mask((0, 0, 300.0), (0, 0, 1000.0), thickness=1)
    search = sliding_windows(m)
    # two one-pixel lines of 360 rows in the lower half: mean 720 / 1280
    expected = (360 - 720 / W) / (720 / W)
    assert search.base_confidence == pytest.approx((expected, expected))
    assert sliding_windows(m, bases=(300.0, 1000.0)).base_confidence == (None, None)


def test_bad_search_switches():

    with pytest.raises(ConfigError, match="trim_outliers_pct"):
        SearchConfig(trim_outliers_pct=120)
    with pytest.raises(ConfigError, match="grow_margin_px"):
        SearchConfig(grow_margin_px=-5)


# --------------------------------------------------------------------------- country roads (issue 16)


YM_VIEW = 0.03263888888888889  # the default 1280 x 720 view's metres per row


LANE_LINES = (np.array([0.0, 0.0, 420.0]), np.array([0.0, 0.0, 860.0]))


def test_lane_pixels_equal_find_non_zero_for_any_width_and_view():
    # lane_pixels scans a contiguous mask of a width divisible by 4 as int32 words; any other mask
    # pixel by pixel: both give cv2.findNonZero's pixels in its order
    rng = np.random.default_rng(0)
    for trial in range(60):
        h, w = int(rng.integers(1, 30)), int(rng.integers(1, 120))
        mask = ((rng.random((h, w)) < rng.random()) * rng.integers(1, 256)).astype(np.uint8)
        for view in (mask, mask[:, 1:], mask[1:]):
            pts = cv2.findNonZero(view)
            pts = np.empty((0, 2), np.int32) if pts is None else pts.reshape(-1, 2)
            ys, xs = lane_pixels(view)
            assert ys.dtype == xs.dtype == np.int32
            assert np.array_equal(ys, pts[:, 1]) and np.array_equal(xs, pts[:, 0])


def test_a_fit_is_reused_only_for_the_same_pixels_under_the_same_config():
    """One image's searches share their fits (``fits``): the same pixels under the same config
    give the fit already made (the same object), under another config their own fit."""
    from lanelib.search import fit_side
    ys = np.arange(200, 720, dtype=np.int32)
    xs = (300 + 0.1 * (ys - 200)).astype(np.int32)
    loose, strict = SearchConfig(min_line_pixels=100), SearchConfig(min_line_pixels=1000)
    memo: dict = {}
    first, _ = fit_side((ys, xs), "left", 720, loose, "no lane pixels", fits=memo)
    again, _ = fit_side((ys.copy(), xs.copy()), "left", 720, loose, "no lane pixels", fits=memo)
    assert first.found and again is first
    other, _ = fit_side((ys, xs), "left", 720, strict, "no lane pixels", fits=memo)
    assert not other.found  # 520 pixels, fewer than this config's 1000: not the loose config's fit
    moved, _ = fit_side((ys, xs + 50), "left", 720, loose, "no lane pixels", fits=memo)
    assert moved.found and moved.coeffs_px[2] == pytest.approx(first.coeffs_px[2] + 50)
