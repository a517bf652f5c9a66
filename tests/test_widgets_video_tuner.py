"""``VideoTuner``: the tracker's parameters on a clip, the tracked frame, the strip, save and play."""
from __future__ import annotations

import json
from pathlib import Path

import ipywidgets
import numpy as np
import pytest

from lanelib import io, widgets
from lanelib.config import PipelineConfig, load_config, save_config
from lanelib.errors import InputError
from lanelib.params import SearchConfig
from lanelib.tracking import LaneTracker

REPO = Path(__file__).resolve().parents[1]
CLIP = REPO / "videos" / "project.mp4"
STRAIGHT = REPO / "test_images" / "straight_1.jpg"
N = 30  # frames tracked: enough for the tracker, fast for the tests



@pytest.fixture
def tuner(camera):
    return widgets.VideoTuner({"project": CLIP}, calibration=camera, max_frames=N)


def test_the_controls_exist_and_show_the_config(tuner):
    tc, cc = tuner.config.tracking, tuner.config.checks
    c = tuner.controls
    assert set(c) == {"tracking.smooth_frames", "tracking.recency_decay", "tracking.hold_frames",
                      "tracking.max_jump_m", "tracking.base_history_frames", "tracking.min_base_peak",
                      "tracking.trend_frames", "tracking.blind_hold_frames", "tracking.max_gap_m",
                      "checks.width_m", "max_frames"}
    assert (c["tracking.trend_frames"].value, c["tracking.blind_hold_frames"].value,
            c["tracking.max_gap_m"].value) == (tc.trend_frames, tc.blind_hold_frames, tc.max_gap_m) == (0, 0, 12.0)
    assert c["tracking.base_history_frames"].value == tc.base_history_frames == 0  # off by default
    assert c["tracking.min_base_peak"].value == tc.min_base_peak
    assert (c["tracking.smooth_frames"].value, c["tracking.hold_frames"].value) == (tc.smooth_frames,
                                                                                    tc.hold_frames)
    assert c["tracking.recency_decay"].value == tc.recency_decay
    assert c["tracking.max_jump_m"].value == tc.max_jump_m
    assert isinstance(c["checks.width_m"], ipywidgets.FloatRangeSlider)
    assert c["checks.width_m"].value == (cc.min_width_m, cc.max_width_m)
    assert c["max_frames"].value == N == tuner.max_frames
    assert c["max_frames"].max == io.video_info(CLIP).n_frames
    assert "lanelib-slider-tracking-hold_frames" in c["tracking.hold_frames"]._dom_classes
    assert tuner.parts == ("tracking", "checks")
    assert tuner.frame_slider.max == N - 1 and tuner.frame_slider in tuner.widget.children


def test_every_frame_of_the_project_clip_is_found(tuner):
    assert tuner.runs == 1 and len(tuner.results) == len(tuner.frames) == N
    assert all(r.found for r in tuner.results)
    assert np.array_equal(tuner.frames[0], io.read_frame(CLIP, 0))
    text = tuner.readout()
    assert f"tracked {N} frames (1.2 s): lane found in {N} of {N}, held 0" in text
    assert "frame 0: windows, lane found, offset +0.09 m, width 3.71 m" in text


def test_a_tracker_parameter_re_runs_the_tracker(tuner):
    tuner.controls["tracking.hold_frames"].value = 4
    assert tuner.config.tracking.hold_frames == 4 and tuner.runs == 2
    tuner.controls["tracking.smooth_frames"].value = 2
    tuner.controls["tracking.recency_decay"].value = 0.8
    assert (tuner.config.tracking.smooth_frames, tuner.config.tracking.recency_decay) == (2, 0.8)
    assert tuner.runs == 4 and len(tuner.results) == N
    tuner.controls["checks.width_m"].value = (3.2, 4.2)
    assert (tuner.config.checks.min_width_m, tuner.config.checks.max_width_m) == (3.2, 4.2)
    assert tuner.runs == 5
    tuner.controls["tracking.base_history_frames"].value = 30
    tuner.controls["tracking.min_base_peak"].value = 4.5
    assert (tuner.config.tracking.base_history_frames, tuner.config.tracking.min_base_peak) == (30, 4.5)
    assert tuner.runs == 7
    tuner.controls["tracking.trend_frames"].value = 5
    tuner.controls["tracking.blind_hold_frames"].value = 20
    tuner.controls["tracking.max_gap_m"].value = 18.0
    assert (tuner.config.tracking.trend_frames, tuner.config.tracking.blind_hold_frames,
            tuner.config.tracking.max_gap_m) == (5, 20, 18.0)
    assert tuner.runs == 10


def test_narrow_width_bounds_lose_the_lane_and_say_why(tuner):
    tuner.controls["checks.width_m"].value = (3.8, 4.5)  # the clip's lane is 3.7 m wide
    assert not any(r.found for r in tuner.results)
    assert f"lane found in 0 of {N}" in tuner.readout()
    assert "outside 3.8-4.5 m" in tuner.readout()


def test_moving_the_frame_does_not_re_run_the_tracker(tuner):
    results, runs, bytes0 = tuner.results, tuner.runs, tuner.preview.value
    tuner.frame_slider.value = 20
    assert tuner.frame == 20 and tuner.runs == runs and tuner.results is results
    assert np.array_equal(tuner.raw, tuner.frames[20])
    assert tuner.preview.value != bytes0 and "frame 20: prior" in tuner.readout()
    tuner.frame = 0
    assert tuner.preview.value == bytes0
    with pytest.raises(InputError, match=rf"frame {N} is outside the tracked frames \(0\.\.{N - 1}\)"):
        tuner.frame = N


