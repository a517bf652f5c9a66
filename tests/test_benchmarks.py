"""Tests of lanelib.benchmarks: the official TuSimple and CULane metrics on hand-computed cases,
the benchmark files (read, write, round trips, bad input) and ``evaluate tusimple|culane``."""
from __future__ import annotations

import math

import numpy as np
import pytest

from lanelib import evaluate
from lanelib.benchmarks import metrics
from lanelib.benchmarks.metrics import (CULaneCounts, culane_image, interpolate_lane, iou_matrix,
                                        lane_mask, matched_pairs, tusimple_image, tusimple_score)

H = list(range(160, 720, 10))  # 56 rows, TuSimple's h_samples for 1280x720
Y = np.asarray(H, float)


def vertical(x: float, missing_top: int = 0) -> list[float]:
    """A vertical TuSimple lane at ``x``, -2 on the first ``missing_top`` rows."""
    return [-2.0] * missing_top + [float(x)] * (len(H) - missing_top)


def slanted(x0: float, k: float, shift: float = 0.0) -> list[float]:
    """A straight TuSimple lane x = x0 + k*(y - 160) + shift."""
    return list(x0 + k * (Y - 160.0) + shift)


# --------------------------------------------------------------------------- TuSimple metric

def test_evaluate_shares_the_one_point_matching():
    assert evaluate.score_lines is metrics.score_lines
    assert evaluate.line_accuracy is metrics.line_accuracy
    assert evaluate.line_threshold_px is metrics.line_threshold_px


def test_tusimple_perfect_prediction():
    gt = [vertical(x) for x in (200, 500, 800, 1100)]
    assert tusimple_image(gt, gt, H, 10.0) == metrics.TuSimpleImage(1.0, 0.0, 0.0)


@pytest.mark.parametrize("shift, hit", [(19.0, True), (-19.0, True), (21.0, False), (-21.0, False)])
def test_tusimple_vertical_lane_shifted_19_px_is_hit_21_px_missed(shift, hit):
    gt = [vertical(400)]
    r = tusimple_image([vertical(400 + shift)], gt, H)
    # hit: every row within 20 px; missed: no row, the truth lane is FN and the prediction FP
    assert (r.accuracy, r.fp, r.fn) == ((1.0, 0.0, 0.0) if hit else (0.0, 1.0, 1.0))


def test_tusimple_threshold_widens_with_the_slant():
    # x = 300 + y: 45 degrees from vertical, so the hit distance is 20 / cos(45) = 28.28 px
    gt = slanted(300.0, 1.0)
    assert metrics.line_threshold_px(np.asarray(gt), Y) == pytest.approx(20.0 * math.sqrt(2.0))
    assert tusimple_image([slanted(300.0, 1.0, 27.0)], [gt], H).accuracy == 1.0
    assert tusimple_image([slanted(300.0, 1.0, 29.0)], [gt], H).accuracy == 0.0
    # the same 27 px on a vertical lane is a miss
    assert tusimple_image([vertical(327)], [vertical(300)], H).accuracy == 0.0


def test_tusimple_angle_is_fitted_on_the_points_only():
    # -2 rows are left out of the fit: the lane stays at 45 degrees
    gt = np.asarray([-2.0] * 10 + slanted(300.0, 1.0)[10:])
    assert metrics.line_threshold_px(metrics.tusimple_x(gt), Y) == pytest.approx(20.0 * math.sqrt(2.0))


def test_tusimple_counts_every_row_and_rows_without_points_on_both_sides_hit():
    gt = [vertical(400, missing_top=16)]  # 40 labelled rows of 56
    # the prediction has no point where the label has none: 56 of 56 rows hit
    assert tusimple_image([vertical(400, missing_top=16)], gt, H).accuracy == 1.0
    # a prediction that also draws the 16 unlabelled rows misses them: 40 / 56
    r = tusimple_image([vertical(400)], gt, H)
    assert r.accuracy == pytest.approx(40 / 56) and (r.fp, r.fn) == (1.0, 1.0)  # < 0.85
    # a prediction reaching 8 rows less far misses 8 rows: 48 / 56 = 0.857 >= 0.85, matched
    r = tusimple_image([vertical(400, missing_top=24)], gt, H)
    assert r.accuracy == pytest.approx(48 / 56) and (r.fp, r.fn) == (0.0, 0.0)


