"""The hard-road parts (``roads``): double lines read at their inner stripe (``roads.stripes``),
the road seen ahead (``roads.edge.road_view_top_px``) and the other histogram peaks
(``roads.fallbacks.candidate_bases``), on drawn masks and views."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from lanelib.errors import ConfigError
from lanelib.fit import fit_line
from lanelib.params import SearchConfig
from lanelib.roads.edge import road_view_interior, road_view_top_px
from lanelib.roads.fallbacks import candidate_bases
from lanelib.roads.stripes import inner_stripe, stripe_spacing_px, two_stripes
from lanelib.search import fit_side, lane_pixels, sliding_windows

H, W = 720, 1280
XM_DEFAULT, YM_DEFAULT = 0.00578125, 0.03263888888888889  # the default 1280x720 view (m/px)
# the inner stripe of a double line switched on (``double_line_px``, off by default; 38 px in the
# ``hard-roads`` preset): what the search and fits of these tests are about
DOUBLE = SearchConfig(double_line_px=38.0)


def draw_curve(mask, coeffs, thickness=20):
    ys = np.arange(H)
    pts = np.column_stack([np.polyval(coeffs, ys), ys]).round().astype(np.int32)
    cv2.polylines(mask, [pts.reshape(-1, 1, 2)], False, 255, thickness)
    return mask


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
    on = sliding_windows(mask, DOUBLE)
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
    on = sliding_windows(mask, DOUBLE)
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
    fit, used = fit_side((ys, xs), "left", H, DOUBLE, "none")
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
    fit, used = fit_side((ys, xs), "left", H, DOUBLE, "none")
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
    fit, used = fit_side((ys, xs), "left", H, DOUBLE, "none", top_px=432)
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
    single = sliding_windows(blurred_double_line(338.0, 300, single=True), DOUBLE)
    assert single.left.x_at(H - 1) == pytest.approx(338.0, abs=2)


def test_double_line_spacing_is_validated():
    with pytest.raises(ConfigError, match="double_line_px"):
        SearchConfig(double_line_px=-1)


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
