"""LaneTracker on drawn lanes with known geometry: checks, inference, smoothing, hold and reset."""
from __future__ import annotations

import math
import re
from dataclasses import replace

import cv2
import numpy as np
import pytest

from lanelib.checks import gap_problem, pitched_pair_problem
from lanelib.config import PipelineConfig, override
from lanelib.errors import ConfigError
from lanelib.fit import fit_line, least_squares_poly, normal_width_m, offset_line
from lanelib.perspective import PerspectiveConfig
from lanelib.pipeline import LanePipeline
from lanelib.roads.proposers import reacquire_half_px, remembered_bases
from lanelib.roads.stripes import stripe_spread
from lanelib.tracking import LaneTracker, TrackerConfig

H, W = 720, 1280
LEFT_X, RIGHT_X = 320.0, 960.0  # the default dst lines: 3.7 m apart
XM = PerspectiveConfig().xm_per_px


def frame(pipe: LanePipeline, left_x: float | None = LEFT_X, right_x: float | None = RIGHT_X,
          right_top_x: float | None = None) -> np.ndarray:
    """Return an undistorted road frame whose bird's-eye view shows lines at the given x (px).

    ``None`` leaves a line out; ``right_top_x`` slants the right line to that x at the top row.
    """
    bird = np.full((H, W, 3), 70, np.uint8)
    if left_x is not None:
        cv2.line(bird, (round(left_x), 0), (round(left_x), H - 1), (235, 235, 235), 24)
    if right_x is not None:
        top = right_x if right_top_x is None else right_top_x
        cv2.line(bird, (round(top), 0), (round(right_x), H - 1), (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


@pytest.fixture(scope="module")
def pipe() -> LanePipeline:
    return LanePipeline(PipelineConfig())


@pytest.fixture(scope="module")
def double_pipe() -> LanePipeline:
    """The default pipeline with the inner stripe of a double line on (``search.double_line_px``,
    off by default), which the stripes' spread of ``stripe_spread`` and ``grade_pair_check`` reads."""
    return LanePipeline(override(PipelineConfig(), ["search.double_line_px=38"]))


# the opt-in parts these tests switch on (off by default; the ``hard-roads`` preset's values)
TREND = dict(trend_frames=5)
NEAR_GAP = dict(near_gap_m=1.0)
REACQUIRE = dict(reacquire_after_frames=3)
RESTART = dict(restart_frames=25)


def number_after(text: str, prefix: str) -> float:
    """Return the number that follows ``prefix`` in ``text``."""
    return float(re.search(re.escape(prefix) + r"(-?[0-9.]+)", text).group(1))


def bottom_x(result, side: str) -> float:
    return float(np.polyval(getattr(result, side).coeffs_px, H - 1))


def test_steady_lane_is_tracked_with_the_drawn_geometry(pipe):
    tracker = LaneTracker(pipe)
    results = [tracker.update(frame(pipe)) for _ in range(4)]
    assert [r.method for r in results] == ["windows", "prior", "prior", "prior"]
    for r in results:
        assert r.found and r.reason == ""
        assert r.lane_width_m == pytest.approx(3.7, abs=0.05)
        assert abs(r.offset_m) < 0.03
        assert r.left_conf == pytest.approx(1.0) and r.right_conf == pytest.approx(1.0)


def test_a_lost_line_is_inferred_from_the_other_and_the_tracked_width(pipe):
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    r = tracker.update(frame(pipe, right_x=None))
    assert r.found
    assert "right line inferred from the left line and the tracked width" in r.reason
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)
    assert r.lane_width_m == pytest.approx(3.7, abs=0.05)
    assert r.right_conf == pytest.approx(0.5 * r.left_conf)
    assert "inferred" in r.right.reason and r.left.reason == ""


def test_one_line_alone_cannot_start_a_track(pipe):
    r = LaneTracker(pipe).update(frame(pipe, left_x=None))
    assert not r.found and "one line alone cannot start a track" in r.reason
    assert r.left_conf == 0 and r.right_conf == 0 and math.isnan(r.offset_m)


def test_a_jumping_line_is_rejected_and_replaced(pipe):
    tracker = LaneTracker(pipe, TrackerConfig(max_jump_m=0.2))
    for _ in range(3):
        tracker.update(frame(pipe))
    jump_px = 0.3 / pipe.perspective.xm_per_px  # inside the 60 px search band, over the limit
    r = tracker.update(frame(pipe, right_x=RIGHT_X + jump_px))
    assert r.found and "(limit 0.2 m)" in r.reason
    assert number_after(r.reason, "right line jumped ") == pytest.approx(0.3, abs=0.015)
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)  # inferred, not the jump


def test_a_line_far_from_the_track_is_not_followed(pipe):
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    jump_px = 1.0 / pipe.perspective.xm_per_px  # 1 m: outside the band and the windows' reach
    r = tracker.update(frame(pipe, right_x=RIGHT_X + jump_px))
    assert r.found and "no lane pixels near the previous right fit" in r.reason
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)


@pytest.mark.parametrize("kwargs, prefix, value", [
    (dict(right_x=LEFT_X + 5.0 / XM), "lane width ", 5.0),
    (dict(right_x=LEFT_X + 2.2 / XM), "lane width ", 2.2),
    (dict(right_top_x=RIGHT_X + 1.4 / XM), "lines not parallel (width varies by ", 1.4),
])
def test_an_implausible_pair_does_not_start_a_track(pipe, kwargs, prefix, value):
    r = LaneTracker(pipe).update(frame(pipe, **kwargs))
    assert not r.found
    assert number_after(r.reason, prefix) == pytest.approx(value, abs=0.05)


def test_a_bright_patch_is_not_taken_for_a_line(pipe):
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.rectangle(bird, (0, 0), (round(LEFT_X) + 40, H - 1), (210, 190, 50), -1)  # dry yellow verge
    cv2.line(bird, (round(RIGHT_X), 0), (round(RIGHT_X), H - 1), (235, 235, 235), 24)
    r = tracker.update(pipe.perspective.unwarp(bird))
    assert r.found and "left line is a bright patch, not a line" in r.reason
    assert number_after(r.reason, "fills ") > 60
    assert "left line inferred from the right line" in r.reason
    assert bottom_x(r, "left") == pytest.approx(LEFT_X, abs=3)


def test_texture_is_not_taken_for_a_line(pipe):
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    bird = np.full((H, W, 3), 70, np.uint8)
    gravel = np.random.default_rng(5).random((H, 240)) < 0.3  # light gravel over the left line's band
    bird[:, round(LEFT_X) - 120:round(LEFT_X) + 120][gravel] = (235, 235, 235)
    cv2.line(bird, (round(RIGHT_X), 0), (round(RIGHT_X), H - 1), (235, 235, 235), 24)
    r = tracker.update(pipe.perspective.unwarp(bird))
    assert r.found and "left line is texture, not a line" in r.reason
    assert number_after(r.reason, "m, ") > 70
    assert "left line inferred from the right line" in r.reason
    assert bottom_x(r, "left") == pytest.approx(LEFT_X, abs=3)
    assert r.rejected is not None and r.rejected.left.found and "texture" in r.rejected.reason