def test_tusimple_missing_lane():
    gt = [vertical(x) for x in (200, 500, 800, 1100)]
    r = tusimple_image(gt[:3], gt, H)
    assert (r.accuracy, r.fp, r.fn) == (0.75, 0.0, 0.25)


def test_tusimple_extra_lane():
    gt = [vertical(500), vertical(800)]
    r = tusimple_image(gt + [vertical(1100)], gt, H)
    assert (r.accuracy, r.fn) == (1.0, 0.0) and r.fp == pytest.approx(1 / 3)


def test_tusimple_no_prediction():
    r = tusimple_image([], [vertical(500), vertical(800)], H)
    assert (r.accuracy, r.fp, r.fn) == (0.0, 0.0, 1.0)


def test_tusimple_more_than_two_extra_lanes_or_slow_scores_zero():
    gt = [vertical(500), vertical(800)]
    four = gt + [vertical(100), vertical(1100)]
    assert tusimple_image(four, gt, H).accuracy == 1.0  # 2 extra lanes are allowed
    assert tusimple_image(four + [vertical(1200)], gt, H) == metrics.TuSimpleImage(0.0, 0.0, 1.0)
    assert tusimple_image(gt, gt, H, run_time_ms=200.0).accuracy == 1.0
    assert tusimple_image(gt, gt, H, run_time_ms=200.5) == metrics.TuSimpleImage(0.0, 0.0, 1.0)


def test_tusimple_five_labelled_lanes_drop_the_worst_and_one_fn():
    gt = [vertical(x) for x in (100, 350, 600, 850, 1100)]
    r = tusimple_image(gt[:4], gt, H)  # the fifth is missed: accuracy 0, dropped; its FN forgiven
    assert (r.accuracy, r.fp, r.fn) == (1.0, 0.0, 0.0)
    r = tusimple_image(gt[:3], gt, H)  # two missed: (3 + 0 + 0 - 0) / 4, one FN of two forgiven
    assert (r.accuracy, r.fp, r.fn) == (0.75, 0.0, 0.25)


def test_tusimple_wrong_lane_length_is_an_error():
    with pytest.raises(ValueError, match="predicted lane 1 has 3 x values for 56 h_samples"):
        tusimple_image([[1.0, 2.0, 3.0]], [vertical(500)], H)


def test_tusimple_set_divides_by_the_labelled_images():
    a = metrics.TuSimpleImage(1.0, 0.0, 0.0)
    b = metrics.TuSimpleImage(0.5, 0.5, 0.25)
    s = tusimple_score([("a", a), ("b", b)], 2)
    assert (s.accuracy, s.fp, s.fn) == (0.75, 0.25, 0.125)
    assert s.to_dict() == {"benchmark": "tusimple", "images": 2, "Accuracy": 0.75, "FP": 0.25,
                           "FN": 0.125}
    assert "Accuracy  75.00 %" in s.table()


def test_lanelib_mode_scores_only_truth_points():
    # lanelib's own truth (every_row=False): rows without a truth point do not count
    gt = metrics.tusimple_x(vertical(400, missing_top=16))
    assert metrics.line_accuracy(np.asarray(vertical(400), float), gt, 20.0) == 1.0
    assert metrics.line_accuracy(np.asarray(vertical(400), float), gt, 20.0, every_row=True) == \
        pytest.approx(40 / 56)


# --------------------------------------------------------------------------- CULane metric

def strip(x: float) -> np.ndarray:
    """A vertical CULane lane at ``x`` from above the canvas to below it (no end caps inside)."""
    return np.array([[x, -60.0], [x, 650.0]])


def test_culane_draws_31_px_strips_for_30_px_lines():
    m = lane_mask(strip(800))
    assert m.shape == (590, 1640) and set(np.unique(m)) == {0, 1}
    # OpenCV's 30-thick line covers x - 15 .. x + 15: 31 px on every row
    assert (m.sum(axis=1) == 31).all()
    assert np.flatnonzero(m[300]).tolist() == list(range(785, 816))


