"""Known-answer tests of the vote over straight lines (``lines.vote``) on drawn lines-view masks,
and of the benchmark cameras' presets (their bird's-eye points make the label lines parallel)."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from lanelib import data
from lanelib.config import preset
from lanelib.lines.trace import ViewLine
from lanelib.lines.vote import follow_ahead, reported, run_centres, vote_candidates, vote_lines
from lanelib.params import LinesConfig
from lanelib.perspective import Perspective

XM, YM = 0.02, 0.1          # m per view px across and along
H, W = 400, 800             # a 40 m x 16 m view
CFG = LinesConfig(min_span_m=5.0, extend_m=0.0)


def paint(mask, x_bottom, slope_px=0.0, rows=None):
    """Draw a line 8 px wide centred on x = x_bottom + slope_px * (H - 1 - y) on ``rows`` (default:
    every row); x_bottom is a half pixel (a run of columns x - 3.5 .. x + 3.5)."""
    for y in (range(H) if rows is None else rows):
        x = int(np.floor(x_bottom + slope_px * (H - 1 - y)))
        mask[y, x - 3:x + 5] = 255


def xs_at_bottom(lines):
    return [round(float(line.x_at(H - 1)), 1) for line in lines]


def test_run_centres_keep_narrow_runs_only():
    m = np.zeros((3, 20), np.uint8)
    m[0, 2:6] = 255      # 4 px: paint
    m[1, 0:20] = 255     # 20 px: a car, not paint
    m[2, 10:12] = 255
    rows, xs = run_centres(m, 5)
    assert rows.tolist() == [0, 2] and xs.tolist() == [3.5, 10.5]


def test_a_line_seen_in_pieces_between_vehicles_is_one_line():
    m = np.zeros((H, W), np.uint8)
    pieces = [*range(0, 60), *range(150, 200), *range(330, 400)]   # hidden in between
    paint(m, 300.5, rows=pieces)
    m[200:330, 200:420] = 255                                      # a vehicle: wide, votes for nothing
    lines = vote_lines(m, CFG, XM, YM)
    assert xs_at_bottom(lines) == [300.5]
    assert lines[0].y_top_px == 0 and lines[0].y_bottom_px == H - 1


def test_parallel_tilted_dashes_share_the_heading_and_a_crossing_streak_does_not_count():
    m = np.zeros((H, W), np.uint8)
    dashes = [y for y in range(H) if y % 120 < 30]                  # 3 m dashes, 9 m gaps
    for x0 in (150.5, 335.5, 520.5):                                # 3.7 m apart
        paint(m, x0, slope_px=0.5, rows=dashes)                     # heading 0.1 m across per m
    paint(m, 700.5, slope_px=-0.6, rows=range(250, 400))            # 15 m streak, another heading
    lines = vote_lines(m, CFG, XM, YM)
    assert xs_at_bottom(lines) == pytest.approx([150.5, 335.5, 520.5], abs=0.3)
    assert all(abs(line.coeffs_px[1] + 0.5) < 0.02 for line in lines)  # dx/dy of x = 0.5 * (H - 1 - y)


def test_scattered_texture_and_a_short_mark_are_not_lines():
    rng = np.random.default_rng(0)
    m = np.zeros((H, W), np.uint8)
    for y in range(H):                                              # road texture: a random speck a row
        x = rng.integers(0, W - 4)
        m[y, x:x + 3] = 255
    assert vote_lines(m, CFG, XM, YM) == []
    m[:] = 0
    paint(m, 600.5, rows=range(360, 400))                           # a 4 m mark: shorter than 5 m
    assert vote_lines(m, CFG, XM, YM) == []


def test_extend_reports_a_line_over_the_whole_view():
    m = np.zeros((H, W), np.uint8)
    paint(m, 400.5, rows=range(200, 300))
    line, = vote_lines(m, LinesConfig(min_span_m=5.0, extend_m=100.0), XM, YM)
    assert (line.y_top_px, line.y_bottom_px) == (0.0, H - 1.0)
    line, = vote_lines(m, CFG, XM, YM)
    assert (line.y_top_px, line.y_bottom_px) == (200.0, 299.0)


@pytest.mark.parametrize("name, vp, width_per_row", [("culane", (755, 382), 2.89),
                                                     ("tusimple", (646, 241), 2.21)])
def test_benchmark_presets_make_straight_lanes_parallel(name, vp, width_per_row):
    """Lines through the preset camera's vanishing point, a lane width apart, come out vertical and
    one lane width apart in its bird's-eye view."""
    p = preset(name).perspective
    view = Perspective(p)
    y0, y1 = p.size_px[1] - 1, vp[1] + 60
    for k in (-1.5, -0.5, 0.5, 1.5):                                # four lines of a straight road
        pts = np.array([[vp[0] + k * width_per_row * (y - vp[1]), y] for y in (y0, y1)], float)
        (xa, _), (xb, _) = view(pts)
        assert abs(xa - xb) < 2.0, (name, k, xa, xb)
    left, right = view(np.array([[vp[0] - 0.5 * width_per_row * (y0 - vp[1]), y0],
                                 [vp[0] + 0.5 * width_per_row * (y0 - vp[1]), y0]], float))[:, 0]
    assert (right - left) * p.xm_per_px == pytest.approx(p.lane_width_m, rel=0.01)


