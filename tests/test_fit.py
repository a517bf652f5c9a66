"""Fits and measurements (``fit``): curvature, radius, offset, width, offset lines and parallel
fits, against lines drawn from known geometry."""
from __future__ import annotations

import math

import numpy as np
import pytest

from lanelib.fit import (RADIUS_MAX_M, curvature, fit_line, fit_to_metres, measure, normal_width_m,
                         offset_line, offset_rows_px, parallel_fits, radius, shared_curvature)
from lanelib.params import SearchConfig
from lanelib.records import LineFit

H, W = 720, 1280
XM_DEFAULT, YM_DEFAULT = 0.00578125, 0.03263888888888889  # the default 1280x720 view (m/px)


def test_metric_coefficients_are_an_exact_scaling():
    coeffs = (3e-4, -0.2, 400.0)
    xm, ym = 3.7 / 640, 23.5 / 720
    ys = np.linspace(0, H, 50)
    xs = np.polyval(coeffs, ys)
    refit = np.polyfit(ys * ym, xs * xm, 2)
    np.testing.assert_allclose(fit_to_metres(coeffs, xm, ym), refit, rtol=1e-8)


@pytest.mark.parametrize("radius_m,direction", [(300.0, 1), (1000.0, -1), (150.0, -1)])
def test_radius_of_a_circle_is_returned_in_metres(radius_m, direction):
    xm, ym = 3.7 / 640, 23.5 / 720
    # a circle in metres tangent to the vertical at the car (bottom row), bending left or right
    y_m = np.arange(H) * ym
    y_car = (H - 1) * ym
    dy = y_car - y_m
    x_m = 3.0 + direction * (radius_m - np.sqrt(radius_m ** 2 - dy ** 2))
    coeffs_px = np.polyfit(np.arange(H), x_m / xm, 2)
    k = curvature(fit_to_metres(coeffs_px, xm, ym), y_car)
    assert k == pytest.approx(direction / radius_m, rel=0.02)
    assert radius(k) == pytest.approx(radius_m, rel=0.02)


def test_offset_width_and_sign_conventions():
    xm, ym = 3.7 / 640, 23.5 / 720
    # lane from x=300 to x=940: centre 620; the car at 640 is 20 px right of centre
    left, right = LineFit((0.0, 0.0, 300.0), 1000, 700.0), LineFit((0.0, 0.0, 940.0), 1000, 700.0)
    m = measure(left, right, H, 640.0, xm, ym)
    assert m.offset_m == pytest.approx(20 * xm) and m.offset_m > 0
    assert m.lane_width_m == pytest.approx(3.7)
    assert m.curvature_per_m == 0 and m.radius_m == RADIUS_MAX_M


def test_too_few_pixels_and_short_span_are_not_found():
    cfg = SearchConfig(min_line_pixels=150)
    ys, xs = np.arange(700, 710), np.full(10, 300)
    fit = fit_line(ys, xs, H, cfg)
    assert not fit.found and "only 10 lane pixels" in fit.reason
    ys, xs = np.repeat(np.arange(700, 720), 20), np.tile(np.arange(300, 320), 20)
    fit = fit_line(ys, xs, H, cfg)
    assert not fit.found and "span only" in fit.reason


def test_short_span_is_fitted_straight():
    ys = np.repeat(np.arange(500, 640), 5)  # 140 px: above min_found_span, below min_span
    xs = 300 + 0.1 * ys
    fit = fit_line(ys, xs, H)
    assert fit.found and fit.coeffs_px[0] == 0.0 and fit.coeffs_px[1] == pytest.approx(0.1)


def test_offset_is_read_on_the_bottom_row():
    xm, ym = 3.7 / 640, 23.5 / 720
    # a lane centred on the car's column at the bottom row, seen at a heading (0.05 px/px)
    b = 0.05
    left = LineFit((0.0, b, 320.0 - b * (H - 1)), 1000, 700.0)
    right = LineFit((0.0, b, 960.0 - b * (H - 1)), 1000, 700.0)
    assert measure(left, right, H, 640.0, xm, ym).offset_m == pytest.approx(0.0, abs=1e-9)


def test_lane_curvature_follows_the_better_supported_line():
    xm, ym = 3.7 / 640, 23.5 / 720
    strong = LineFit((2e-4, -0.3, 300.0), 20000, 719.0)
    weak = LineFit((-6e-4, 0.5, 700.0), 200, 90.0)  # one dash, fitted with the wrong bend
    m = measure(strong, weak, H, 640.0, xm, ym)
    assert m.curvature_per_m == pytest.approx(m.left_curvature_per_m, rel=0.02)
    assert np.sign(m.curvature_per_m) == np.sign(m.left_curvature_per_m) != np.sign(m.right_curvature_per_m)


