"""The plausibility checks every found lane passes (params.LaneChecks), in one image or a video.

Known answers on drawn masks and fits (width, parallel, curvature, band fill, scatter), the
result a rejected frame gives (not found, the reason, the rejected measurement kept apart), and
images that hold no lane at all: noise, blobs, stripes, flat grey, a chessboard, black frames.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import cv2
import numpy as np
import pytest

from lanelib import draw, io
from lanelib.batch import process_images
from lanelib.checks import LaneCheck, check_lane, line_problem, pair_problem, search_bands_px
from lanelib.config import PipelineConfig
from lanelib.errors import ConfigError
from lanelib.fit import fit_line
from lanelib.params import LaneChecks, SearchConfig
from lanelib.perspective import PerspectiveConfig
from lanelib.pipeline import LanePipeline
from lanelib.records import LaneSearch, LineFit, Window
from lanelib.roads.stripes import two_stripes
from lanelib.search import lane_pixels, search_around, sliding_windows
from lanelib.tracking import LaneTracker

H, W = 720, 1280
XM_DEFAULT, YM_DEFAULT = 0.00578125, 0.03263888888888889  # the default 1280x720 view (m/px)
XM, YM = PerspectiveConfig().xm_per_px, PerspectiveConfig().ym_per_px
CAR_X = 640.0


def number_after(text: str, prefix: str) -> float:
    """Return the number that follows ``prefix`` in ``text``."""
    return float(re.search(re.escape(prefix) + r"(-?[0-9.]+)", text).group(1))


def lane_mask(left, right, thickness: int = 20) -> np.ndarray:
    """Return a bird's-eye 0/255 mask with the parabolas x = f(y) (pixel coefficients) drawn."""
    m = np.zeros((H, W), np.uint8)
    ys = np.arange(H)
    for coeffs in (left, right):
        pts = np.column_stack([np.polyval(coeffs, ys), ys]).round().astype(np.int32)
        cv2.polylines(m, [pts.reshape(-1, 1, 2)], False, 255, thickness)
    return m


def check_mask(mask: np.ndarray) -> LaneCheck:
    """Return the checks of the sliding-window search of a bird's-eye mask (default geometry)."""
    s = sliding_windows(mask, car_x=CAR_X)
    assert s.left.found and s.right.found
    return check_lane(s.left, s.right, search_bands_px(s, (W, H)), H, XM, YM)


def parabolas(width_m: float, a: float = 1.5e-4, b: float = -0.2):
    """Return left and right pixel coefficients of two parallel parabolas ``width_m`` apart at the car."""
    half = width_m / XM / 2
    c = CAR_X - (a * (H - 1) ** 2 + b * (H - 1))  # centre line through the car's x on the bottom row
    return (a, b, c - half), (a, b, c + half)


# --------------------------------------------------------------------------- known answers

def test_two_parallel_parabolas_3_7_m_apart_pass():
    check = check_mask(lane_mask(*parabolas(3.7)))
    assert check.ok and check.reason == ""


@pytest.mark.parametrize("width_m", [2.0, 6.0])
def test_a_lane_too_narrow_or_too_wide_fails_with_its_width(width_m):
    check = check_mask(lane_mask(*parabolas(width_m)))
    assert check.left == check.right == ""
    assert "m at the car outside 3.0-4.5 m" in check.pair
    assert number_after(check.pair, "lane width ") == pytest.approx(width_m, abs=0.03)


def test_converging_lines_are_not_parallel():
    # 3.7 m apart at the car, 1.2 m apart at the top of the view
    lean = (2.5 / XM) / 2 / (H - 1)
    left = (0.0, -lean, 320.0 + lean * (H - 1))
    right = (0.0, lean, 960.0 - lean * (H - 1))
    check = check_mask(lane_mask(left, right))
    assert check.pair.startswith("lines not parallel (width varies by ")
    assert number_after(check.pair, "width varies by ") == pytest.approx(2.5, abs=0.05)