def test_hold_then_reset_then_reacquire(pipe):
    cfg = TrackerConfig(hold_frames=3, blind_hold_frames=0)  # every frame without a lane counts
    tracker = LaneTracker(pipe, cfg)
    good = tracker.update(frame(pipe))
    blank = frame(pipe, left_x=None, right_x=None)
    held = [tracker.update(blank) for _ in range(3)]
    for k, r in enumerate(held, 1):
        assert r.found and r.method == "hold"
        assert f"holding the last good lane ({k} of 3 frames)" in r.reason
        assert r.left_conf == pytest.approx(round(good.left_conf * (1 - k / 4), 3))
        assert bottom_x(r, "left") == pytest.approx(bottom_x(good, "left"))
    gone = tracker.update(blank)
    assert not gone.found and "tracker reset" in gone.reason and tracker.lane is None
    back = tracker.update(frame(pipe))
    assert back.found and back.method == "windows"


def test_smoothing_weights_recent_frames_and_settles_after_a_step(pipe):
    cfg = TrackerConfig(smooth_frames=5, recency_decay=0.5)
    tracker = LaneTracker(pipe, cfg)
    for _ in range(5):
        tracker.update(frame(pipe))
    step = 0.3 / pipe.perspective.xm_per_px  # the car moves 0.3 m: both lines shift, under the jump limit
    xs = [bottom_x(tracker.update(frame(pipe, LEFT_X + step, RIGHT_X + step)), "left") for _ in range(5)]
    # weights 1, 1/2, 1/4, 1/8, 1/16 of equal-confidence frames: the share of the new position
    shares = [sum(0.5 ** a for a in range(n)) / sum(0.5 ** a for a in range(5)) for n in range(1, 6)]
    for x, share in zip(xs, shares):
        assert x == pytest.approx(LEFT_X + share * step, abs=1.5)
    assert xs[-1] == pytest.approx(LEFT_X + step, abs=1.5)


def test_smoothing_reduces_frame_to_frame_noise(pipe):
    rng = np.random.default_rng(3)
    tracker = LaneTracker(pipe)
    noise = rng.normal(0, 6, 30)  # px of jitter on both lines (about 3.5 cm)
    raw, tracked = [], []
    for n in noise:
        r = tracker.update(frame(pipe, LEFT_X + n, RIGHT_X + n))
        tracked.append(r.offset_m)
        raw.append(pipe.detect(frame(pipe, LEFT_X + n, RIGHT_X + n)).offset_m)
    assert np.std(np.diff(tracked[5:])) < 0.6 * np.std(np.diff(raw[5:]))