def test_outlier_trimming_recovers_a_parabola_that_the_plain_fit_misses():
    truth = (2e-4, -0.3, 500.0)
    ys = np.repeat(np.arange(H), 2).astype(np.float64)
    xs = np.polyval(truth, ys)
    xs[::20] += 250.0  # 5 % far outliers, all on one side
    plain = fit_line(ys, xs, H)
    trimmed = fit_line(ys, xs, H, SearchConfig(trim_outliers_pct=95))
    assert abs(plain.coeffs_px[2] - truth[2]) > 5  # the plain fit is pulled 12 px aside
    np.testing.assert_allclose(trimmed.coeffs_px, truth, rtol=1e-6, atol=1e-9)
    assert trimmed.n_pixels == len(ys) - len(ys[::20]) and trimmed.scatter_px < 1e-6
    # 0 and 100 keep every pixel: the plain fit
    for pct in (0.0, 100.0):
        assert fit_line(ys, xs, H, SearchConfig(trim_outliers_pct=pct)) == plain


def circle_fit_px(cx_m: float, radius_m: float) -> tuple[float, float, float]:
    """Return the parabola (px) fitted over the view to the arc x = cx - sqrt(R**2 - (y - y0)**2)
    (metres), tangent to the view's columns on its bottom row y0: a right bend of radius R."""
    ys = np.arange(H, dtype=np.float64)
    dy = (ys - (H - 1)) * YM_DEFAULT
    xs = (cx_m - np.sqrt(radius_m ** 2 - dy ** 2)) / XM_DEFAULT
    return tuple(np.polyfit(ys, xs, 2))


def test_offset_line_is_the_concentric_arc_not_a_shifted_copy():
    """A line on an 80 m right bend (its centre 80 m right of it) moved 3.7 m along its normal to
    the right is the concentric arc of radius 76.3 m: within 3 cm over the whole 23.5 m view, where
    the same line shifted 3.7 m in x is 0.18 m off at the view's top."""
    cx = 1.85 + 80.0
    line = circle_fit_px(cx, 80.0)
    truth = circle_fit_px(cx, 80.0 - 3.7)
    moved = offset_line(line, 3.7, XM_DEFAULT, YM_DEFAULT, H)
    ys = np.arange(0, H, 10, dtype=np.float64)
    err_m = np.abs(np.polyval(moved, ys) - np.polyval(truth, ys)) * XM_DEFAULT
    assert err_m.max() < 0.03
    shifted_err_m = abs(np.polyval(line, 0.0) + 3.7 / XM_DEFAULT - np.polyval(truth, 0.0)) * XM_DEFAULT
    assert shifted_err_m > 0.15
    # a straight line is moved by exactly its offset; moving back returns it
    straight = (0.0, 0.0, 320.0)
    assert offset_line(straight, 3.7, XM_DEFAULT, YM_DEFAULT, H) == pytest.approx(
        (0.0, 0.0, 320.0 + 3.7 / XM_DEFAULT), abs=1e-6)
    back = offset_line(moved, -3.7, XM_DEFAULT, YM_DEFAULT, H)
    assert np.abs(np.polyval(back, ys) - np.polyval(line, ys)).max() * XM_DEFAULT < 0.01


def test_normal_width_is_the_width_across_a_slanted_lane():
    """Two straight lines heading 0.3 rad off the view's axis, 3.5 m apart across the lane, are
    3.5 / cos(0.3) = 3.66 m apart on a row; ``normal_width_m`` gives 3.5 m."""
    slope_px = math.tan(0.3) * YM_DEFAULT / XM_DEFAULT  # dx/dy in px per px
    gap_px = 3.5 / math.cos(0.3) / XM_DEFAULT
    left, right = (0.0, -slope_px, 400.0), (0.0, -slope_px, 400.0 + gap_px)
    assert normal_width_m(left, right, H - 1, XM_DEFAULT, YM_DEFAULT) == pytest.approx(3.5, abs=1e-6)
    assert (right[2] - left[2]) * XM_DEFAULT == pytest.approx(3.66, abs=0.01)