def test_crossing_lines_are_refused_where_they_cross():
    # 3.7 m apart at the car, crossing in the middle of the view (row 359.5)
    lean = (3.7 / XM) / (H - 1)
    left = LineFit((0.0, -lean, 320.0 + lean * (H - 1)), 5000, 700.0)
    right = LineFit((0.0, lean, 960.0 - lean * (H - 1)), 5000, 700.0)
    problem = pair_problem(left, right, H, XM, YM)
    assert problem.startswith("lines cross ") and problem.endswith(" m ahead of the view's bottom row")
    assert number_after(problem, "lines cross ") == pytest.approx((H - 1 - 359.5) * YM, abs=0.05)
    # beyond a shorter look-ahead they do not cross there: only not parallel
    assert pair_problem(left, right, H, XM, YM, top_px=400).startswith("lines not parallel")


def test_curved_lines_that_cross_ahead_are_refused():
    # 3.4 m apart at the car, the right line bending across the left one: the width is
    # 3.7 * ((y - y0) / (15 m))**2 - 0.3 m, with y0 15 m ahead, zero 15 * (1 - sqrt(0.3 / 3.7)) m ahead
    y0 = H - 1 - 15.0 / YM
    a = (3.7 / XM) / (H - 1 - y0) ** 2
    left = LineFit((0.0, 0.0, 320.0), 5000, 700.0)
    right = LineFit((a, -2 * a * y0, 320.0 + a * y0 ** 2 - 0.3 / XM), 5000, 700.0)
    problem = pair_problem(left, right, H, XM, YM)
    assert number_after(problem, "lines cross ") == pytest.approx(15.0 * (1 - math.sqrt(0.3 / 3.7)), abs=0.05)


def test_a_fit_that_hooks_back_beyond_its_pixels_is_refused_and_a_curve_passes():
    # a left line seen on the lower 300 rows whose fit turns around on row 300 and comes back
    # 0.8 m by the view's top: refused, naming it; the same fit seen on every row passes, and so
    # does a 300 m bend (it turns nowhere in the view)
    a = 0.8 / XM / 300.0 ** 2
    hooked = LineFit((a, -2 * a * 300, 400.0), 3000, 300.0)
    right = LineFit((a, -2 * a * 300, 400.0 + 3.6 / XM), 3000, 700.0)
    check = check_lane(hooked, right, (160.0, 160.0), H, XM, YM, width_px=W)
    assert check.left.startswith("left line hooks back ")
    assert number_after(check.left, "hooks back ") == pytest.approx(0.8, abs=0.01)
    assert check.right == ""
    assert check_lane(hooked, right, (160.0, 160.0), H, XM, YM).ok  # not asked for
    assert check_lane(replace(hooked, span_px=719.0), right, (160.0, 160.0), H, XM, YM, width_px=W).ok
    a_px = YM ** 2 / (2 * 300.0) / XM  # x = y**2 / (2 R) in metres, straight ahead at the top row
    curve = (LineFit((a_px, 0.0, 400.0), 3000, 300.0), LineFit((a_px, 0.0, 400.0 + 3.6 / XM), 3000, 300.0))
    assert check_lane(*curve, (160.0, 160.0), H, XM, YM, width_px=W).ok


def test_lines_of_different_curvature_fail_even_when_nearly_parallel():
    # x_right - x_left = da * (y - y_mid)**2 in metres: the width varies by only da * (L/2)**2
    length_m = (H - 1) * YM
    da_m = 0.003  # curvatures differ by 2 * da = 0.006 1/m, over the 0.004 limit
    da_px = da_m * YM ** 2 / XM
    mid = (H - 1) / 2
    left = LineFit((0.0, 0.0, 320.0), 5000, 700.0)
    right = LineFit((da_px, -2 * da_px * mid, 960.0 - da_px * mid ** 2), 5000, 700.0)
    problem = pair_problem(left, right, H, XM, YM)
    assert da_m * (length_m / 2) ** 2 < LaneChecks().max_width_spread_m
    assert problem.startswith("curvatures differ by ")
    assert number_after(problem, "curvatures differ by ") == pytest.approx(2 * da_m, abs=2e-4)