@pytest.mark.parametrize("kwargs, message", [
    (dict(smooth_frames=0), "smooth_frames >= 1"),
    (dict(recency_decay=0.0), "recency_decay"),
    (dict(max_jump_m=-1.0), "must be positive"),
    (dict(max_bend_m=0.0), "max_bend_m must be positive"),
])
def test_tracker_config_is_validated(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        TrackerConfig(**kwargs)


def _dash_gap_and_specks(pipe: LanePipeline, seed: int = 0) -> np.ndarray:
    """A frame whose right line shows only in the top 40 % of the view (a gap in the paint) while
    bright specks dot the lower right: the right histogram peak there is a speck."""
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.line(bird, (round(LEFT_X), 0), (round(LEFT_X), H - 1), (235, 235, 235), 24)
    cv2.line(bird, (round(RIGHT_X), 0), (round(RIGHT_X), int(H * 0.4)), (235, 235, 235), 24)
    rng = np.random.default_rng(seed)
    for _ in range(70):
        x, y = int(rng.integers(700, W - 10)), int(rng.integers(H // 2, H - 10))
        if abs(x - RIGHT_X) > 60:
            cv2.rectangle(bird, (x, y), (x + 5, y + 5), (235, 235, 235), -1)
    return pipe.perspective.unwarp(bird)


@pytest.mark.parametrize("history", [0, 20])
def test_remembered_bases_restart_the_windows_after_a_reset(pipe, history):
    tracker = LaneTracker(pipe, TrackerConfig(hold_frames=1, blind_hold_frames=0, base_history_frames=history))
    for _ in range(3):
        tracker.update(frame(pipe))
    blank = frame(pipe, left_x=None, right_x=None)
    tracker.update(blank)
    assert "tracker reset" in tracker.update(blank).reason and tracker.lane is None
    hard = _dash_gap_and_specks(pipe)
    r = tracker.update(hard)
    if history == 0:  # the windows start from a speck: no right line (the top-hat's least
        # width drops most of the 6 px specks, so too few pixels rather than texture), no lane
        assert not r.found and "right line not found" in r.reason
        assert r.search.base_confidence[1] < TrackerConfig().min_base_peak
        assert remembered_bases(tracker) is None
        return
    assert remembered_bases(tracker) == pytest.approx((LEFT_X, RIGHT_X), abs=12)
    assert r.found and "remembered bases" in r.reason
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=6)
    assert r.lane_width_m == pytest.approx(3.7, abs=0.1)
    tracker.reset()  # a new video forgets the bases too
    assert remembered_bases(tracker) is None


def test_a_base_history_needs_a_count():
    with pytest.raises(ConfigError, match="base_history_frames must be 0"):
        TrackerConfig(base_history_frames=-1)


def test_a_held_lane_is_drawn_and_logged_apart_from_a_seen_one(pipe):
    from lanelib import draw
    from lanelib.batch import video_log_row
    tracker = LaneTracker(pipe, TrackerConfig(hold_frames=3))
    seen = tracker.update(frame(pipe))
    blank = frame(pipe, left_x=None, right_x=None)
    held = tracker.update(blank)
    assert held.method == "hold" and seen.method != "hold"
    canvas = np.full((H, W, 3), 100, np.uint8)
    cfg = pipe.config.draw
    mid = pipe.perspective.inverse([((LEFT_X + RIGHT_X) / 2, H - 60)])[0].round().astype(int)
    px = {name: pipe.annotate(canvas, r)[mid[1], mid[0]].astype(int) for name, r in
          (("seen", seen), ("held", held))}
    a = cfg.lane_alpha  # the area is the lane colour blended over the grey frame
    for name, colour in (("seen", cfg.lane_color), ("held", cfg.held_color)):
        assert np.abs(px[name] - (a * np.array(colour) + (1 - a) * 100)).max() <= 2, name
    assert draw.measurement_lines(1000, 0.1, 3.7, True, held=True)[-1] == "Held: not seen in this frame"
    assert "Held" not in " ".join(draw.measurement_lines(1000, 0.1, 3.7, True))
    assert video_log_row(1, 0.04, held)["method"] == "hold"
    assert video_log_row(0, 0.0, seen)["method"] in ("windows", "prior")


# ---- blind frames (nothing seen) and the trend of the lane ------------------------------------

def test_blind_frames_are_held_beside_hold_frames_then_no_lane_with_the_reason(pipe):
    tracker = LaneTracker(pipe, TrackerConfig(hold_frames=2, blind_hold_frames=3))
    good = [tracker.update(frame(pipe)) for _ in range(3)][-1]
    blank = frame(pipe, left_x=None, right_x=None)  # under an overpass: no line at all
    held = [tracker.update(blank) for _ in range(5)]
    notes = [f"holding the last good lane (nothing seen: {k} of 3 blind frames)" for k in (1, 2, 3)]
    notes += [f"holding the last good lane ({k} of 2 frames)" for k in (1, 2)]  # beyond the blind ones
    shares = [1 - k / 4 for k in (1, 2, 3)] + [(1 - k / 3) * (1 - 3 / 4) for k in (1, 2)]
    for r, note, share in zip(held, notes, shares):
        assert r.found and r.method == "hold" and note in r.reason
        assert r.left_conf == pytest.approx(round(good.left_conf * share, 3))
        assert bottom_x(r, "left") == pytest.approx(LEFT_X, abs=3)
    gone = tracker.update(blank)
    assert not gone.found and tracker.lane is None
    assert "lane lost for more than 2 frames beside 3 frames with nothing seen; tracker reset" in gone.reason


def test_lines_seen_and_refused_count_toward_hold_frames_at_once(pipe):
    tracker = LaneTracker(pipe, TrackerConfig(max_jump_m=0.2, hold_frames=2, blind_hold_frames=5))
    for _ in range(3):
        tracker.update(frame(pipe))
    step = 0.3 / XM  # both lines jump 0.3 m: seen, and refused by the jump check
    moved = frame(pipe, LEFT_X + step, RIGHT_X + step)
    held = [tracker.update(moved) for _ in range(2)]
    for k, r in enumerate(held, 1):
        assert r.method == "hold" and f"holding the last good lane ({k} of 2 frames)" in r.reason
        assert "right line jumped" in r.reason and "nothing seen" not in r.reason
    gone = tracker.update(moved)
    assert not gone.found and "lane lost for more than 2 frames; tracker reset" in gone.reason


def _curving_bird(a: float, c_left: float) -> np.ndarray:
    """A bird's-eye frame whose lines are x = a * (H - 1 - y)**2 + c (px): a bend bending away
    from the car, both lines 640 px (3.7 m) apart."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(0, H, 8, dtype=float)
    for c in (c_left, c_left + RIGHT_X - LEFT_X):
        xs = a * (H - 1 - ys) ** 2 + c
        cv2.polylines(bird, [np.round(np.column_stack([xs, ys])).astype(np.int32)], False,
                      (235, 235, 235), 24)
    return bird


def _true_lane(a: float, c_left: float) -> tuple[np.ndarray, np.ndarray]:
    """The pixel coefficients (x = a*y^2 + b*y + c) of ``_curving_bird``'s lines."""
    h = H - 1.0
    left = np.array([a, -2 * a * h, a * h * h + c_left])
    return left, left + np.array([0.0, 0.0, RIGHT_X - LEFT_X])


def test_the_predicted_lane_follows_the_trend_of_a_tightening_bend(pipe):
    # the bend tightens and the lane drifts right at a steady rate: a linear trend per frame
    a0, da, c0, dc = 0.0, 4e-5, LEFT_X, 4.0
    tracker = LaneTracker(pipe, TrackerConfig(**TREND))
    rows = np.linspace(250.0, H - 1.0, 20)  # the near 2/3 of the view, where the bend shows most
    lag, err = [], []
    for n in range(8):
        tracker.update(pipe.perspective.unwarp(_curving_bird(a0 + n * da, c0 + n * dc)))
        truth = _true_lane(a0 + (n + 1) * da, c0 + (n + 1) * dc)  # the next frame's lane
        predicted = tracker.predicted_lane(tracker.frame_number + 1)
        smoothed = tracker.lane
        if n < 2:  # from the third accepted frame on
            assert all(np.array_equal(p, s) for p, s in zip(predicted, smoothed))
            continue
        assert tracker.lost_frames == 0  # every frame accepted
        for side in (0, 1):
            err.append(np.abs(np.polyval(predicted[side], rows) - np.polyval(truth[side], rows)).max())
            lag.append(np.abs(np.polyval(smoothed[side], rows) - np.polyval(truth[side], rows)).max())
    # the average shows the lane of about two frames before the next one (21-27 px off on these
    # rows); the prediction is where the lane is next, to a fraction of a pixel
    assert min(lag) > 15
    assert max(err) < 1.0


def test_the_trend_keeps_the_width_and_stops_at_the_frame_after_the_last_seen_one(pipe):
    tracker = LaneTracker(pipe, TrackerConfig(**TREND))
    for n in range(5):
        tracker.update(frame(pipe, LEFT_X + 5.0 * n, RIGHT_X + 5.0 * n))  # the car drifts left
    nxt = tracker.predicted_lane(tracker.frame_number + 1)
    later = tracker.predicted_lane(tracker.frame_number + 10)  # not seen since: no further than the next
    for side, x0 in ((0, LEFT_X), (1, RIGHT_X)):
        assert np.polyval(nxt[side], H - 1) == pytest.approx(x0 + 25.0, abs=1.5)
        assert np.array_equal(later[side], nxt[side])
    width = np.polyval(nxt[1], H - 1) - np.polyval(nxt[0], H - 1)
    assert width == pytest.approx(RIGHT_X - LEFT_X, abs=1.0)
    blank = frame(pipe, left_x=None, right_x=None)
    held = [tracker.update(blank) for _ in range(3)]
    for r in held:  # the held lane stays where the lane was predicted for the frame after
        assert r.method == "hold" and bottom_x(r, "left") == pytest.approx(LEFT_X + 25.0, abs=1.5)
    off = LaneTracker(pipe, TrackerConfig(trend_frames=0))
    for n in range(5):
        off.update(frame(pipe, LEFT_X + 5.0 * n, RIGHT_X + 5.0 * n))
    assert all(np.array_equal(p, s) for p, s in zip(off.predicted_lane(), off.lane))


@pytest.mark.parametrize("kwargs", [dict(trend_frames=-1), dict(blind_hold_frames=-2)])
def test_trend_and_blind_hold_need_counts(kwargs):
    with pytest.raises(ConfigError, match="trend_frames >= 0 and blind_hold_frames >= 0"):
        TrackerConfig(**kwargs)


def curved_frame(pipe: LanePipeline, k: float) -> np.ndarray:
    """Return a frame whose bird's-eye lines start at LEFT_X and RIGHT_X on the bottom row and
    bend right together, x += k * (H - 1 - y)**2 (parallel: the same bend for both)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(H)
    for x0 in (LEFT_X, RIGHT_X):
        pts = np.column_stack([x0 + k * (H - 1 - ys) ** 2, ys]).round().astype(np.int32)
        cv2.polylines(bird, [pts.reshape(-1, 1, 2)], False, (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


def test_two_lines_that_bend_away_together_outvote_a_lagging_track(pipe):
    """A straight tracked lane, then both lines bend 1 m away from it at the view's top (a bend
    the smoothed track has not caught up with): each line alone bends more than ``max_bend_m``
    from its track, but together they are a lane (same width, same curve), so they are kept."""
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    k = 1.0 / XM / (H - 1) ** 2
    r = tracker.update(curved_frame(pipe, k))
    assert r.found and r.method == "prior"
    assert "both lines bent away from the track together" in r.reason
    assert r.rejected is None
    # a single line bending away alone is still refused and inferred from the other
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(frame(pipe))
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.line(bird, (round(LEFT_X), 0), (round(LEFT_X), H - 1), (235, 235, 235), 24)
    ys = np.arange(H)
    pts = np.column_stack([RIGHT_X + k * (H - 1 - ys) ** 2, ys]).round().astype(np.int32)
    cv2.polylines(bird, [pts.reshape(-1, 1, 2)], False, (235, 235, 235), 24)
    r = tracker.update(pipe.perspective.unwarp(bird))
    assert "right line bent" in r.reason and "right line inferred" in r.reason


def _far_frame(pipe: LanePipeline, right_dx: float = 0.0, right_top_dx: float = 0.0,
               left_far: bool = False, far_rows: int = 120) -> np.ndarray:
    """Return a frame whose right line shows only in the top ``far_rows`` rows of the view (its
    paint near the car in shade), ``right_dx`` px outwards at the top row and ``right_top_dx``
    more at its nearest row, and a full left line (``left_far``: only in the same top rows)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.line(bird, (round(LEFT_X), 0), (round(LEFT_X), far_rows if left_far else H - 1),
             (235, 235, 235), 24)
    cv2.line(bird, (round(RIGHT_X + right_dx), 0), (round(RIGHT_X + right_dx + right_top_dx), far_rows),
             (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


def _tracked(pipe: LanePipeline, config: TrackerConfig | None = None) -> LaneTracker:
    tracker = LaneTracker(pipe, config)
    for _ in range(3):
        tracker.update(frame(pipe))
    return tracker


def test_fit_line_measures_how_far_short_of_the_car_a_line_stops():
    """``gap_px``: rows from the view's bottom row to where all but 2 % of the pixels lie above,
    so a few stray pixels near the car do not make a far line reach it."""
    ys = np.repeat(np.arange(0, 121), 20)
    far = fit_line(ys, np.full(ys.shape, 960), H)
    assert far.gap_px == pytest.approx(H - 1 - 120, abs=3)
    stray = fit_line(np.concatenate([ys, [715] * 8]), np.full(ys.size + 8, 960), H)
    assert stray.span_px > 700 and stray.gap_px == pytest.approx(far.gap_px, abs=3)
    full = fit_line(np.repeat(np.arange(H), 5), np.full(5 * H, 960), H)
    assert full.gap_px < 0.03 * H
    assert gap_problem(far, 0.0326, 12.0, "right").startswith(
        "right line seen only from 19.6 m ahead of the view's bottom row (limit 12.0 m)")
    assert gap_problem(full, 0.0326, 12.0, "right") == ""


def test_a_line_seen_only_far_ahead_is_joined_to_the_line_inferred_near_the_car(pipe):
    """A right line seen only 19.6 m ahead and beyond, slanted so that extrapolated to the car
    it lies 0.42 m outside the lane: it lies along its track where seen, so it is kept there and
    joined, nearer the car, to the line inferred from the left line (which reaches the car)."""
    r = _tracked(pipe).update(_far_frame(pipe, right_top_dx=12.0))
    assert r.found and r.method == "prior"
    assert "right line seen only from" in r.reason
    assert "nearer the car the line inferred from the other line is taken" in r.reason
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)
    assert r.lane_width_m == pytest.approx(3.7, abs=0.03)
    # the rule off: the extrapolated line is taken as seen at the car, and pulls the lane out
    r_off = _tracked(pipe, TrackerConfig(max_gap_m=100.0, near_gap_m=0.0)).update(
        _far_frame(pipe, right_top_dx=12.0))
    assert "seen only" not in r_off.reason
    assert bottom_x(r_off, "right") - RIGHT_X > 3 * abs(bottom_x(r, "right") - RIGHT_X) + 3


def test_two_lines_seen_only_far_ahead_are_joined_to_their_track(pipe):
    r = _tracked(pipe).update(_far_frame(pipe, left_far=True))
    assert r.found and r.reason.count("nearer the car its track is taken") == 2
    assert bottom_x(r, "left") == pytest.approx(LEFT_X, abs=3)
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)


def test_a_far_line_off_its_track_is_refused(pipe):
    """A far line 0.3 m beside its track where seen (inside the prior band; ``max_jump_m`` 0.2 m
    here) is refused and the right line is inferred from the left one. Without a track there
    is nothing to join it to: a far line is taken as the per-frame detector takes it."""
    r = _tracked(pipe, TrackerConfig(max_jump_m=0.2)).update(_far_frame(pipe, right_dx=0.3 / XM))
    assert "at the car it is an extrapolation" in r.reason and "lies along" not in r.reason
    assert "right line inferred from the left line" in r.reason
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3)
    fresh = LaneTracker(pipe).update(_far_frame(pipe))
    assert "seen only" not in fresh.reason


