"""Tight bends (issue 16): the adaptive look-ahead, shorter views, parallel fits and the road presets.

Known answers from drawn lanes: a bird's-eye view of a circular bend of known radius and lane
width (the exact circle, not a parabola), or of a bend tightening along a clothoid, unwarped
into the camera frame.
"""
from __future__ import annotations

import math
from dataclasses import replace
from functools import reduce

import cv2
import numpy as np
import pytest

from lanelib.checks import pair_problem
from lanelib import ablation
from lanelib.config import PipelineConfig, load_config_or_preset, override, preset, preset_names, to_dict
from lanelib.fit import fit_line, parallel_fits
from lanelib.params import LaneChecks, SearchConfig
from lanelib.perspective import PerspectiveConfig
from lanelib.pipeline import LanePipeline
from lanelib.records import LineFit
from lanelib.search import lookahead_top_px
from lanelib.roads.fallbacks import short_view_search
from lanelib.tracking import LaneTracker

H, W = 720, 1280
PC = PerspectiveConfig()
XM, YM = PC.xm_per_px, PC.ym_per_px
BOTTOM_M = 4.79  # the default view's bottom row is 4.79 m ahead of the camera


def bend_birdseye(radius_m: float, width_m: float, offset_m: float = 0.0, car_x: float = W / 2) -> np.ndarray:
    """Return a bird's-eye RGB view of a right bend of ``radius_m`` (circle), lines 0.15 m wide."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(H, dtype=np.float64)
    d = BOTTOM_M + (H - 1 - ys) * YM
    for lateral in (-width_m / 2 - offset_m, width_m / 2 - offset_m):
        r = radius_m - lateral
        ok = d < r
        x_m = radius_m - np.sqrt(r * r - d[ok] ** 2)
        pts = np.column_stack([car_x + x_m / XM, ys[ok]]).round().astype(np.int32)
        cv2.polylines(bird, [pts], False, (235, 235, 235), int(round(0.15 / XM)))
    return bird


def true_x_px(radius_m: float, lateral_m: float, y_px: float, car_x: float = W / 2) -> float:
    d = BOTTOM_M + (H - 1 - y_px) * YM
    r = radius_m - lateral_m
    return car_x + (radius_m - math.sqrt(r * r - d * d)) / XM


@pytest.fixture(scope="module")
def pipe() -> LanePipeline:
    return LanePipeline(PipelineConfig())


@pytest.fixture(scope="module")
def short_pipe() -> LanePipeline:
    """The default pipeline with the shorter views switched on (``search.short_views``, off by
    default; 0.6 and 0.4 of the view in the ``hard-roads`` preset)."""
    return LanePipeline(override(PipelineConfig(), ["search.short_views=[0.6, 0.4]"]))


def test_a_50m_bend_is_found_in_a_short_view_and_not_in_the_whole_view():
    # the shorter views and the growing margin switched on (both off by default): with the
    # margin the whole view's windows follow the lines up the bend, where the pair fails its
    # checks ("lines cross"); without it they lose the lines after 248 rows and fit the rest
    pipe = LanePipeline(override(PipelineConfig(), ["search.short_views=[0.6, 0.4]",
                                                    "search.grow_margin_px=15"]))
    bird = bend_birdseye(50.0, 3.6)
    mask = pipe.binary(bird)
    whole = pipe.search(mask)
    assert not (whole.left.found and whole.right.found and pipe.check(whole).ok)
    short = short_view_search(pipe, mask)
    assert short is not None and short.top_px > 0
    # the fits follow the true circle (within 0.15 m) over the rows their pixels span: the windows
    # lose a line steeper than about one px per row (0.18 m per m of road, 9 m ahead on a 50 m
    # bend), so that is not the whole look-ahead
    for fit, lateral in ((short.left, -1.8), (short.right, 1.8)):
        assert fit.span_px > 200
        rows = np.linspace(H - 1 - fit.span_px, H - 1, 10)
        err = [abs(fit.x_at(y) - true_x_px(50.0, lateral, y)) * XM for y in rows]
        assert max(err) < 0.15
    # ... and measure in metres: the scale of the view is unchanged by the shorter look-ahead
    m = pipe.measure(short.left, short.right)
    assert m.lane_width_m == pytest.approx(3.6, abs=0.1)
    assert m.radius_m == pytest.approx(50.0, rel=0.4)
    assert m.curvature_per_m > 0  # a right bend


def test_detect_retries_the_short_view_and_off_turns_it_off(short_pipe):
    pipe = short_pipe
    raw = pipe.perspective.unwarp(bend_birdseye(50.0, 3.6))
    r = pipe.detect(raw)
    assert r.found and r.search.top_px > 0 and r.radius_m == pytest.approx(50.0, rel=0.4)
    off = LanePipeline(PipelineConfig(search=SearchConfig(short_views=())))
    assert not off.detect(raw).found


def test_the_tracker_keeps_a_50m_bend_in_a_shortened_look_ahead(short_pipe):
    pipe = short_pipe
    raw = pipe.perspective.unwarp(bend_birdseye(50.0, 3.6))
    tracker = LaneTracker(pipe)
    results = [tracker.update(raw) for _ in range(4)]
    assert all(r.found for r in results)
    assert [r.method for r in results[1:]] == ["prior"] * 3
    assert all(r.search.top_px >= H * (1 - 0.6) - 1 for r in results)
    assert results[-1].lane_width_m == pytest.approx(3.6, abs=0.1)
    assert results[-1].radius_m == pytest.approx(50.0, rel=0.4)


def test_a_straight_road_keeps_the_whole_view(pipe):
    straight = (np.array([0.0, 0.0, 320.0]), np.array([0.0, 0.0, 960.0]))
    assert lookahead_top_px(straight, (W, H)) == 0
    raw = pipe.perspective.unwarp(bend_birdseye(1e6, 3.7))
    tracker = LaneTracker(pipe)
    assert all(tracker.update(raw).search.top_px == 0 for _ in range(3))


def test_lookahead_ends_where_a_line_leaves_the_view_but_not_below_the_shortest():
    sc = SearchConfig()
    # a line drifting right by 1 px per row from x=900 at the bottom reaches W - margin/2 at
    # row 719 - (1280 - 1 - 40 - 900) = 380
    lines = (np.array([0.0, -1.0, 600.0 + 719.0]), np.array([0.0, -1.0, 900.0 + 719.0]))
    top = lookahead_top_px(lines, (W, H), sc)
    assert 375 <= top <= 390
    steep = (np.array([0.0, -5.0, 600.0 + 5 * 719.0]), np.array([0.0, -5.0, 900.0 + 5 * 719.0]))
    assert lookahead_top_px(steep, (W, H), sc) == round(H * (1 - sc.min_view_fraction))


def test_a_short_line_takes_the_curvature_of_the_long_one():
    ys = np.arange(300, 720, dtype=np.int32)
    a = 4e-4
    left_xs = np.round(a * ys ** 2.0 - 0.5 * ys + 400).astype(np.int32)
    dash = np.repeat(np.arange(620, 720, dtype=np.int32), 3)  # one dash: 100 rows, fitted straight alone
    right_xs = np.round(a * dash ** 2.0 - 0.5 * dash + 1000).astype(np.int32)
    sc = SearchConfig()
    left = fit_line(ys, left_xs, H, sc)
    right = fit_line(dash, right_xs, H, sc)
    assert right.coeffs_px[0] == 0.0  # alone: a straight line
    left2, right2 = parallel_fits(left, right, (ys, left_xs), (dash, right_xs), H, sc)
    assert left2 == left
    assert right2.coeffs_px[0] == pytest.approx(left.coeffs_px[0])
    assert right2.x_at(300) == pytest.approx(a * 300 ** 2 - 0.5 * 300 + 1000, abs=2.0)
    assert abs(right.x_at(300) - (a * 300 ** 2 - 0.5 * 300 + 1000)) > 30  # straight: far off


def straight_pair(width_m: float) -> tuple[LineFit, LineFit]:
    return (LineFit((0.0, 0.0, 640.0 - width_m / 2 / XM), 2000, 700.0),
            LineFit((0.0, 0.0, 640.0 + width_m / 2 / XM), 2000, 700.0))


def test_the_country_preset_accepts_a_4_6m_lane_the_highway_preset_refuses():
    assert {"highway", "country"} <= set(preset_names())
    highway, country = preset("highway").checks, preset("country").checks
    left, right = straight_pair(4.6)
    assert "lane width 4.60 m" in pair_problem(left, right, H, XM, YM, highway)
    assert pair_problem(left, right, H, XM, YM, country) == ""
    # both refuse what is no lane at all
    for width in (1.5, 6.5):
        assert pair_problem(*straight_pair(width), H, XM, YM, country).startswith("lane width")


def test_the_country_preset_allows_the_curvature_difference_of_a_hairpin():
    # a 4.8 m lane on a 30 m hairpin: the lines' curvatures differ by about w / R**2 = 0.0053 1/m
    kl, kr = 1 / (30 - 2.4), 1 / (30 + 2.4)
    assert abs(kl - kr) > LaneChecks().max_curvature_diff_per_m
    assert abs(kl - kr) < preset("country").checks.max_curvature_diff_per_m


def flat(config) -> dict:
    """Return a config as {dotted key: value}, e.g. {"search.grow_margin_px": 0, ...}."""
    def walk(d, prefix):
        for k, v in d.items():
            if isinstance(v, dict):
                yield from walk(v, f"{prefix}{k}.")
            else:
                yield f"{prefix}{k}", v
    return dict(walk(to_dict(config), ""))


def changed_keys(config, base=PipelineConfig()) -> set[str]:
    a, b = flat(config), flat(base)
    return {k for k in a if a[k] != b[k]}


HARD_ROAD_KEYS = {s.partition("=")[0] for s in ablation.HARD_ROADS}


def test_presets_load_by_name_and_keep_the_other_defaults():
    highway = load_config_or_preset("highway")
    assert highway.checks == LaneChecks()  # the highway preset spells out the defaults
    assert highway == PipelineConfig()  # ... and nothing else: no hard-road part
    country = load_config_or_preset("country")
    hard = load_config_or_preset("hard-roads")
    assert country.perspective == PipelineConfig().perspective
    assert (country.checks.min_width_m, country.checks.max_width_m) == (2.5, 5.0)
    # country is the hard-roads preset plus its wider checks
    assert country == replace(hard, checks=country.checks)
    assert changed_keys(country, hard) == {"checks.min_width_m", "checks.max_width_m",
                                           "checks.max_curvature_diff_per_m"}
    # hard-roads changes nothing but the fourteen hard-road switches' keys
    assert changed_keys(hard) == HARD_ROAD_KEYS and len(HARD_ROAD_KEYS) == 14
    assert hard.checks == LaneChecks() and hard.perspective == PipelineConfig().perspective


def test_the_hard_roads_preset_switches_on_exactly_the_fourteen_parts():
    """The fourteen hard-road parts are off by default (opt-in, the ablation showed no effect on a
    real row) and all on in the ``hard-roads`` preset: its settings (``ablation.HARD_ROADS``) on
    the defaults are the preset, each part's switch is off ("", (), 0, false) by default and on
    there, and they are the ablation's fourteen opt-in parts from "fallback masks" to "shoulder"."""
    default, hard = PipelineConfig(), preset("hard-roads")
    assert override(default, ablation.HARD_ROADS) == hard
    assert len(ablation.HARD_ROADS) == len(HARD_ROAD_KEYS) == 14
    on, off = flat(hard), flat(default)
    for key in HARD_ROAD_KEYS:
        assert not off[key] and off[key] in ("", [], 0, False), key  # off by default
        assert on[key], key  # on in the preset
    assert (off["thresholds.fallback_rule"], off["search.short_views"], off["edge.enabled"]) == ("", [], False)
    names = ["fallback masks", "shorter views", "growing margin", "inner stripe of a double line",
             "asphalt edge", "lane trend", "blind hold", "near-gap join", "grade pair check",
             "stripe spread", "re-acquisition", "restart from one line", "road view", "shoulder"]
    parts = [p for p in ablation.PARTS if p.name in names]
    assert [p.name for p in parts] == names and not any(p.default for p in parts)
    switched = set()
    for part in parts:  # each part alone switches keys of the preset to the preset's values
        one = override(default, part.settings)
        keys = changed_keys(one)
        assert keys and keys <= HARD_ROAD_KEYS, part.name
        assert all(flat(one)[k] == on[k] for k in keys), part.name
        switched |= keys
    assert switched == HARD_ROAD_KEYS
    assert override(default, [s for p in parts for s in p.settings]) == hard
    every = ablation.PARTS[[p.name for p in ablation.PARTS].index("every hard-road part")]
    assert override(default, every.settings) == hard