def test_a_bright_patch_fills_its_band():
    mask = lane_mask(*parabolas(3.7))
    mask[:, :360] = 255  # a bright verge up to the left line
    check = check_mask(mask)
    assert check.left.startswith("left line is a bright patch, not a line (fills ")
    assert number_after(check.left, "fills ") > 60 and check.right == "" and check.pair == ""


def test_texture_spreads_over_its_band():
    mask = lane_mask(*parabolas(3.7))
    rng = np.random.default_rng(0)
    speckle = rng.random((H, 480)) < 0.25  # gravel: a quarter of the pixels lit, evenly
    mask[:, 80:560] = np.where(speckle, 255, 0).astype(np.uint8)
    check = check_mask(mask)
    assert check.left.startswith("left line is texture, not a line (its pixels scatter ")
    assert number_after(check.left, "m, ") > 75 and check.right == ""


BEND = (4e-4, -0.55, 420.0)  # a bend's centre curve in the bird's-eye view (px), inside the view


def double_line(spacing_px: float, width_px: int, rows=slice(None)) -> np.ndarray:
    """Return a bird's-eye mask with two stripes ``width_px`` wide, ``spacing_px`` apart centre to
    centre, either side of the curve ``BEND`` (on ``rows`` only)."""
    m = np.zeros((H, W), np.uint8)
    ys = np.arange(H)
    for side in (-0.5, 0.5):
        pts = np.column_stack([np.polyval(BEND, ys) + side * spacing_px, ys]).round().astype(np.int32)
        cv2.polylines(m, [pts.reshape(-1, 1, 2)], False, 255, width_px)
    out = np.zeros_like(m)
    out[rows] = m[rows]
    return out