def _sweeping_frame(pipe: LanePipeline, right_from: int = H - 1, left_from: int = H - 1,
                    sweep_px: float = 200.0, slant_px: float = 0.0) -> np.ndarray:
    """Return a frame whose bird's-eye lines start at LEFT_X and RIGHT_X on the bottom row and
    sweep right as x += sweep_px * (d / (H - 1))**3, d = H - 1 - y: a bend whose flat view's
    line turns sideways ever faster ahead, which a second-order fit follows only on average.
    Each line shows from the top row down to row ``left_from``/``right_from`` (its paint nearer
    the car in shade); ``slant_px`` moves the shown part of a right line that stops short of the
    car outwards by up to that much at the top row (0 at its nearest row)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(H, dtype=float)
    sweep = sweep_px * ((H - 1 - ys) / (H - 1)) ** 3
    for x0, last in ((LEFT_X, left_from), (RIGHT_X, right_from)):
        xs = x0 + sweep
        if x0 == RIGHT_X and last < H - 1:
            xs = xs + slant_px * (last - ys) / last
        shown = ys <= last
        pts = np.column_stack([xs[shown], ys[shown]]).round().astype(np.int32)
        cv2.polylines(bird, [pts.reshape(-1, 1, 2)], False, (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


def _sweep_fit_at_car(x0: float, sweep_px: float = 200.0) -> float:
    """The x (px) on the bottom row of the second-order fit to ``_sweeping_frame``'s whole line
    starting at ``x0``: the best a fit of the lane seen down to the car can do."""
    ys = np.arange(H, dtype=float)
    coeffs = least_squares_poly(ys, x0 + sweep_px * ((H - 1 - ys) / (H - 1)) ** 3, 2, float(H))
    return float(np.polyval(coeffs, H - 1))


def test_a_line_seen_only_from_a_few_metres_ahead_on_a_bend_is_joined_to_the_inference(pipe):
    """On a bend, a right line seen only from 6.6 m ahead (paint in shade nearer the car; less
    than ``max_gap_m``), whose flat-view curve sweeps sideways faster ahead than a parabola: its
    own fit extrapolated to the car lies 40 px (0.23 m) outside the truth's. The tracked right
    line bends 0.13 m over those 6.6 m (more than ``near_gap_bend_m``) and the left line
    reaches the car, so the line is joined near the car to the line inferred from the left one
    (``near_gap_m``, switched on here: off by default): it lies where the whole line's fit does,
    to 3 px (2 cm). Rule off (``near_gap_m`` 0): the extrapolation is reported, over 25 px out."""
    one = dict(smooth_frames=1, trend_frames=0)  # the frame's own line is reported
    on = dict(one, **NEAR_GAP)

    def shaded(config: TrackerConfig, **kwargs):
        tracker = LaneTracker(pipe, config)
        for _ in range(4):
            tracker.update(_sweeping_frame(pipe, **kwargs.get("before", {})))
        return tracker.update(_sweeping_frame(pipe, **kwargs.get("now", {})))

    truth = _sweep_fit_at_car(RIGHT_X)
    r = shaded(TrackerConfig(**on), now=dict(right_from=H - 1 - 200))
    assert r.found and "right line seen only from 6.6 m ahead" in r.reason
    assert "nearer the car the line inferred from the other line is taken" in r.reason
    assert bottom_x(r, "right") == pytest.approx(truth, abs=3)
    off = shaded(TrackerConfig(near_gap_m=0.0, **one), now=dict(right_from=H - 1 - 200))
    assert off.found and "seen only" not in off.reason
    assert bottom_x(off, "right") - truth > 25
    # the left line stops short of the car too: nothing near the car to join to, so both are
    # extrapolated as before (joined to the track alone they drift while the car moves)
    both = shaded(TrackerConfig(**on), now=dict(right_from=H - 1 - 200, left_from=H - 1 - 200))
    assert "seen only" not in both.reason


def test_a_line_stopping_short_of_the_car_on_a_straight_road_is_extrapolated(pipe):
    """The same gap on a straight road (a dashed line's): the tracked line bends less than
    ``near_gap_bend_m`` over it, the curvature plays no part in the extrapolation, and the
    line is taken as seen (slanted here, 60 px out at the top row: extrapolated, it lies
    23-28 px inside at the car; ``near_gap_m`` switched on, and it does not join it)."""
    tracker = LaneTracker(pipe, TrackerConfig(smooth_frames=1, trend_frames=0, **NEAR_GAP))
    for _ in range(4):
        tracker.update(_sweeping_frame(pipe, sweep_px=0.0))
    r = tracker.update(_sweeping_frame(pipe, right_from=H - 1 - 200, sweep_px=0.0, slant_px=60.0))
    assert r.found and "seen only" not in r.reason
    assert 20 < RIGHT_X - bottom_x(r, "right") < 30


def test_a_width_extrapolated_to_the_car_on_a_bend_is_not_measured_there(pipe):
    """Both lines of the bend seen only from 6.6 m ahead (their paint nearer the car in shade;
    the right one slanted 60 px out at the top row), so neither is joined to an inference and
    both are extrapolated to the car, where the pair is 0.19 m narrower than the lane: the
    frame's lines are reported, but its width is no measurement and ``seen_width_m`` (the width
    a line lost later is inferred at) keeps the 3.70 m seen down to the car before (with
    ``near_gap_m`` switched on; off by default). Rule off (``near_gap_m`` 0) it takes the
    3.50 m; on a straight road (a dashed line's gaps) the extrapolation does not rest on the
    curvature and its width counts as before."""
    def width_after(config: TrackerConfig, sweep_px: float = 200.0):
        tracker = LaneTracker(pipe, config)
        for _ in range(4):
            tracker.update(_sweeping_frame(pipe, sweep_px=sweep_px))
        before = tracker.seen_width_m
        r = tracker.update(_sweeping_frame(pipe, right_from=H - 1 - 200, left_from=H - 1 - 200,
                                           sweep_px=sweep_px, slant_px=60.0))
        return r, before, tracker.seen_width_m

    one = dict(smooth_frames=1, trend_frames=0)  # the newest frame's width is the median
    on = dict(one, **NEAR_GAP)
    r, before, after = width_after(TrackerConfig(**on))
    assert r.found and r.sources == ("seen", "seen")
    assert before == pytest.approx(3.70, abs=0.01) and after == before
    r, before, after = width_after(TrackerConfig(near_gap_m=0.0, **one))
    assert r.found and after == pytest.approx(3.50, abs=0.02)
    r, before, after = width_after(TrackerConfig(**on), sweep_px=0.0)
    assert r.found and before == pytest.approx(3.70, abs=0.01)
    assert after == pytest.approx(3.54, abs=0.02)


def test_near_gap_needs_non_negative_limits():
    with pytest.raises(ConfigError, match="near_gap_bend_m >= 0"):
        TrackerConfig(near_gap_bend_m=-0.1)


def test_max_gap_must_be_positive():
    with pytest.raises(ConfigError, match="max_gap_m must be positive"):
        TrackerConfig(max_gap_m=0.0)


def _pitched_frame(pipe: LanePipeline, spread_top: float, right: bool,
                   stripes_top: float | None = None) -> np.ndarray:
    """Return a frame whose bird's-eye view shows a double left line (stripes 38 px apart at the
    bottom row) and, with ``right``, the right line, the view spreading the road ahead by
    ``spread_top`` at the top row (1 at the bottom, linear in between); the stripes spread by
    ``stripes_top`` (default: ``spread_top``)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(H, dtype=float)
    k = 1.0 + (spread_top - 1.0) * (H - 1 - ys) / (H - 1)
    ks = k if stripes_top is None else 1.0 + (stripes_top - 1.0) * (H - 1 - ys) / (H - 1)
    lines = [(LEFT_X + 0 * ys, 16), (LEFT_X - 38.0 * ks, 16)]
    if right:
        lines.append((LEFT_X + (RIGHT_X - LEFT_X) * k, 24))
    for xs, thickness in lines:
        pts = np.column_stack([xs, ys]).round().astype(np.int32)
        cv2.polylines(bird, [pts.reshape(-1, 1, 2)], False, (235, 235, 235), thickness)
    return pipe.perspective.unwarp(bird)