def test_max_frames_changes_the_frames_tracked(tuner):
    tuner.controls["max_frames"].value = 10
    assert len(tuner.results) == 10 and tuner.frame_slider.max == 9 and tuner.runs == 2
    tuner.controls["max_frames"].value = N  # from the cached frames
    assert len(tuner.results) == N and tuner.runs == 3


def test_the_strip_has_its_size_and_its_marker_follows_the_frame(tuner):
    s0 = tuner.strip()
    assert s0.shape == (160, 1200, 3) and s0.dtype == np.uint8
    x0, x1 = tuner.strip_x(0), tuner.strip_x(N - 1)
    assert 0 <= x0 < x1 < 1200
    assert (s0[:, x0] == 255).all()
    tuner.frame = N - 1
    s1 = tuner.strip()
    assert (s1[:, x1] == 255).all() and not (s1[:, x0] == 255).all()
    assert tuner.strip((600, 100)).shape == (100, 600, 3)
    sheet = tuner.preview_sheet()
    assert sheet.shape[1] == tuner.tile_width_px and sheet.shape[0] > tuner.composite.shape[0] * 800 // 1280


def test_the_composite_is_that_of_a_kept_images_run(tuner, camera):
    """Re-thresholding the shown frame gives the composite a keep_images run draws."""
    tuner.frame = 12
    tracker = LaneTracker(tuner.pipeline)
    for i, f in enumerate(tuner.frames[:13]):
        r = tracker.update(f, keep_images=(i == 12))
    assert np.array_equal(tuner.composite, tuner.pipeline.debug_composite(r, raw=tuner.frames[12]))


def test_save_writes_tracking_and_checks_and_keeps_the_rest(tuner, tmp_path):
    path = tmp_path / "tuned.json"
    other = PipelineConfig(search=SearchConfig(margin_px=77))
    save_config(other, path)
    tuner.controls["tracking.hold_frames"].value = 7
    tuner.controls["checks.width_m"].value = (3.1, 4.4)
    tuner.save(path)
    saved = load_config(path)
    assert saved.tracking == tuner.config.tracking and saved.tracking.hold_frames == 7
    assert (saved.checks.min_width_m, saved.checks.max_width_m) == (3.1, 4.4)
    assert saved.search.margin_px == 77
    held = json.loads(path.read_text())
    assert held["tracking"]["hold_frames"] == 7


def test_load_puts_the_file_into_the_sliders(tuner, tmp_path):
    path = tmp_path / "tuned.json"
    path.write_text(json.dumps({"tracking": {"smooth_frames": 3}, "checks": {"max_width_m": 4.0}}))
    tuner.load(path)
    assert tuner.controls["tracking.smooth_frames"].value == 3
    assert tuner.controls["checks.width_m"].value == (3.0, 4.0)
    assert tuner.config.tracking.smooth_frames == 3 and tuner.runs == 2


def test_an_image_is_refused(camera):
    with pytest.raises(InputError, match=r"VideoTuner: straight \(straight_1.jpg\) not a video; the "
                                         r"tracker needs a clip"):
        widgets.VideoTuner({"clip": CLIP, "straight": STRAIGHT}, calibration=camera, max_frames=N)
    with pytest.raises(InputError, match="max_frames=0"):
        widgets.VideoTuner({"clip": CLIP}, max_frames=0)


def test_play_writes_the_tracked_frames_and_returns_a_video(tuner, tmp_path):
    out = tmp_path / "sub" / "tuned.mp4"
    video = tuner.play(out)
    info = io.video_info(out)
    assert (info.n_frames, info.size, info.fps) == (N, (1280, 720), io.video_info(CLIP).fps)
    assert isinstance(video, ipywidgets.Video) and video.format == "mp4"
    assert video.value == out.read_bytes()
    assert repr(video) == "TunedVideo('tuned.mp4', frames=30)"
    assert video._repr_mimebundle_()["text/plain"] == repr(video)
    assert [p.name for p in out.parent.iterdir()] == ["tuned.mp4"]  # no temporary file left
    with pytest.raises(InputError, match="needs a video suffix"):
        tuner.play(tmp_path / "tuned.txt")
    with pytest.raises(InputError, match="output would overwrite an input"):
        tuner.play(CLIP)


def test_play_keeps_a_short_small_clip_when_asked(tuner, tmp_path):
    """``seconds`` keeps the first tracked frames, ``width_px`` scales them (even sizes for H.264)."""
    out = tmp_path / "short.mp4"
    video = tuner.play(out, seconds=0.4, width_px=641)  # 10 frames at 25 fps
    info = io.video_info(out)
    assert (info.n_frames, info.size) == (10, (640, 360))
    assert repr(video) == "TunedVideo('short.mp4', frames=10)" and video.value == out.read_bytes()
    assert tuner.play(out, seconds=60).frames == N  # no more than were tracked
    for bad in ({"seconds": 0}, {"seconds": float("nan")}, {"seconds": True}, {"width_px": 8},
                {"width_px": 640.0}):
        with pytest.raises(InputError, match="VideoTuner.play: (seconds|width_px)="):
            tuner.play(out, **bad)