def test_a_shorter_look_ahead_allows_its_share_of_the_width_spread():
    # lines diverging by 1.4 m over the whole view: 0.56 m over its lower 40 %, still too much
    left = LineFit((0.0, 0.0, 320.0), 2000, 700.0)
    right = LineFit((0.0, -1.4 / XM / 719, 960.0 + 1.4 / XM), 2000, 700.0)
    top = round(H * 0.6)
    problem = pair_problem(left, right, H, XM, YM, LaneChecks(), top)
    assert problem.startswith("lines not parallel")


@pytest.mark.parametrize("kwargs", [dict(short_views=(0.0,)), dict(short_views=(1.0,)),
                                    dict(min_view_fraction=0.0), dict(min_view_fraction=1.5),
                                    dict(short_bend_resolution=-1.0)])
def test_search_config_checks_the_look_ahead_shares(kwargs):
    with pytest.raises(Exception, match="short_views|min_view_fraction|short_bend_resolution"):
        SearchConfig(**kwargs)


def clothoid_lines(s0_m: float, start_m: float, ramp_m: float, end_curvature: float, width_m: float,
                   ahead_m: float = 40.0, step_m: float = 0.05) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Return the (s, ahead, lateral) points (m, the car at ``s0_m`` heading along the road) of
    the left and right lines of a road straight up to ``start_m`` whose curvature then changes
    linearly to ``end_curvature`` (1/m, left < 0) over ``ramp_m`` and stays (a clothoid)."""
    s = np.arange(s0_m, s0_m + ahead_m, step_m)
    k = np.clip((s - start_m) / ramp_m, 0.0, 1.0) * end_curvature
    heading = np.concatenate([[0.0], np.cumsum(k[:-1] * step_m)])
    ahead = np.concatenate([[0.0], np.cumsum(np.cos(heading[:-1]) * step_m)])
    lateral = np.concatenate([[0.0], np.cumsum(np.sin(heading[:-1]) * step_m)])
    return [(s, ahead - off * np.sin(heading), lateral + off * np.cos(heading))
            for off in (-width_m / 2, width_m / 2)]


def draw_lines_birdseye(lines, dash_m: float = 3.0, period_m: float = 12.0) -> np.ndarray:
    """Return a bird's-eye RGB view of ``clothoid_lines``: the left line solid, the right one
    dashed (``dash_m`` of paint every ``period_m``), 0.15 m wide."""
    bird = np.full((H, W, 3), 70, np.uint8)
    thick = int(round(0.15 / XM))
    for i, (s, ahead, lateral) in enumerate(lines):
        pts = np.column_stack([W / 2 + lateral / XM, H - 1 - (ahead - BOTTOM_M) / YM])
        paint = np.ones(len(s), bool) if i == 0 else np.mod(s, period_m) < dash_m
        cuts = np.flatnonzero(np.diff(paint.astype(np.int8))) + 1
        for run, on in zip(np.split(pts, cuts), np.split(paint, cuts)):
            if on[0] and len(run) > 1:
                cv2.polylines(bird, [run.round().astype(np.int32)], False, (235, 235, 235), thick)
    return bird


def test_the_tracker_follows_a_bend_tightening_to_35m_within_15m():
    # country's hairpin: from straight to a 35 m left bend in 15 m of road, a 3.4 m lane whose
    # right line is dashed, 0.48 m per frame (12 m/s at 25 fps). The lines' fitted curvatures in
    # the 9.4 m look-ahead differ by more than the highway's 0.004 1/m while the bend tightens
    # (both lines within 0.1 m of the truth): refused by it, the pair of the sliding windows
    # (0.27-0.34 m off the lines) was taken instead in 3 frames and the right line inferred in
    # 8 more. The allowance grows as the look-ahead shortens (``checks.pair_problem``). A dash of
    # the right line seen only from 2-7 m ahead on the bend is joined near the car to the line
    # inferred from the left one (``TrackerConfig.near_gap_m``); such a joined line's curvature
    # may differ by more (one frame, 0.0105 1/m): it is refused and the right line inferred, as
    # accurate there (the worst error 0.218 m, 0.220 m without the join).
    # The lane trend (the predicted lane follows the tightening bend) and the near-gap join are
    # switched on (both off by default); with the trend off the lines lag the bend (0.30 m).
    pipe = LanePipeline(override(PipelineConfig(), ["tracking.trend_frames=5", "tracking.near_gap_m=1"]))
    start, ramp, step = 20.0, 15.0, 0.48
    tracker = LaneTracker(pipe)
    worst, joined_refused = 0.0, 0
    for i in range(int((start + ramp) / step) + 1):
        s0 = i * step
        lines = clothoid_lines(s0, start, ramp, -1 / 35, 3.4)
        r = tracker.update(pipe.perspective.unwarp(draw_lines_birdseye(lines)))
        assert r.found
        if s0 < start - BOTTOM_M:  # the bend has not reached the view's bottom row yet
            continue
        if s0 + BOTTOM_M < start + ramp and "curvatures differ" in r.reason:  # tightening
            assert "nearer the car the line inferred from the other line is taken" in r.reason, (i, r.reason)
            joined_refused += 1
        for fit, (_, ahead, lateral) in zip((r.left, r.right), lines):
            y = H - 1 - (ahead - BOTTOM_M) / YM
            x = W / 2 + lateral / XM
            inside = (y >= r.search.top_px) & (y <= H - 1) & (x >= 0) & (x < W)
            worst = max(worst, float(np.abs(fit.x_at(y[inside]) - x[inside]).max()) * XM)
    # the tracked (smoothed) lines on the look-ahead's rows, from where the bend reaches the
    # view's bottom row until the car is on the 35 m arc
    assert worst < 0.25
    assert joined_refused <= 1


def test_the_lines_of_a_35m_hairpin_leaving_the_view_keep_their_bend(pipe):
    # a 35 m right bend, a 3.4 m lane: the inner line leaves the view sideways 6.6 m into it,
    # less than ``min_span_fraction`` of the view (7 m). Fitted straight in the tracked 9.4 m
    # look-ahead, the lines were 0.46-0.91 m off in the view (and the straight track refused
    # the bowed lines as bent); their resolved bend is kept (``short_bend_resolution``), both
    # short lines share one curvature (``fit.shared_curvature``) and the bend against the
    # track is read where both lie in the view (``LaneTracker._bend_rows``): 2-3 cm.
    raw = pipe.perspective.unwarp(bend_birdseye(35.0, 3.4))
    tracker = LaneTracker(pipe)
    for _ in range(8):
        r = tracker.update(raw)
    assert r.found and r.sources == ("seen", "seen") and r.search.top_px > 0
    for fit, lateral in ((r.left, -1.7), (r.right, 1.7)):
        ys = np.arange(r.search.top_px, H, dtype=np.float64)
        truth = np.array([true_x_px(35.0, lateral, y) for y in ys])
        inside = (truth >= 0) & (truth < W)
        assert np.abs(fit.x_at(ys[inside]) - truth[inside]).max() * XM < 0.06
    right_in_view_m = (H - 1 - min(y for y in range(H) if true_x_px(35.0, 1.7, y) < W)) * YM
    assert right_in_view_m < 0.3 * H * YM  # the short line the old rule fitted straight


def test_a_line_is_checked_against_its_track_only_where_both_lie_in_the_view(pipe):
    # a tracked left line leaving the view on the left at row ~470, and this frame's line bowing
    # 0.3 m more over the rows in the view: above them the two extrapolations part by over 2 m
    # (refused as bent, limit 0.7 m, before ``_bend_rows``); where both are seen they agree.
    y = np.arange(H, dtype=np.float64)
    track_left = np.polyfit(y, 300.0 - 1.2 * (H - 1 - y), 2)
    extra = 0.3 / XM / 250.0 ** 2  # 0.3 m over the last 250 rows
    bowed = np.polyfit(y, np.polyval(track_left, y) + extra * (H - 1 - y) ** 2, 2)
    track = (track_left, track_left + np.array([0.0, 0.0, 3.4 / XM]))
    assert (np.polyval(bowed, 0.0) - np.polyval(track_left, 0.0)) * XM > 2.0
    left, _, why = LaneTracker(pipe).check(LineFit(tuple(bowed), 2000, 250.0), LineFit(None), track)
    assert left is not None, why
    # the same bow inside the view is refused
    much = np.polyfit(y, np.polyval(track_left, y) + 4 * extra * (H - 1 - y) ** 2, 2)
    left, _, why = LaneTracker(pipe).check(LineFit(tuple(much), 2000, 250.0), LineFit(None), track)
    assert left is None and "bent" in why[0]