@pytest.mark.parametrize("stripe_spread, top_x",
                         [(True, LEFT_X + 1.25 * (RIGHT_X - LEFT_X)), (False, RIGHT_X)])
def test_an_inferred_line_widens_ahead_as_the_seen_double_lines_stripes(double_pipe, stripe_spread, top_x):
    """A straight lane tracked with both lines; then the right line goes and the view spreads the
    road ahead by 1.25 at the top row: the double left line's stripes spread with it, and the
    inferred right line follows (at the car it stays at the tracked width). With the switch off
    it keeps the tracked width on every row. (The stripes are read with ``double_line_px`` on.)"""
    pipe = double_pipe
    tracker = LaneTracker(pipe, replace(pipe.config.tracking, stripe_spread=stripe_spread))
    for _ in range(3):
        tracker.update(_pitched_frame(pipe, 1.0, True))
    r = tracker.update(_pitched_frame(pipe, 1.25, False))
    assert r.found and "right line inferred" in r.reason
    assert ("widened ahead as its double stripes" in r.reason) == stripe_spread
    assert bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=4)
    # the smoothed lane averages this frame with the three before it: read the frame's own fit
    top = float(np.polyval(tracker.state.history[-1].right, 0.0))
    assert top == pytest.approx(top_x, abs=12)