def test_culane_preset_makes_the_dev_labels_parallel():
    root = data.culane_dev()
    if root is None:
        pytest.skip(data.missing_reason("", "culane-dev"))
    view = Perspective(preset("culane").perspective)
    slopes = []
    for labels in sorted(root.glob("driver_*/*/*.lines.txt"))[::6]:
        for text in labels.read_text().splitlines():
            pts = np.array(text.split(), float).reshape(-1, 2)
            pts = pts[pts[:, 1] >= 450]
            if len(pts) >= 5:
                v = view(pts)
                slopes.append(np.polyfit(v[:, 1], v[:, 0], 1)[0])
    # the labelled lines run along the road in the view: nearly vertical, whatever the traffic
    assert len(slopes) > 20 and np.median(np.abs(slopes)) < 0.15


@pytest.mark.parametrize("tight", [0.0, 0.04])
def test_junk_that_outvotes_the_paint_for_a_heading_does_not_set_it(tight):
    """A ragged band of texture along a slanted line (a verge, a truck's side) holds the most
    votes of any heading but is no clean line; the parallel dashes of the lane at heading 0 are
    what the vote reports when it tries more than one heading, with or without the tight lines of
    other headings (``tight_scatter_m``)."""
    rng = np.random.default_rng(1)
    m = np.zeros((H, W), np.uint8)
    for x0 in (250.5, 435.5):                                       # the ego lane, 3.7 m
        paint(m, x0, rows=[y for y in range(H) if y % 90 < 30])
    for y in range(H):                                              # the band: 1.6 m wide, 6 specks a row
        for dx in rng.uniform(-40, 40, 6):
            x = int(650 + 0.25 * (H - 1 - y) + dx)
            m[y, x:x + 3] = 255
    kw = dict(min_span_m=5.0, extend_m=0.0, max_slope=0.3, vote_tolerance_m=0.25, max_scatter_m=0.13,
              tight_scatter_m=tight)
    assert xs_at_bottom(vote_lines(m, LinesConfig(headings=5, **kw), XM, YM)) == pytest.approx([250.5, 435.5], abs=0.5)
    assert vote_lines(m, LinesConfig(headings=1, **kw), XM, YM) == []  # the band's heading: nothing


def test_a_vehicle_edge_ahead_of_the_car_is_refused_and_a_lane_change_is_not():
    cfg = LinesConfig(min_span_m=5.0, extend_m=0.0, min_offset_m=1.0, near_paint_m=1.0)
    car_x = 400.0
    edge = np.zeros((H, W), np.uint8)
    paint(edge, car_x + 25.5, rows=range(0, 330))                   # 0.5 m right, from 7 m ahead
    weighed = vote_candidates(edge, cfg, XM, YM, car_x)
    assert weighed[0].refused.startswith("it runs 0.5 m from the car's centre line")
    changing = np.zeros((H, W), np.uint8)
    paint(changing, car_x + 25.5)                                   # the same line, from the car on
    assert vote_candidates(changing, cfg, XM, YM, car_x)[0].refused == ""