def band_pixels(mask: np.ndarray, half_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Return (ys, xs) of the mask's pixels within ``half_px`` of the curve ``BEND``."""
    ys, xs = lane_pixels(mask)
    near = np.abs(xs - np.polyval(BEND, ys)) < half_px
    return ys[near], xs[near]


def as_two_stripes(ys: np.ndarray, xs: np.ndarray) -> LineFit:
    """Return ``fit_line`` of the pixels with their spread about two stripes (``two_stripes``), as
    the search records it for a line it does not narrow to an inner stripe."""
    within = two_stripes(ys, xs, 2, H)[3]
    return replace(fit_line(ys, xs, H), stripe_scatter_px=math.sqrt(within / len(ys)))


@pytest.mark.parametrize("spacing_m", [0.12, 0.22, 0.3])
def test_a_double_line_is_not_texture_but_noise_in_its_band_is(spacing_m):
    """A double yellow line, two stripes 0.12-0.3 m apart centre to centre (each half as wide, at
    most 0.12 m), on a bend, in a band 80 px wide (a prior band the view's edge cuts on a
    hairpin, as on country.mp4): one fit runs between the stripes, and from 0.22 m on its
    pixels scatter from it over 70 % of an even spread over the band, like texture. As two
    stripes they hold tight (``LineFit.stripe_scatter_px``: about 30-60 % of an even spread over
    half the band), so the line passes; pixels spread evenly over the same band stay texture,
    also as two stripes (about 100 % of half the band)."""
    spacing = spacing_m / XM
    width = int(round(min(spacing_m / 2, 0.12) / XM))
    band = 80.0
    even = band / math.sqrt(12.0)
    fit = as_two_stripes(*band_pixels(double_line(spacing, width), band / 2))
    if spacing_m >= 0.22:
        assert fit.scatter_px / even > LaneChecks().max_band_scatter
        one = replace(fit, stripe_scatter_px=None)  # one fit only: texture
        assert line_problem(one, band, LaneChecks(), XM, "left").startswith("left line is texture")
    assert fit.stripe_scatter_px / (even / 2) < 0.6
    assert line_problem(fit, band, LaneChecks(), XM, "left") == ""
    rng = np.random.default_rng(4)
    noise = np.where(rng.random((H, W)) < 0.3, 255, 0).astype(np.uint8)
    gravel = as_two_stripes(*band_pixels(noise, band / 2))
    problem = line_problem(gravel, band, LaneChecks(), XM, "left")
    assert problem.startswith("left line is texture, not a line (its pixels scatter ")
    assert number_after(problem, "as two stripes ") > 90


@pytest.mark.parametrize("spacing_m", [0.12, 0.22, 0.3])
def test_a_double_line_in_a_prior_band_is_a_line_at_its_inner_stripe(spacing_m):
    """Searched around the previous fit (between the stripes) in a band 80 px wide, the double
    line passes the line checks; stripes 0.6-1.5 x ``double_line_px`` apart (0.22 and 0.3 m) are
    fitted to the inner stripe, as the truth marks a double centre line; at 0.12 m, under that
    range, the fit runs between them and the line still passes as two stripes (the search
    records their spread, ``LineFit.stripe_scatter_px``). The inner stripe is switched on
    (``double_line_px`` 38; off by default)."""
    spacing = spacing_m / XM
    width = int(round(min(spacing_m / 2, 0.12) / XM))
    mask = double_line(spacing, width)
    prior = LineFit(BEND)
    config = SearchConfig(prior_margin_px=40, double_line_px=38.0)
    s = search_around(mask, prior, LineFit(None), config)
    band = search_bands_px(s, (W, H), config)[0]
    assert band == 80.0
    assert line_problem(s.left, band, LaneChecks(), XM, "left") == ""
    inner = np.polyval(BEND, H - 1) + spacing / 2
    expected = inner if spacing_m >= 0.22 else np.polyval(BEND, H - 1)
    assert s.left.x_at(H - 1) == pytest.approx(expected, abs=3)
    assert (s.left.stripe_scatter_px is None) == (spacing_m >= 0.22)


@pytest.mark.parametrize("share, problem", [(0.6, False), (0.8, True)])
def test_scatter_is_compared_with_an_even_spread_over_the_band(share, problem):
    even_px = 160.0 / math.sqrt(12.0)  # pixels spread evenly over a 160 px window
    fit = LineFit((0.0, 0.0, 320.0), 20000, 719.0, scatter_px=share * even_px)
    text = line_problem(fit, 160.0, LaneChecks(), XM, "right")
    if problem:
        metres = share * even_px * XM
        assert text == (f"right line is texture, not a line (its pixels scatter {metres:.2f} m, "
                        "80% of an even spread over its search band, limit 70%)")
    else:
        assert text == ""


def test_scatter_is_the_rms_distance_of_the_pixels_from_the_fit():
    rng = np.random.default_rng(1)
    ys = np.sort(rng.integers(0, H, 5000))
    xs = (300 + 0.1 * ys + 2e-4 * ys ** 2 + rng.normal(0, 8, ys.size)).round().astype(np.int32)
    fit = fit_line(ys, xs, H)
    rms = np.sqrt(np.mean((xs - np.polyval(np.polyfit(ys, xs, 2), ys)) ** 2))
    assert fit.scatter_px == pytest.approx(rms, rel=1e-6)
    assert 7.5 < fit.scatter_px < 8.5


def test_bands_are_measured_inside_the_view():
    # texture along the view's edge fills only the part of its window inside the view
    empty = (np.empty(0, np.int32), np.empty(0, np.int32))
    fit = LineFit((0.0, 0.0, 20.0), 5000, 700.0)
    wins = (Window("left", -40, 120, 0, 80), Window("left", -100, 60, 80, 160),
            Window("right", 1200, 1360, 0, 80))
    s = LaneSearch(fit, fit, "windows", empty, empty, wins)
    assert search_bands_px(s, (W, H)) == (90.0, 80.0)  # (120 + 60) / 2, 1280 - 1200
    prior = LaneSearch(fit, LineFit(None), "prior", empty, empty)
    assert search_bands_px(prior, (W, H), SearchConfig(prior_margin_px=60)) == (80.0, 120.0)


def test_a_missing_line_is_not_checked():
    check = check_lane(LineFit(None, reason="no pixels"), LineFit((0.0, 0.0, 960.0), 5000, 700.0),
                       (160.0, 160.0), H, XM, YM)
    assert check.ok


@pytest.mark.parametrize("kwargs, message", [
    (dict(min_width_m=5.0), "min_width_m < max_width_m"),
    (dict(check_rows=1), "check_rows must be at least 2"),
    (dict(max_band_fill=0.0), "must be positive"),
    (dict(max_band_scatter=-1.0), "must be positive"),
])
def test_lane_checks_are_validated(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        LaneChecks(**kwargs)


# --------------------------------------------------------------------------- results

def lane_frame(pipe: LanePipeline, left_x: float = 320.0, right_x: float = 960.0) -> np.ndarray:
    """Return an undistorted road frame whose bird's-eye view shows lines at ``left_x``, ``right_x`` (px)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    for x in (left_x, right_x):
        cv2.line(bird, (round(x), 0), (round(x), H - 1), (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


@pytest.fixture(scope="module")
def pipe() -> LanePipeline:
    return LanePipeline()


def test_a_found_lane_has_nothing_rejected(pipe):
    r = pipe.process(lane_frame(pipe))
    assert r.found and r.rejected is None and r.reason == ""
    s = r.summary()
    assert s["rejected"] is None and s["lane_width_m"] == pytest.approx(3.7, abs=0.05)


def test_a_narrow_lane_is_rejected_and_kept_apart(pipe):
    r = pipe.process(lane_frame(pipe, 320.0, 320.0 + 2.0 / XM))
    assert not r.found and not r.left_found and not r.right_found
    assert r.reason.startswith("lane width ")
    assert number_after(r.reason, "lane width ") == pytest.approx(2.0, abs=0.03)
    assert math.isnan(r.lane_width_m) and math.isnan(r.offset_m) and math.isnan(r.radius_m)
    assert r.left_conf == 0 and r.right_conf == 0
    assert r.left.reason == r.reason and r.left.n_pixels > 0  # the rejected fit says why
    assert r.rejected.left.found and r.rejected.right.found
    s = r.summary()
    assert s["found"] is False and s["reason"] == r.reason
    rej = s["rejected"]
    assert rej["lane_width_m"] == pytest.approx(2.0, abs=0.03)
    assert rej["offset_m"] == pytest.approx((CAR_X - (320.0 + 1.0 / XM)) * XM, abs=0.03)
    assert rej["radius_m"] > 5000 and rej["reason"] == r.reason
    assert "No lane found: lane width" in " ".join(pipe_text(pipe, r))


def pipe_text(pipe: LanePipeline, r) -> list[str]:
    """Return the text lines the overlay writes for a result."""
    return draw.measurement_lines(r.radius_m, r.offset_m, r.lane_width_m, r.found, r.reason)


def test_one_implausible_line_keeps_the_other(pipe):
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.rectangle(bird, (0, 0), (360, H - 1), (210, 190, 50), -1)  # a dry yellow verge
    cv2.line(bird, (960, 0), (960, H - 1), (235, 235, 235), 24)
    r = pipe.detect(pipe.perspective.unwarp(bird))
    assert not r.found and r.right_found and not r.left_found
    assert r.reason.startswith("left line is a bright patch, not a line")
    assert r.right_conf > 0.5 and r.left_conf == 0
    assert r.rejected.left.found and r.rejected.reason == r.reason
    assert r.rejected.measurement.lane_width_m > 3.7  # measured from the patch's edge: never reported


def test_results_json_holds_the_rejected_measurement(pipe, tmp_path):
    src = tmp_path / "in"
    io.write_image(src / "lane.png", lane_frame(pipe))
    io.write_image(src / "narrow.png", lane_frame(pipe, 320.0, 320.0 + 2.0 / XM))
    rows = process_images(io.list_images(src), tmp_path / "out")
    data = {r["file"]: r for r in json.loads((tmp_path / "out" / "results.json").read_text())}
    assert data["lane.png"]["found"] and data["lane.png"]["rejected"] is None
    narrow = data["narrow.png"]
    assert narrow["found"] is False and narrow["lane_width_m"] is None and narrow["offset_m"] is None
    assert narrow["rejected"]["lane_width_m"] == pytest.approx(2.0, abs=0.03)
    assert narrow["rejected"]["reason"].startswith("lane width ")
    assert len(rows) == 2


@pytest.mark.parametrize("right_x, prefix", [
    (320.0 + 5.0 / XM, "lane width "),
    (320.0 + 2.2 / XM, "lane width "),
])
def test_the_tracker_and_a_single_image_reject_a_pair_alike(pipe, right_x, prefix):
    frame = lane_frame(pipe, 320.0, right_x)
    alone = pipe.detect(frame)
    tracked = LaneTracker(pipe).update(frame)
    assert not alone.found and not tracked.found
    assert alone.rejected.reason in tracked.reason
    assert tracked.rejected.measurement.lane_width_m == pytest.approx(alone.rejected.measurement.lane_width_m)


def test_checks_from_the_config_reach_the_tracker_and_detect(pipe):
    strict = LanePipeline(PipelineConfig(checks=LaneChecks(min_width_m=3.8)))
    frame = lane_frame(strict)  # 3.7 m
    assert pipe.detect(frame).found
    assert "outside 3.8-4.5 m" in strict.detect(frame).reason
    assert "outside 3.8-4.5 m" in LaneTracker(strict).update(frame).reason


# --------------------------------------------------------------------------- no lane at all

def _stripes(angle_deg: float, spacing_px: int) -> np.ndarray:
    """Return white stripes (half the spacing wide) on black at ``angle_deg`` from vertical."""
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    t = math.radians(angle_deg)
    u = xx * math.cos(t) + yy * math.sin(t)
    return np.where((u % spacing_px) < spacing_px / 2, 235, 0).astype(np.uint8)


def _chessboard(square_px: int) -> np.ndarray:
    yy, xx = np.mgrid[0:H, 0:W]
    return np.where((xx // square_px + yy // square_px) % 2, 255, 0).astype(np.uint8)


def _blobs(sigma_px: float, seed: int) -> np.ndarray:
    noise = np.random.default_rng(seed).integers(0, 256, (H, W, 3), dtype=np.uint8)
    return cv2.normalize(cv2.GaussianBlur(noise, (0, 0), sigma_px), None, 0, 255, cv2.NORM_MINMAX)


NO_LANE = {
    "uniform noise": lambda: np.random.default_rng(0).integers(0, 256, (H, W, 3), dtype=np.uint8),
    "grey noise": lambda: np.random.default_rng(1).integers(0, 256, (H, W), dtype=np.uint8),
    **{f"noise blurred to blobs ({s} px)": (lambda s=s: _blobs(s, 2)) for s in (4, 15, 40)},
    **{f"{name} stripes every {sp} px": (lambda a=a, sp=sp: _stripes(a, sp))
       for name, a in (("vertical", 0), ("horizontal", 90), ("diagonal /", 45), ("diagonal \\", -45))
       for sp in (24, 80, 200)},
    **{f"flat grey {g}": (lambda g=g: np.full((H, W, 3), g, np.uint8)) for g in (60, 128, 200, 255)},
    **{f"chessboard of {sq} px squares": (lambda sq=sq: _chessboard(sq)) for sq in (80, 160)},
    "all black": lambda: np.zeros((H, W, 3), np.uint8),
    "near-black noise": lambda: np.random.default_rng(3).integers(0, 12, (H, W, 3), dtype=np.uint8),
}


@pytest.mark.parametrize("name", list(NO_LANE))
def test_images_without_a_lane_are_never_found(pipe, name):
    img = NO_LANE[name]()
    if img.ndim == 2:
        img = np.dstack([img] * 3)
    for r in (pipe.process(img), pipe.detect(img)):
        assert not r.found, (name, r.lane_width_m)
        assert r.reason
        assert all(math.isnan(v) for v in (r.radius_m, r.offset_m, r.lane_width_m))
        assert r.summary()["found"] is False


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
