"""Lane-pixel search, fits and measurements against masks drawn from known geometry."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from lanelib.checks import pair_problem
from lanelib.errors import ConfigError
from lanelib.fit import RADIUS_MAX_M, curvature, fit_line, fit_to_metres, measure, normal_width_m, offset_line, offset_rows_px, parallel_fits, radius, shared_curvature
from lanelib.params import LaneChecks, SearchConfig
from lanelib.records import LineFit
from lanelib.roads.edge import road_view_interior, road_view_top_px
from lanelib.roads.stripes import inner_stripe, stripe_spacing_px, two_stripes
from lanelib.search import base_peak_confidence, candidate_bases, find_bases, fit_side, histogram, lane_pixels, search_around, sliding_windows

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


def test_missing_line_is_reported_not_raised():
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 350.0))
    search = sliding_windows(m)
    assert search.left.found and not search.right.found
    assert "no lane pixels right of the car" in search.right.reason
    meas = measure(search.left, search.right, H, 640.0, 0.005, 0.03)
    assert math.isnan(meas.offset_m) and math.isnan(meas.radius_m) and not math.isnan(meas.left_curvature_per_m)


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


def test_empty_mask_finds_nothing_and_says_why():
    search = sliding_windows(np.zeros((H, W), np.uint8))
    assert not search.left.found and not search.right.found
    assert search.bases_px == (None, None)


def test_histogram_and_bases():
    m = lane_mask((0, 0, 300.0), (0, 0, 1000.0), thickness=1)
    hist = histogram(m, 0.5)
    assert hist[300] == H // 2 and hist[1000] == H // 2
    assert find_bases(hist, 640) == (300.0, 1000.0)


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


def test_a_line_with_no_pixels_in_the_lower_half_is_searched_from_the_whole_histogram():
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 320.0))
    cv2.line(m, (960, 100), (960, 300), 255, 24)  # one far dash, nothing below row 300
    search = sliding_windows(m)
    assert search.bases_px[1] == pytest.approx(960, abs=12)
    assert search.right.found and search.right.x_at(200) == pytest.approx(960, abs=2)


# --------------------------------------------------------------------------- the seeds' switches

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
    # two stripes 50 px apart on every row also pass for a double line: its inner stripe is kept
    double = sliding_windows(m, SearchConfig(), bases=(280.0, 1000.0))
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


def test_candidate_bases_are_the_strongest_peaks_each_side_one_per_line():
    hist = np.zeros(1280, np.int64)
    for x, height, width in ((100, 50, 20), (300, 80, 20), (700, 60, 20), (900, 90, 20), (1100, 20, 20)):
        hist[x - width // 2:x + width // 2] = height
        hist[x] = height + 1  # each line's own peak column
    left, right = candidate_bases(hist, 640.0, 2, 80)
    assert left == [300.0, 100.0] and right == [900.0, 700.0]
    assert candidate_bases(hist, 640.0, 5, 80) == ([300.0, 100.0], [900.0, 700.0, 1100.0])
    assert candidate_bases(np.zeros(100, np.int64), 50.0, 3, 10) == ([], [])
    with pytest.raises(ConfigError, match="candidates 0 must be 1"):
        SearchConfig(candidates=0)


# --------------------------------------------------------------------------- country roads (issue 16)

XM_DEFAULT, YM_DEFAULT = 0.00578125, 0.03263888888888889  # the default 1280x720 view (m/px)


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


def double_line_mask(inner_x: float, outer_x: float, right_x: float = 960.0) -> np.ndarray:
    """Return a mask with a double line (stripes 21 px wide at ``inner_x`` and ``outer_x``, bottom
    row, on a gentle curve) on the left and one line at ``right_x``."""
    m = np.zeros((H, W), np.uint8)
    for x in (inner_x, outer_x, right_x):
        draw_curve(m, (1e-4, -0.05, x + 0.05 * (H - 1) - 1e-4 * (H - 1) ** 2), 21)
    return m


def test_a_double_line_is_fitted_to_its_inner_stripe():
    """Stripes 38 px apart (0.22 m): the left line is fitted to the stripe nearer the lane, as the
    truth marks a double centre line; with the switch off the fit runs between the stripes."""
    mask = double_line_mask(338.0, 300.0)
    on = sliding_windows(mask)
    assert on.left.x_at(H - 1) == pytest.approx(338.0, abs=2)
    assert on.right.x_at(H - 1) == pytest.approx(960.0, abs=2)  # one stripe: unchanged
    off = sliding_windows(mask, SearchConfig(double_line_px=0))
    assert off.left.x_at(H - 1) == pytest.approx(319.0, abs=3)
    # a double line on the right: its inner stripe is its left one
    ys, xs = lane_pixels(double_line_mask(960.0, 998.0, right_x=320.0))
    keep = xs > 640
    iy, ix = inner_stripe(ys[keep], xs[keep], "right", 38.0, H)
    assert fit_line(iy, ix, H).x_at(H - 1) == pytest.approx(960.0, abs=2)
    assert fit_line(ys[keep], xs[keep], H).x_at(H - 1) == pytest.approx(979.0, abs=3)


@pytest.mark.parametrize("spacing_m", [0.22, 0.3])
def test_a_double_line_on_a_hairpin_is_split_at_its_stripes(spacing_m):
    """A double line (stripes 0.12 m wide, 0.22 or 0.3 m apart centre to centre) on a 25 m
    hairpin, seen only on the view's lowest 160 rows and heading 0.2 rad off the view's axis (as
    a country road's centre line leaves the view on a hairpin): one straight fit through its
    pixels misses the bend, and split at that fit's residuals the stripes run into each other.
    Fitted as two stripes sharing one curve (``two_stripes``), the inner one is kept whole."""
    a = 1 / (2 * 25.0 * XM_DEFAULT / YM_DEFAULT ** 2)  # 25 m radius
    b = -1.2 - 2 * a * (H - 1)  # slope -1.2 px/px on the bottom row
    bend = (a, b, 300.0 - a * (H - 1) ** 2 - b * (H - 1))
    spacing, width = spacing_m / XM_DEFAULT, int(round(0.12 / XM_DEFAULT))
    m = np.zeros((H, W), np.uint8)
    for y in range(560, H):
        for side in (-0.5, 0.5):
            lo = int(round(np.polyval(bend, y) + side * spacing - width / 2))
            m[y, lo:lo + width] = 255
    ys, xs = lane_pixels(m)
    iy, ix = inner_stripe(ys, xs, "left", 38.0, H)
    assert len(iy) == len(ys) // 2 and (ix > np.polyval(bend, iy)).all()
    coeffs, spaced, upper, rss = two_stripes(ys, xs, 2, H)
    assert np.median(spaced) == pytest.approx(spacing, abs=1.5)
    assert math.sqrt(rss / len(ys)) == pytest.approx(width / math.sqrt(12), abs=0.5)


@pytest.mark.parametrize("gap_px", [0.0, 90.0])
def test_one_line_or_stripes_too_far_apart_are_left_whole(gap_px):
    """A single line (no second stripe), and two lines 90 px (0.52 m) apart, over 1.5x the 38 px
    spacing, are not a double line: every pixel is kept."""
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 400.0), 21)
    if gap_px:
        draw_curve(m, (0.0, 0.0, 400.0 - gap_px), 21)
    ys, xs = lane_pixels(m)
    out = inner_stripe(ys, xs, "left", 38.0, H)
    assert len(out[0]) == len(ys)


def blurred_double_line(inner_x: float, clear_from: int, blob_px: int = 80, single: bool = False,
                        lean_px: float = 0.0) -> np.ndarray:
    """Return a mask with a double line on a gentle curve, its inner stripe at ``inner_x`` on the
    bottom row (stripes 21 px wide, 38 px apart centre to centre: 0.12 m and 0.22 m), resolved
    from the bottom row up to row ``clear_from`` and, above it, blurred into one blob ``blob_px``
    wide centred between the stripes (far ahead a few raw pixels hold both stripes, as on
    country.mp4); ``single``: one stripe alone, widening alike far ahead; ``lean_px``: the blob
    centred that far right of the stripes' middle. A line at x = 960 on the right."""
    bend = (1e-4, -0.05, inner_x + 0.05 * (H - 1) - 1e-4 * (H - 1) ** 2)
    m = np.zeros((H, W), np.uint8)
    for y in range(H):
        x = np.polyval(bend, y)
        if y < clear_from:
            centre = (x if single else x - 19.0) + lean_px
            m[y, int(round(centre - blob_px / 2)):int(round(centre + blob_px / 2))] = 255
        else:
            for stripe in ((x,) if single else (x, x - 38.0)):
                m[y, int(round(stripe - 10.5)):int(round(stripe + 10.5))] = 255
    draw_curve(m, (0.0, 0.0, 960.0), 21)
    return m


@pytest.mark.parametrize("clear_from", [300, 420])
def test_a_double_line_blurred_ahead_is_fitted_to_its_inner_stripe_at_the_car(clear_from):
    """A double line resolved on the view's lower 300-420 rows (10-14 m of road) and blurred into
    one blob beyond: the blob fills the gap, so the line as a whole is not two stripes, and one
    fit through all its pixels runs between the stripes, 19 px (0.11 m) off the inner stripe at
    the car. The near rows, where the stripes are resolved, are narrowed to the inner stripe
    and the blurred rows left out (neither split by a guess nor kept whole, which would pull
    the fit 7 px, 0.04 m, off at the car): the fit lies within 2 px (0.012 m) of the inner
    stripe on the bottom row and on the rows it rests on."""
    mask = blurred_double_line(338.0, clear_from)
    between = sliding_windows(mask, SearchConfig(double_line_px=0))
    assert abs(between.left.x_at(H - 1) - 338.0) * XM_DEFAULT > 0.1
    on = sliding_windows(mask)
    assert abs(on.left.x_at(H - 1) - 338.0) < 2
    assert on.right.x_at(H - 1) == pytest.approx(960.0, abs=2)  # one stripe: unchanged
    ys, xs = on.left_pixels
    assert ys.min() >= clear_from  # the blurred rows are left out
    bend = (1e-4, -0.05, 338.0 + 0.05 * (H - 1) - 1e-4 * (H - 1) ** 2)
    rows = np.arange(clear_from, H)
    assert np.abs(on.left.x_at(rows) - np.polyval(bend, rows)).max() < 2
    assert (np.abs(xs - np.polyval(bend, ys)) <= 11).all()  # the inner stripe's pixels only


def test_a_stub_of_inner_stripe_does_not_replace_the_whole_line():
    """Resolved only on the lowest 180 rows (a quarter of the view, under ``min_span_fraction``),
    a double line's inner stripe would be fitted straight, its curve unmeasured: ``fit_side``
    keeps the fit of the whole line (between the stripes, as before) rather than that stub."""
    ys, xs = lane_pixels(blurred_double_line(338.0, 540))
    keep = xs < 640
    ys, xs = ys[keep], xs[keep]
    assert len(inner_stripe(ys, xs, "left", 38.0, H)[0]) < len(ys)  # a stub of inner stripe
    fit, used = fit_side((ys, xs), "left", H, SearchConfig(), "none")
    assert len(used[0]) == len(ys)
    assert fit.coeffs_px == fit_line(ys, xs, H).coeffs_px


@pytest.mark.parametrize("lean_px", [40.0, -40.0])
def test_near_rows_are_judged_on_their_own_stripes_when_the_blur_bends_the_curve(lean_px):
    """A blob leaning 40 px to one side of the stripes ahead pulls the curve fitted to the whole
    line 14 px off the stripes' middle at the car, where the residuals of the resolved near rows
    then show neither two narrow stripes nor a clear gap. Each band of rows is also judged by
    its own pixels (two straight stripes fitted to them): the near rows are resolved, and the
    line is fitted to its inner stripe within 1 px at the car (through the blob and both
    stripes before: 36 and 3 px off)."""
    ys, xs = lane_pixels(blurred_double_line(338.0, 420, lean_px=lean_px))
    keep = xs < 640
    ys, xs = ys[keep], xs[keep]
    fit, used = fit_side((ys, xs), "left", H, SearchConfig(), "none")
    assert used[0].min() >= 420  # the blob is left out
    assert abs(fit.x_at(H - 1) - 338.0) < 1


def test_a_short_patch_of_double_line_is_not_fitted_through_both_stripes():
    """A double line resolved as a whole but seen only on 50 rows, with one stray pixel on the
    bottom row lending the whole its span: its inner stripe spans too little to be found, and
    the line is not found, not fitted through both stripes (between them, and bent towards the
    stray pixel: edge46_s77.mp4 frame 84, 134 px off at the car in the raw image, after which
    the track was lost for 40 frames)."""
    mask = np.zeros((H, W), np.uint8)
    for y in range(600, 650):
        for stripe in (338.0, 300.0):
            mask[y, int(round(stripe - 10.5)):int(round(stripe + 10.5))] = 255
    mask[H - 1, 300] = 255
    ys, xs = lane_pixels(mask)
    whole = fit_line(ys, xs, H)
    assert whole.found  # the stray pixel lends the patch a span of 119 px
    assert inner_stripe(ys, xs, "left", 38.0, H)[0].max() < 650  # resolved as a whole
    fit, used = fit_side((ys, xs), "left", H, SearchConfig(), "none", top_px=432)
    assert not fit.found and "span" in fit.reason
    assert (np.abs(used[1] - 338) <= 11).all()


def test_a_single_line_or_a_double_line_blurred_at_the_car_is_left_whole():
    """One stripe widening into a blob ahead is a single line, and a double line blurred on all
    but the lowest band of rows shows no resolved run of rows at the car: both are returned
    whole (no stripe is guessed where the stripes are not resolved)."""
    for mask in (blurred_double_line(338.0, 300, single=True), blurred_double_line(338.0, 680)):
        ys, xs = lane_pixels(mask)
        keep = xs < 640
        out = inner_stripe(ys[keep], xs[keep], "left", 38.0, H)
        assert len(out[0]) == np.count_nonzero(keep)
    single = sliding_windows(blurred_double_line(338.0, 300, single=True))
    assert single.left.x_at(H - 1) == pytest.approx(338.0, abs=2)


def test_double_line_spacing_is_validated():
    with pytest.raises(ConfigError, match="double_line_px"):
        SearchConfig(double_line_px=-1)


def test_a_grade_spread_that_the_track_already_has_passes_the_pair_check():
    """Lines that spread 1 m apart over the view (the flat view of a road climbing ahead) fail
    the parallel check on their own, and pass it against a tracked width that spreads alike."""
    spread = 1.0 / XM_DEFAULT  # 1 m in px, from the bottom row to the top
    left, right = LineFit((0.0, 0.0, 320.0)), LineFit((0.0, -spread / (H - 1), 960.0 + spread))
    checks = LaneChecks()
    alone = pair_problem(left, right, H, XM_DEFAULT, YM_DEFAULT, checks)
    assert alone.startswith("lines not parallel")
    rows = np.linspace(0.0, H - 1.0, checks.check_rows)
    reference = np.polyval(right.coeffs_px, rows) - np.polyval(left.coeffs_px, rows)
    assert pair_problem(left, right, H, XM_DEFAULT, YM_DEFAULT, checks,
                        width_reference_px=reference) == ""
    # a reference that does not spread: refused as before
    flat = np.full(len(rows), 640.0)
    assert pair_problem(left, right, H, XM_DEFAULT, YM_DEFAULT, checks,
                        width_reference_px=flat).startswith("lines not parallel")


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


def test_stripe_spacing_is_measured_per_band_of_rows():
    """Two stripes 38 px apart at the bottom row and 57 px at the top (a flat view spreading the
    road ahead): the spacing is read on each band of rows; one stripe alone gives no band."""
    m = np.zeros((H, W), np.uint8)
    draw_curve(m, (0.0, 0.0, 400.0), 15)
    ys = np.arange(H)
    outer = 400.0 - (38.0 + 19.0 * (H - 1 - ys) / (H - 1))
    pts = np.column_stack([outer, ys]).round().astype(np.int32)
    cv2.polylines(m, [pts.reshape(-1, 1, 2)], False, 255, 15)
    rows, gaps = stripe_spacing_px(m, (0.0, 0.0, 400.0), 38.0)
    assert len(rows) == 8
    assert gaps == pytest.approx(38.0 + 19.0 * (H - 1 - rows) / (H - 1), abs=2.0)
    single = np.zeros((H, W), np.uint8)
    draw_curve(single, (0.0, 0.0, 400.0), 15)
    assert len(stripe_spacing_px(single, (0.0, 0.0, 400.0), 38.0)[0]) == 0


# --------------------------------------------------------------------------- the road seen from the car

YM_VIEW = 0.03263888888888889  # the default 1280 x 720 view's metres per row


def _drawn_view(crest_px: int | None, shadows: bool, seed: int = 3) -> np.ndarray:
    """A drawn 1280 x 720 bird's-eye view: grey asphalt with grain, a straight lane between x 420
    and 860, grass (saturated green) above ``crest_px`` (None: road to the top), and with
    ``shadows`` dark bluish shadow bands across the whole road (a tree's, a bridge's)."""
    rng = np.random.default_rng(seed)
    h, w = 720, 1280
    grey = rng.normal(105, 12, (h, w, 1)).clip(0, 255)
    view = np.repeat(grey, 3, axis=2) + rng.normal(0, 3, (h, w, 3))
    if shadows:
        for y0 in (80, 250, 420, 560):
            view[y0:y0 + 60] = view[y0:y0 + 60] * 0.3 + np.array([0.0, 3.0, 12.0])
    if crest_px is not None:
        grass = np.array([96.0, 120.0, 60.0]) * rng.uniform(0.6, 1.2, (crest_px, w, 1))
        view[:crest_px] = grass
    view[:, 412:428] = view[:, 852:868] = 230  # the painted lines
    return view.clip(0, 255).astype(np.uint8)


LANE_LINES = (np.array([0.0, 0.0, 420.0]), np.array([0.0, 0.0, 860.0]))


@pytest.mark.parametrize("crest_px", [200, 360, 520])
@pytest.mark.parametrize("shadows", [False, True])
def test_the_road_view_ends_at_a_drawn_crest_and_a_shadowed_road_keeps_the_whole_view(crest_px, shadows):
    """Grass beyond a crest ends the look-ahead on the sampled row just below it (within one
    sample, 8 rows = 0.26 m, never beyond it), with or without shadows on the road; a shadowed
    road without a crest keeps the whole view (0): a shadow keeps the road's low saturation."""
    rows = np.arange(719, -1, -8)
    for crest in (crest_px, None):
        view = _drawn_view(crest, shadows)
        top = road_view_top_px(view[rows], rows, LANE_LINES, YM_VIEW, 0.15, 1.0)
        if crest is None:
            assert top == 0
        else:
            assert crest <= top <= crest + 8


def test_the_road_view_reads_only_the_lane_interior_and_needs_a_run_of_rows():
    """Grass beside the lane (outside the lines), a patch of dirt across the lane shorter than
    ``run_m``, and a view sampled over only some columns (``col0_px``) leave the whole view."""
    view = _drawn_view(None, True)
    view[:, :380] = (96, 120, 60)
    view[:, 900:] = (96, 120, 60)
    view[300:316] = (140, 110, 60)  # 0.5 m of dirt across the road
    rows = np.arange(719, -1, -8)
    assert road_view_top_px(view[rows], rows, LANE_LINES, YM_VIEW, 0.15, 1.0) == 0
    assert road_view_top_px(view[rows], rows, LANE_LINES, YM_VIEW, 0.15, 0.3) == 319  # the row below it
    lo, hi = road_view_interior(rows, LANE_LINES, 1280)
    assert lo.min() == 530 and hi.max() == 750
    crest = _drawn_view(400, False)
    part = crest[rows, 500:800]
    assert road_view_top_px(part, rows, LANE_LINES, YM_VIEW, 0.15, 1.0, 1280, 500) == 407


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