def test_a_line_that_bends_away_from_the_straight_vote_is_followed():
    """A dashed line on a 270 m bend drifts 3 m off its straight start over 40 m; followed, its fit
    stays on the paint from the car to the far end of the view; without following, the runs
    near the straight line the vote found scatter about their fit, and the line is refused."""
    m = np.zeros((H, W), np.uint8)
    truth = lambda y: 300.5 + 150.0 * ((H - 1 - y) / (H - 1)) ** 2   # x (px) along the bend
    for y in range(H):
        if y % 60 < 40:
            x = int(np.floor(truth(y)))
            m[y, x - 3:x + 5] = 255
    kw = dict(min_span_m=5.0, extend_m=100.0, vote_tolerance_m=0.25, max_scatter_m=0.13)
    followed, = vote_lines(m, LinesConfig(follow_bends=True, **kw), XM, YM)
    assert abs(followed.x_at(0) - truth(0)) < 2.0 and abs(followed.x_at(H - 1) - truth(H - 1)) < 2.0
    straight, = vote_candidates(m, LinesConfig(follow_bends=False, **kw), XM, YM)
    assert straight.refused.startswith("its paint scatters")


def test_row_weights_count_far_rows_less():
    """The same 8 m stroke of paint is a line near the car and too little paint far away, where
    each view row sees a fraction of a raw frame's row."""
    weights = np.where(np.arange(H) < H // 2, 0.1, 1.0)            # far half: a tenth of a row each
    cfg = LinesConfig(min_span_m=5.0, extend_m=0.0, min_peak_m=3.0)
    near, far = np.zeros((H, W), np.uint8), np.zeros((H, W), np.uint8)
    paint(near, 300.5, rows=range(300, 380))
    paint(far, 300.5, rows=range(20, 100))
    assert xs_at_bottom(vote_lines(near, cfg, XM, YM)) == [300.5]
    assert len(vote_lines(far, cfg, XM, YM)) == 1                          # unweighted: a line
    assert vote_candidates(far, cfg, XM, YM, row_weights=weights) == []     # 8 m x 0.1: too little
    assert xs_at_bottom(reported(vote_candidates(near, cfg, XM, YM, row_weights=weights), cfg, H, YM)) == [300.5]


def test_the_culane_preset_counts_far_rows_of_the_lines_view_less():
    from lanelib.pipeline import LanePipeline
    weights = LanePipeline(preset("culane"), None, size=(1640, 590)).lines_row_weights()
    assert weights[-1] == 1.0 and weights[0] < 0.5                  # the car's end counts fully
    assert np.all(np.diff(weights[weights > 0]) >= -1e-9)          # and nothing counts more further out


@pytest.mark.parametrize("clear", [True, False])
def test_a_refused_vehicle_edge_hides_the_line_it_crosses_only_when_it_clears_crossings(clear):
    """A vehicle's edge under the car (paint from 5 m ahead, at the car's centre line) outvotes a
    dashed lane line and crosses it 30 m ahead. It is refused either way; the lane line is
    weighed and reported only when a refused line clears no crossing cells."""
    m = np.zeros((400, 600), np.uint8)
    for y0 in range(0, 400, 80):  # a dashed line at x = 150: 4 m dashes every 8 m
        m[400 - y0 - 40:400 - y0, 150:158] = 255
    for t in range(50, 400):  # the edge: x = 300 at the car, 0.5 px across per px ahead
        x = int(round(300 - 0.5 * t))
        m[399 - t, x:x + 6] = 255
    config = LinesConfig(min_offset_m=1.0, near_paint_m=1.0, heading_spread=1.0, min_span_m=5.0,
                         refused_clear_crossings=clear)
    found = vote_candidates(m, config, 0.02, 0.1, car_x_px=303.0)
    assert "a vehicle's edge" in found[0].refused and found[0].paint_m > 30
    lane = [c for c in found if abs(c.x0_px - 154) < 8 and abs(c.slope) < 0.05]
    if clear:
        assert not lane  # cleared as crossing the refused edge: never weighed
    else:
        assert len(lane) == 1 and lane[0].refused == "" and 15 < lane[0].paint_m < 25


def test_a_line_is_followed_along_its_paint_beyond_the_view():
    """A line straight over the searched rows (from row 200) bends away beyond them and its paint
    ends at row 60: the part followed beyond meets the line at the first searched row, stays on
    the bend and ends where the paint does; paint elsewhere is not followed, and a line whose
    paint ends within the searched rows goes on no further."""
    first = 200
    truth = lambda y: 300.5 + (0.001 * (first - y) ** 2 if y < first else 0.0)   # a 250 m bend
    m = np.zeros((H, W), np.uint8)
    for y in range(60, H):
        x = int(np.floor(truth(y)))
        m[y, x - 3:x + 5] = 255
    m[0:150, 600:608] = 255                                           # another line, beyond only
    paint(m, 100.5, rows=range(250, H))                               # paint ending 15 m ahead
    cfg = LinesConfig(vote_tolerance_m=0.25, max_scatter_m=0.13)
    voted = [ViewLine((0.0, 0.0, 300.5), first, H - 1.0, 200, 0.5), ViewLine((0.0, 0.0, 100.5), first, H - 1.0, 150, 0.5)]
    ahead, short = follow_ahead(voted, m, first, cfg, XM, YM)
    assert short is None
    assert ahead.y_top_px == 60 and ahead.y_bottom_px == first
    assert abs(ahead.x_at(first) - 300.5) < 1.0
    assert all(abs(ahead.x_at(y) - truth(y)) < 2.0 for y in range(60, first, 10))


@pytest.mark.parametrize("settings, reach_m", [((), 75.0), (("lines.follow_ahead_m=0",), 40.0)])
def test_predict_reports_lines_as_far_as_their_paint_goes(settings, reach_m):
    """Two lane lines painted on the road from the car to 75 m ahead, seen by the TuSimple
    camera: with its preset (the vote on the view's first 40 m, the lines followed 40 m beyond)
    each line reaches the raw row of its paint's far end; without following, the row of the
    view's end."""
    from lanelib.config import override
    from lanelib.pipeline import LanePipeline
    pipe = LanePipeline(override(preset("tusimple"), settings), None, size=(1280, 720))
    view = pipe.lines_view()[0]
    raw = np.full((720, 1280, 3), 90, np.uint8)
    rows = view.bottom_px - np.arange(0.0, 75.0, 0.05) / view.ym_per_px
    for edges in ((-1.925, -1.775), (1.775, 1.925)):
        strip = [view.inverse(np.column_stack([view.car_x_px + x / view.xm_per_px + 0 * rows, rows])) for x in edges]
        cv2.fillPoly(raw, [np.round(np.vstack([strip[0], strip[1][::-1]])).astype(np.int32)], (230, 230, 230))
    found = pipe.detect_lines(raw, ego=False)
    assert [line.offset_m for line in found.lines] == pytest.approx([-1.85, 1.85], abs=0.05)
    reach = view.inverse(np.array([[view.car_x_px, view.bottom_px - reach_m / view.ym_per_px]]))[0, 1]
    assert [line.points_px[0, 1] for line in found.lines] == pytest.approx([reach, reach], abs=2.0)


@pytest.mark.parametrize("seen_window_m, top", [(2.0, 200.0), (0.0, 100.0)])
def test_a_line_is_seen_where_its_runs_hug_it_not_in_the_vehicle_ahead(seen_window_m, top):
    """A line painted from the car to 20 m ahead (rows 200-399) runs into a vehicle ahead, whose
    edges give runs 0.1-0.2 m either side of it up to 30 m (rows 100-199): the line is seen up to
    its paint's end, where its runs stop hugging its fit; counting every run near it, up to the
    vehicle's top."""
    m = np.zeros((H, W), np.uint8)
    paint(m, 300.5, rows=range(200, H))
    for y in range(100, 200):
        x = 300 + (-10, -6, 6, 10)[y % 4]                               # px, 0.02 m each
        m[y, x - 1:x + 1] = 255
    cfg = LinesConfig(min_span_m=5.0, extend_m=0.0, vote_tolerance_m=0.25, seen_window_m=seen_window_m)
    line, = vote_lines(m, cfg, XM, YM)
    assert abs(line.y_top_px - top) <= 1 and line.y_bottom_px == H - 1


@pytest.mark.parametrize("use_strength, x_bottom", [(True, 300.5), (False, 340.5)])
def test_a_faint_seam_beside_dashed_paint_outvotes_it_only_when_every_run_counts_alike(use_strength, x_bottom):
    """Dashes (3 m paint, 3 m gap: 20 m of paint in 40 m) and, 0.8 m beside them, a seam along
    the whole view that passes the mask's floor but barely (strength 0.5: counts half): one line
    is reported there. By its strength the paint's 20 m outvote the seam's 40 m at half; every
    run alike, the seam's 40 m win."""
    m = np.zeros((H, W), np.uint8)
    paint(m, 300.5, rows=[y for y in range(H) if y % 60 < 30])
    paint(m, 340.5)
    strength = np.ones((H, W), np.float32)
    strength[:, 330:350] = 0.5
    weighed = vote_candidates(m, CFG, XM, YM, strength=strength if use_strength else None)
    assert xs_at_bottom(reported(weighed, CFG, H, YM)) == [x_bottom]


@pytest.mark.parametrize("fraction, kept", [(0.0, [125.5, 310.5, 492.5, 592.5]), (0.7, [125.5, 310.5, 492.5])])
def test_a_line_nearer_than_a_lane_beside_the_line_inside_it_is_refused(fraction, kept):
    """The ego lines 1.8 m either side of the car (the view's middle, x 400), a neighbour line
    3.7 m beyond the left one, and a barrier's foot 2 m beyond the right one, whose paint is
    longer than the right line's dashes: no lane is 2 m wide, so with ``min_lane_fraction`` 0.7
    (2.6 m) the foot, further from the car, is refused and says why; the neighbour stays."""
    m = np.zeros((H, W), np.uint8)
    for x in (125.5, 310.5):
        paint(m, x)
    paint(m, 492.5, rows=[y for y in range(H) if y % 60 < 30])
    paint(m, 592.5)
    config = LinesConfig(min_span_m=5.0, extend_m=0.0, min_lane_fraction=fraction)
    weighed = vote_candidates(m, config, XM, YM)
    assert xs_at_bottom(reported(weighed, config, H, YM)) == kept
    refused = [c.refused for c in weighed if c.refused.startswith("it runs")]
    assert refused == ([] if fraction == 0 else [
        "it runs 2.0 m beside the line inside it, less than min_lane_fraction 0.70 of a lane: no lane is that narrow"])


@pytest.mark.parametrize("tight, kept", [(0.0, [150.5, 335.5]), (0.04, [150.5, 335.5, 520.5])])
def test_a_tight_line_at_another_heading_is_reported_with_tight_scatter(tight, kept):
    """The ego lines run straight ahead; the line beyond the right one bends away (a bend's
    chord, a lane that merges), 0.1 m across per m along: the vote keeps the ego lines' heading,
    and with ``tight_scatter_m`` the other line, tight and apart from them, is reported too."""
    m = np.zeros((H, W), np.uint8)
    for x in (150.5, 335.5):
        paint(m, x)
    paint(m, 520.5, slope_px=0.5)
    config = LinesConfig(min_span_m=5.0, extend_m=0.0, max_slope=0.3, headings=5, max_scatter_m=0.13,
                         tight_scatter_m=tight)
    assert xs_at_bottom(reported(vote_candidates(m, config, XM, YM), config, H, YM)) == pytest.approx(kept, abs=0.5)