@pytest.mark.parametrize("d", [0, 5, 10, 11, 20, 31, 40])
def test_culane_iou_of_shifted_strips_is_analytic(d):
    # two 31 px strips d px apart on every row: IoU = (31 - d) / (31 + d), 0 once apart
    expected = max(31 - d, 0) / (31 + d) if d < 31 else 0.0
    assert iou_matrix([strip(800)], [strip(800 + d)])[0, 0] == pytest.approx(expected)


def test_culane_shift_10_px_is_a_match_11_px_is_not():
    # (31 - 10) / 41 = 0.512 > 0.5; (31 - 11) / 42 = 0.476
    assert culane_image([strip(800)], [strip(810)]) == CULaneCounts(1, 0, 0, 1)
    assert culane_image([strip(800)], [strip(811)]) == CULaneCounts(0, 1, 1, 1)


def test_culane_iou_exactly_at_threshold_is_not_a_match():
    assert matched_pairs(np.array([[0.5]])) == 0
    assert matched_pairs(np.array([[0.5001]])) == 1


def test_culane_hungarian_beats_greedy():
    # greedy would pair truth 0 with pred 0 (0.9) and leave truth 1 unmatched (0.1)
    ious = np.array([[0.9, 0.8],
                     [0.7, 0.1]])
    assert matched_pairs(ious) == 2  # 0 - 1 (0.8) and 1 - 0 (0.7)


def test_culane_perfect_missing_and_extra_lanes():
    gt = [strip(300), strip(800), strip(1300)]
    perfect = culane_image(gt, gt)
    assert perfect == CULaneCounts(3, 0, 0, 1) and perfect.f1 == 1.0
    missing = culane_image(gt, gt[:2])
    assert missing == CULaneCounts(2, 0, 1, 1)
    assert (missing.precision, missing.recall) == (1.0, 2 / 3) and missing.f1 == pytest.approx(0.8)
    extra = culane_image(gt[:1], gt[:1] + [strip(1000)])
    assert extra == CULaneCounts(1, 1, 0, 1) and extra.precision == 0.5
    assert culane_image([], gt) == CULaneCounts(0, 3, 0, 1)
    assert culane_image(gt, []) == CULaneCounts(0, 0, 3, 1)


def test_culane_sums_and_zero_denominators():
    total = CULaneCounts(2, 0, 1, 1) + CULaneCounts(1, 1, 0, 1)
    assert total == CULaneCounts(3, 1, 1, 2)
    assert (total.precision, total.recall, total.f1) == (0.75, 0.75, 0.75)
    assert (CULaneCounts().precision, CULaneCounts().recall, CULaneCounts().f1) == (0.0, 0.0, 0.0)
    assert total.to_dict()["F1"] == 0.75 and "F1         75.00 %" in total.table()


def test_culane_lane_of_one_point_matches_nothing():
    assert iou_matrix([np.array([[800.0, 300.0]])], [strip(800)])[0, 0] == 0.0
    assert culane_image([np.array([[800.0, 300.0]])], [strip(800)]) == CULaneCounts(0, 1, 1, 1)


def test_culane_spline_keeps_two_points_and_resamples_more():
    two = np.array([[100.0, 500.0], [300.0, 300.0]])
    assert np.array_equal(interpolate_lane(two), two)
    # collinear points: the natural spline is the straight line, 50 samples per segment + the end
    three = np.array([[100.0, 500.0], [200.0, 400.0], [300.0, 300.0]])
    out = interpolate_lane(three)
    assert out.shape == (101, 2)
    assert np.allclose(out[:, 0] + out[:, 1], 600.0) and np.allclose(out[[0, 50, 100]], three)
    # a bent lane passes through its points, and a repeated point is dropped first
    bent = np.array([[100.0, 500.0], [180.0, 400.0], [300.0, 300.0], [300.0, 300.0]])
    out = interpolate_lane(bent)
    assert out.shape == (101, 2) and np.allclose(out[[0, 50, 100]], bent[:3])


def test_culane_slanted_lane_shifted_along_x():
    # a 45-degree lane shifted 10 px sideways is 7.1 px away across: a match; 30 px is not
    lane = np.array([[400.0, 590.0], [700.0, 290.0], [1000.0, -10.0]])
    near = iou_matrix([lane], [lane + [10.0, 0.0]])[0, 0]
    far = iou_matrix([lane], [lane + [30.0, 0.0]])[0, 0]
    assert near > 0.5 > far > 0.0