def test_offset_line_takes_a_distance_per_row():
    """A straight line moved by a distance that grows from 3.5 m on the bottom row to 4.5 m on
    the top one (a lane the flat view widens ahead) is the straight line through those points."""
    rows = offset_rows_px(H)
    offset = 3.5 + (H - 1 - rows) / (H - 1)
    moved = offset_line((0.0, 0.0, 320.0), offset, XM_DEFAULT, YM_DEFAULT, H)
    assert np.polyval(moved, H - 1) == pytest.approx(320.0 + 3.5 / XM_DEFAULT, abs=0.5)
    assert np.polyval(moved, 0.0) == pytest.approx(320.0 + 4.5 / XM_DEFAULT, abs=0.5)
    widths = normal_width_m((0.0, 0.0, 320.0), moved, rows, XM_DEFAULT, YM_DEFAULT)
    assert np.abs(widths - offset).max() < 0.01


YM_VIEW = 0.03263888888888889  # the default 1280 x 720 view's metres per row


LANE_LINES = (np.array([0.0, 0.0, 420.0]), np.array([0.0, 0.0, 860.0]))


def _arc_pixels(radius_m: float, rows: np.ndarray, x0_px: float = 900.0, thickness_px: int = 20):
    """Pixels (ys, xs) of a line on a circle of ``radius_m`` (a right bend) on ``rows``, the
    bottom row at ``x0_px``, ``thickness_px`` wide: the exact circle, not a parabola."""
    d = (H - 1 - rows) * YM_DEFAULT
    x = x0_px + (radius_m - np.sqrt(radius_m ** 2 - d ** 2)) / XM_DEFAULT
    offsets = np.arange(thickness_px) - (thickness_px - 1) / 2
    ys = np.repeat(rows, thickness_px)
    xs = np.round((x[:, None] + offsets[None, :]).ravel()).astype(np.int64)
    return ys.astype(np.int64), xs, x


def test_a_short_line_keeps_a_resolved_bend_in_a_look_ahead_and_a_dash_stays_straight():
    rows = np.arange(520, H)  # 200 rows, 6.5 m: below min_span_fraction (216 rows)
    ys, xs, x = _arc_pixels(35.0, rows)
    sc = SearchConfig()
    bowed = fit_line(ys, xs, H, sc, top_px=432)
    assert bowed.coeffs_px[0] > 0
    assert np.abs(bowed.x_at(rows) - x).max() < 2.0  # px: the arc over its span
    whole = fit_line(ys, xs, H, sc)  # the whole view (no look-ahead): straight as before
    assert whole.coeffs_px[0] == 0.0 and np.abs(whole.x_at(rows) - x).max() > 8.0
    off = fit_line(ys, xs, H, SearchConfig(short_bend_resolution=0.0), top_px=432)
    assert off.coeffs_px[0] == 0.0
    # a dash on a gentle 1 km bend bows by a fraction of a pixel over its 3 m: straight
    ys, xs, _ = _arc_pixels(1000.0, np.arange(628, H))
    assert fit_line(ys, xs, H, sc, top_px=432).coeffs_px[0] == 0.0


def test_two_short_lines_share_one_curvature_fitted_to_both():
    a = 2.5e-3
    left_rows, right_rows = np.arange(560, H), np.arange(500, 700)
    lx = a * left_rows ** 2.0 - 3.0 * left_rows + 1400.0
    rx = a * right_rows ** 2.0 - 3.3 * right_rows + 2200.0
    left = LineFit((0.0, 0.1, 10.0), len(left_rows), 159.0)
    right = LineFit((1e-3, 0.0, 0.0), len(right_rows), 199.0)
    l2, r2 = shared_curvature(left, right, (left_rows, lx), (right_rows, rx), H)
    assert l2.coeffs_px == pytest.approx((a, -3.0, 1400.0), rel=1e-6)
    assert r2.coeffs_px == pytest.approx((a, -3.3, 2200.0), rel=1e-6)
    assert l2.scatter_px == pytest.approx(0.0, abs=1e-4) and l2.n_pixels == left.n_pixels
    # parallel_fits: two short lines of which one bows share the curvature; two straight
    # short lines are left as they are
    s2 = parallel_fits(left, right, (left_rows, lx), (right_rows, rx), H)
    assert s2[0].coeffs_px[0] == s2[1].coeffs_px[0] == pytest.approx(a)
    straight = (LineFit((0.0, 0.1, 10.0), 100, 159.0), LineFit((0.0, 0.0, 900.0), 100, 199.0))
    assert parallel_fits(*straight, (left_rows, lx), (right_rows, rx), H) == straight