def test_stripes_seen_only_near_the_car_do_not_widen_the_lane_ahead(double_pipe):
    """The double left line's outer stripe only on the bottom half of the view: its spacing is
    read on four bands of rows, but over under half the look-ahead, too short to scale the
    width ahead: the inferred line keeps the tracked width (``stripe_spread`` switched on)."""
    pipe = double_pipe
    tracker = LaneTracker(pipe, replace(pipe.config.tracking, stripe_spread=True))
    for _ in range(3):
        tracker.update(_pitched_frame(pipe, 1.0, True))
    bird = pipe.perspective.warp(_pitched_frame(pipe, 1.25, False))
    bird[: H // 2, : round(LEFT_X) - 20] = 70  # the outer stripe is worn away ahead
    r = tracker.update(pipe.perspective.unwarp(bird))
    assert r.found and "right line inferred" in r.reason
    assert "double stripes" not in r.reason
    assert float(np.polyval(tracker.state.history[-1].right, 0.0)) == pytest.approx(RIGHT_X, abs=12)


def _turning_frame(pipe: LanePipeline, n: int, right: bool = True) -> np.ndarray:
    """Frame ``n`` of a bend that turns and tightens from frame to frame: the left line is
    x = a*d**2 + b*d + LEFT_X (d = H - 1 - y, a and b growing with n) and the right line its
    parallel curve 3.7 m to the right along the normal (``fit.offset_line``)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    ys = np.arange(0, H, 4, dtype=float)
    d = H - 1 - ys
    xl = 1.2e-4 * n * d * d - 0.08 * n * d + LEFT_X
    curves = [xl]
    if right:
        ym = pipe.perspective.ym_per_px
        rc = offset_line(np.polyfit(ys, xl, 2), 3.7, XM, ym, H)
        curves.append(np.polyval(rc, ys))
    for xs in curves:
        cv2.polylines(bird, [np.round(np.column_stack([xs, ys])).astype(np.int32)], False,
                      (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


def test_an_inferred_line_keeps_the_width_seen_at_the_car(pipe):
    """Both lines seen for 3 frames (3.7 m), then the right line is lost for 24 frames of a bend
    that turns further each frame: the right line is inferred at the width measured while both
    were seen (``seen_width_m``), not at the width read back from the tracked lane, which holds
    the lines inferred before (that one drifted 3.70 -> 3.44 m over these frames)."""
    ym = pipe.perspective.ym_per_px
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(_turning_frame(pipe, 0))
    assert tracker.seen_width_m == pytest.approx(3.7, abs=0.02)
    widths = []
    for n in range(1, 25):
        r = tracker.update(_turning_frame(pipe, n, right=False))
        assert r.found and "right line inferred from the left line" in r.reason
        widths.append(normal_width_m(r.left.coeffs_px, r.right.coeffs_px, H - 1.0, XM, ym))
    assert tracker.seen_width_m == pytest.approx(3.7, abs=0.02)  # inferred frames add nothing
    assert max(abs(w - 3.7) for w in widths) < 0.05


def _short_track(grade_pair_check: bool = True) -> LaneTracker:
    """Return a tracker of a level straight lane measured on the bottom 320 rows of the view (as
    on a tight bend), so its look-ahead is some 390 rows (``TrackerConfig.lookahead_growth_m``),
    where the pair's width may vary by 0.4 m; searched 150 px either side of the track, so the
    search around it sees a line that spreads away from it by 87 px at the look-ahead's top (on
    a clip the windows from the track find such a line, ``LaneTracker.update``). The double
    line's stripes are read with ``double_line_px`` on (off by default)."""
    config = override(PipelineConfig(), ["search.double_line_px=38"])
    pipe = LanePipeline(replace(config, search=replace(config.search, prior_margin_px=150),
                                tracking=replace(config.tracking, grade_pair_check=grade_pair_check)))
    tracker = LaneTracker(pipe)
    for _ in range(3):
        tracker.update(_pitched_frame(pipe, 1.0, True))
    tracker.state.history = type(tracker.state.history)(
        [replace(a, top_px=H // 2 + 40) for a in tracker.state.history], maxlen=tracker.state.history.maxlen)
    return tracker


@pytest.mark.parametrize("grade_pair_check", [True, False])
def test_a_tracked_lane_that_spreads_as_its_double_stripes_keeps_both_lines(pipe, grade_pair_check):
    """Tracked on a level road, then the flat view spreads the road ahead by 1.25 at the top row
    (a climb comes into view): against the tracked width the pair is not parallel (0.53 m over
    the look-ahead, limit 0.4 m), but the double left line's stripes spread alike, so on the
    road ahead's grade the lines are parallel and both are kept. With the switch off the right
    line is dropped and inferred."""
    tracker = _short_track(grade_pair_check)
    r = tracker.update(_pitched_frame(tracker.pipeline, 1.25, True))
    assert r.found and "lines not parallel" in r.reason
    assert ("parallel on the road ahead's grade" in r.reason) == grade_pair_check
    assert ("right line inferred" in r.reason) != grade_pair_check


@pytest.mark.parametrize("stripes_top", [1.0, 1.6])
def test_a_lane_that_spreads_unlike_its_double_stripes_stays_refused(pipe, stripes_top):
    """The right line spreads by 1.25 at the top row but the stripes keep their spacing (the
    road ahead is level: the right line is something else) or spread by 1.6: refused as before.
    And without a track the flat check alone decides (no lane is started on the stripes' word)."""
    tracker = _short_track()
    r = tracker.update(_pitched_frame(tracker.pipeline, 1.25, True, stripes_top=stripes_top))
    assert "lines not parallel" in r.reason and "road ahead's grade" not in r.reason
    assert "right line inferred" in r.reason
    checked = LanePipeline(override(PipelineConfig(), ["search.double_line_px=38",
                                                       "tracking.grade_pair_check=true"]))
    fresh = LaneTracker(checked).update(_pitched_frame(checked, 1.3, True))
    assert not fresh.found and "lines not parallel" in fresh.reason



def _paint_returns_frame(pipe: LanePipeline, right_dx: float | None, near_row: int = H - 1) -> np.ndarray:
    """Return a frame with the full left line and the right line ``right_dx`` px outside
    ``RIGHT_X`` from the view's top row down to ``near_row`` only (its paint nearer the car
    missing), or no right line (``right_dx`` None)."""
    bird = np.full((H, W, 3), 70, np.uint8)
    cv2.line(bird, (round(LEFT_X), 0), (round(LEFT_X), H - 1), (235, 235, 235), 24)
    if right_dx is not None:
        x = round(RIGHT_X + right_dx)
        cv2.line(bird, (x, 0), (x, near_row), (235, 235, 235), 24)
    return pipe.perspective.unwarp(bird)


def _after_missing_paint(pipe: LanePipeline, config: TrackerConfig, right_dx: float,
                         frames: int = 12) -> list:
    """Track a 3.7 m lane for 3 frames, lose the right line's paint for 8 frames, then show it
    ``right_dx`` px outside its old place (the lane widened while its paint was missing), its
    paint coming back from the view's top row towards the car by 60 rows (2 m of road) a
    frame. Return the results of those last ``frames`` frames."""
    tracker = LaneTracker(pipe, config)
    for _ in range(3):
        tracker.update(frame(pipe))
    for _ in range(8):
        r = tracker.update(_paint_returns_frame(pipe, None))
        assert "right line inferred" in r.reason
    return [tracker.update(_paint_returns_frame(pipe, right_dx, min(H - 1, 100 + 60 * k)))
            for k in range(frames)]


def test_a_line_inferred_for_long_is_reacquired_where_its_paint_returns(pipe):
    """Known answer: the right line's paint returns 0.6 m (104 px) outside where the inference
    puts it, beyond the 60 px band around the track and the 0.5 m jump limit. Looked for in a
    band that widened with the frames it was inferred (``reacquire_after_frames``), it is found;
    while it is seen only more than ``max_gap_m`` ahead it is joined to the inference near the
    car, and that pair is not parallel, so it stays inferred; from the frame its paint comes
    within 12 m of the car it is seen, and 4 frames later the smoothed line lies within 3 px
    of it at the car and at the top row, the lane 4.3 m wide (the re-acquisition switched on;
    off by default). Without the re-acquisition it is never found again (the lane reads 3.7 m)."""
    dx = 0.6 / XM
    results = _after_missing_paint(pipe, TrackerConfig(**REACQUIRE), dx)
    sources = [r.sources[1] for r in results]
    first = sources.index("seen")
    assert sources[:first] == ["inferred"] * first and set(sources[first:]) == {"seen"}
    gap_m = (H - 1 - (100 + 60 * first)) * pipe.perspective.ym_per_px
    assert gap_m <= TrackerConfig().max_gap_m < gap_m + 60 * pipe.perspective.ym_per_px
    last = results[-1]
    assert first + 4 < len(results) and last.reason == ""
    assert bottom_x(last, "right") == pytest.approx(RIGHT_X + dx, abs=3)
    assert float(np.polyval(last.right.coeffs_px, 0.0)) == pytest.approx(RIGHT_X + dx, abs=3)
    assert last.lane_width_m == pytest.approx(4.3, abs=0.03)
    off = _after_missing_paint(pipe, TrackerConfig(reacquire_after_frames=0), dx)
    assert all(r.sources[1] == "inferred" for r in off)
    assert bottom_x(off[-1], "right") == pytest.approx(RIGHT_X, abs=3)


def test_a_line_too_far_from_the_inference_for_a_lane_stays_refused(pipe):
    """The right paint returns 1.0 m outside the inference: inside the re-acquisition band
    (1.2 m), but the lane it would make is 4.7 m wide (limit 4.5 m): refused every frame, the
    line stays inferred where it was. A confident wrong line is worse than an inferred one.
    (The re-acquisition switched on, as its band is what this is about.)"""
    results = _after_missing_paint(pipe, TrackerConfig(**REACQUIRE), 1.0 / XM)
    assert all(r.found and r.sources[1] == "inferred" for r in results)
    assert all(bottom_x(r, "right") == pytest.approx(RIGHT_X, abs=3) for r in results)


def test_the_reacquisition_band_widens_with_the_inferred_run(pipe):
    """No wider search before ``reacquire_after_frames`` inferred frames; then the band's half
    width starts at twice ``prior_margin_px`` and grows by it each frame, up to
    ``reacquire_band_m``; the jump limit against the inferred line is the band's (the
    re-acquisition switched on, ``reacquire_after_frames`` 3; off by default)."""
    tracker = LaneTracker(pipe, TrackerConfig(**REACQUIRE))
    for _ in range(3):
        tracker.update(frame(pipe))
    margin = pipe.config.search.prior_margin_px
    halves = []
    for _ in range(6):
        tracker.update(_paint_returns_frame(pipe, None))
        halves.append(reacquire_half_px(tracker, 1))
    cap = TrackerConfig().reacquire_band_m / XM
    assert halves == pytest.approx([0, 0, 2 * margin, 3 * margin, cap, cap])
    assert reacquire_half_px(tracker, 0) == 0
    assert tracker.jump_limit_m(1) == pytest.approx(TrackerConfig().reacquire_band_m)
    assert tracker.jump_limit_m(0) == TrackerConfig().max_jump_m
    tracker.update(frame(pipe))
    assert reacquire_half_px(tracker, 1) == 0


@pytest.mark.parametrize("kwargs", [dict(reacquire_after_frames=-1), dict(reacquire_band_m=0.0)])
def test_reacquisition_needs_a_count_and_a_band(kwargs):
    with pytest.raises(ConfigError, match="reacquire_after_frames"):
        TrackerConfig(**kwargs)


def _lose_track(pipe: LanePipeline, **kwargs) -> LaneTracker:
    """Return a tracker that tracked both drawn lines for 3 frames, then held the lane through 3
    blank frames and reset on the fourth (every blank frame counts toward the hold)."""
    tracker = LaneTracker(pipe, TrackerConfig(hold_frames=3, blind_hold_frames=0, **kwargs))
    for _ in range(3):
        assert tracker.update(frame(pipe)).found
    blank = frame(pipe, left_x=None, right_x=None)
    held = [tracker.update(blank) for _ in range(4)]
    assert [r.method for r in held[:3]] == ["hold"] * 3
    assert "tracker reset" in held[3].reason and tracker.lane is None
    assert math.isnan(tracker.seen_width_m)  # the track's, forgotten; the reset remembers it
    assert tracker.state.lost_track.width_m == pytest.approx(3.7, abs=0.02)
    return tracker


@pytest.mark.parametrize("side", ["left", "right"])
def test_one_line_restarts_a_lane_lost_recently_with_the_other_inferred(pipe, side):
    """Known answer: after the reset only one line shows, 0.2 m from where it was tracked (the
    car drifted); the lane's true other line lies 3.7 m (640 px) beside it. The first frame waits
    for the next to agree; the second restarts the lane, the other line inferred at the width
    seen before the loss, within 0.05 m of the truth, and the track goes on from it (the restart
    from one line switched on, ``restart_frames`` 25; off by default)."""
    tracker = _lose_track(pipe, **RESTART)
    shift = 0.2 / XM
    lone = dict(left_x=LEFT_X + shift, right_x=None) if side == "left" else dict(left_x=None, right_x=RIGHT_X + shift)
    other = "right" if side == "left" else "left"
    first = tracker.update(frame(pipe, **lone))
    assert not first.found and "restarts the lane if the next frame's agrees" in first.reason
    results = [tracker.update(frame(pipe, **lone)) for _ in range(3)]
    r = results[0]
    assert r.found and f"{side} line alone restarts the lane: 0.20 m at the car" in r.reason
    assert f"{other} line inferred from the {side} line and the width seen before the loss" in r.reason
    assert r.sources == (("seen", "inferred") if side == "left" else ("inferred", "seen"))
    for r in results:
        assert r.found and r.sources[0 if side == "left" else 1] == "seen"
        assert bottom_x(r, side) == pytest.approx((LEFT_X if side == "left" else RIGHT_X) + shift, abs=3)
        truth = (RIGHT_X if side == "left" else LEFT_X) + shift
        assert abs(bottom_x(r, other) - truth) * XM < 0.05
        assert r.lane_width_m == pytest.approx(3.7, abs=0.05)
    assert r.method == "prior" and r.right_conf == pytest.approx(0.5 * r.left_conf) if side == "left" else True


def test_a_video_that_starts_with_one_line_never_reports_a_lane(pipe):
    tracker = LaneTracker(pipe)
    for _ in range(30):
        r = tracker.update(frame(pipe, right_x=None))
        assert not r.found and "one line alone cannot start a track" in r.reason


@pytest.mark.parametrize("case", ["too far", "too late", "off", "disagree"])
def test_one_line_does_not_restart_a_lane_lost_long_ago_or_elsewhere(pipe, case):
    tracker = _lose_track(pipe, restart_frames=0 if case == "off" else 5)
    lone = frame(pipe, right_x=None, left_x=LEFT_X + (1.0 / XM if case == "too far" else 0.0))
    blank = frame(pipe, left_x=None, right_x=None)
    if case == "too late":  # the lone line shows from the 6th frame after the reset on
        for _ in range(5):
            tracker.update(blank)
    if case == "disagree":  # frames whose lines lie 0.6 m apart (max_jump_m 0.5), each 0.3 m from the lost one
        frames = [frame(pipe, right_x=None, left_x=LEFT_X + s / XM) for s in (0.3, -0.3, 0.3, -0.3)]
    else:
        frames = [lone] * 4
    for f in frames:
        r = tracker.update(f)
        assert not r.found
        assert "one line alone cannot start a track" in r.reason or case == "disagree"
    assert tracker.lane is None


def test_a_restarted_track_that_never_saw_both_lines_is_not_restarted_again(pipe):
    tracker = _lose_track(pipe, **RESTART)
    lone = frame(pipe, right_x=None)
    assert [tracker.update(lone).found for _ in range(2)] == [False, True]
    blank = frame(pipe, left_x=None, right_x=None)
    for _ in range(4):
        r = tracker.update(blank)
    assert "tracker reset" in r.reason
    for _ in range(3):
        r = tracker.update(lone)
        assert not r.found and "one line alone cannot start a track" in r.reason


@pytest.mark.parametrize("kwargs", [dict(restart_frames=-1), dict(restart_distance_m=0.0)])
def test_a_restart_needs_a_count_and_a_distance(kwargs):
    with pytest.raises(ConfigError, match="restart_frames"):
        TrackerConfig(**kwargs)



def _double_line_mask(coeffs, spread_top: float, first_row: int = 0) -> np.ndarray:
    """Return a bird's-eye mask of a double line along the fit ``coeffs`` (the inner, right
    stripe), its outer stripe 38 px to the left at the car and ``spread_top`` times that on row 0
    (the flat view's spread ahead), drawn from row ``first_row`` down, 10 px wide."""
    mask = np.zeros((H, W), np.uint8)
    for y in range(first_row, H):
        gap = 38.0 * (1.0 + (spread_top - 1.0) * (H - 1.0 - y) / (H - 1.0))
        x = float(np.polyval(coeffs, y))
        for xs in (x - gap, x):
            lo, hi = int(round(xs - 5)), int(round(xs + 5))
            if hi > 0 and lo < W:
                mask[y, max(lo, 0):min(hi, W)] = 255
    return mask


def test_the_stripes_spread_is_read_over_the_rows_where_the_line_is_in_view(double_pipe):
    """A double line on a tight bend leaves the view sideways on row 420 (of 720): its stripes
    show only below it, 300 rows, short of half the view, but all of the view where the line
    is, and the spread they tell (drawn: 1.09 on row 500) is read (``roads.stripes.stripe_spread``).
    A line that stays in the view, its stripes shown on the same 300 rows only, is not read
    (stripes missing on over half of it)."""
    a = -0.004  # x = 320 on the bottom row, 0 on row 420, outside the view above
    b = (320.0 - a * ((H - 1.0) ** 2 - 420.0 ** 2)) / (H - 1.0 - 420.0)
    bent = np.array([a, b, -a * 420.0 ** 2 - b * 420.0])
    pipe = double_pipe
    spacing = pipe.config.search.double_line_px
    assert spacing == 38.0
    spread = stripe_spread(_double_line_mask(bent, 1.3), bent, spacing, 0, pipe.size)
    assert spread is not None
    assert np.polyval(spread, H - 1.0 - 500.0) == pytest.approx(1.0 + 0.3 * 219.0 / 719.0, abs=0.03)
    straight = np.array([0.0, 0.0, 320.0])
    assert stripe_spread(_double_line_mask(straight, 1.3, 420), straight, spacing, 0, pipe.size) is None


@pytest.mark.parametrize("top_m, starts", [(-1.5, True), (1.2, True), (-2.2, False)])
def test_a_pitched_views_lane_starts_the_track_on_its_third_frame(pipe, top_m, starts):
    """Known answer: a lane 3.7 m wide at the car whose right line leans ``top_m`` by the view's
    top row (the flat view of a road pitched from the bird's-eye points' plane: 41 % narrower,
    32 % wider) is refused as not parallel on its own; the same pair in three frames in a row
    starts the track on the third (``pitched_start_frames``), and the next frame checks it
    against the tracked width. A lean of 59 % is beyond ``max_pitch_change`` and never starts."""
    tracker = LaneTracker(pipe)
    image = frame(pipe, right_top_x=RIGHT_X + top_m / XM)
    results = [tracker.update(image) for _ in range(4)]
    assert all(not r.found and "lines not parallel" in r.reason for r in results[:2])
    if not starts:
        assert not any(r.found for r in results)
        assert "even in a pitched view" not in results[-1].reason  # tried only on the flat check's word
        assert pitched_pair_problem(results[-1].rejected.left, results[-1].rejected.right, H, XM,
                                    PerspectiveConfig().ym_per_px).startswith(
            "lines not parallel even in a pitched view")
        return
    assert results[2].found and "a lane in a pitched flat view" in results[2].reason
    assert results[2].sources == ("seen", "seen")
    assert results[3].found and results[3].reason == ""
    assert results[3].lane_width_m == pytest.approx(3.7, abs=0.05)
    off = LaneTracker(pipe, replace(pipe.config.tracking, pitched_start_frames=0))
    assert not any(off.update(image).found for _ in range(4))


def test_a_pitched_start_needs_the_same_pair_in_a_row(pipe):
    """Two pitched frames whose right lines lie 0.6 m apart at the car (beyond ``max_jump_m``)
    do not confirm each other: the run starts again, and the track starts two frames later."""
    lean = -1.5 / XM
    images = [frame(pipe, right_top_x=RIGHT_X + lean),
              frame(pipe, right_x=RIGHT_X + 0.6 / XM, right_top_x=RIGHT_X + 0.6 / XM + lean)]
    tracker = LaneTracker(pipe)
    found = [tracker.update(images[k]).found for k in (0, 0, 1, 1, 1)]
    assert found == [False, False, False, False, True]


def test_pitched_start_is_validated():
    with pytest.raises(ConfigError, match="max_pitch_change"):
        TrackerConfig(max_pitch_change=1.0)
    with pytest.raises(ConfigError, match="pitched_start_frames"):
        TrackerConfig(pitched_start_frames=-1)


@pytest.mark.slow
@pytest.mark.udacity
def test_the_challenge_video_lane_is_found_from_its_first_frames(udacity_calibration):
    """The Udacity challenge video (the highway camera, its flat view pitched: every lane
    narrows ahead by about 40 % there) acquires the lane by its third frame, on the yellow line
    and the white dashes (about 3.5 m wide at the car), and holds it."""
    from lanelib import data
    from lanelib.io import VideoReader

    path = data.challenge_video()
    if path is None:
        pytest.skip(data.missing_reason(data.CHALLENGE_VIDEO))
    tracker = LaneTracker(LanePipeline(PipelineConfig(), udacity_calibration))
    with VideoReader(path) as reader:
        results = [tracker.update(image) for _, image in zip(range(8), reader)]
    assert all(r.found for r in results[2:])
    for r in results[2:]:
        assert 3.2 <= r.lane_width_m <= 3.8 and abs(r.offset_m) < 0.6
