"""Tuners on a video: the picker takes video files too, and a frame slider picks the frame shown.

The frame is read by seeking (``io.read_frame``); the tuner's hooks (``_prepare``, ``_update``)
treat it as they treat an image.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lanelib import io, widgets
from lanelib.errors import InputError

REPO = Path(__file__).resolve().parents[1]
CLIP = REPO / "videos" / "project.mp4"
STRAIGHT = REPO / "test_images" / "straight_1.jpg"


@pytest.fixture(scope="module")
def items():
    """A video first, then an image, as the picker's {label: path}."""
    return {"clip": CLIP, "straight": STRAIGHT}


@pytest.mark.parametrize("cls", [widgets.ThresholdTuner, widgets.HoughTuner])
def test_a_video_shows_a_frame_slider_that_the_preview_follows(cls, items):
    t = cls(items)
    n = io.video_info(CLIP).n_frames
    s = t.frame_slider
    assert (s.min, s.max, s.value, s.continuous_update) == (0, n - 1, 0, False)
    assert s.layout.display != "none" and t.is_video and t.frame == 0
    assert "lanelib-slider-frame" in s._dom_classes and s in t.widget.children
    assert np.array_equal(t.raw, io.read_frame(CLIP, 0))
    config, bytes0 = t.config, t.preview.value

    s.value = 100  # what releasing the slider in the browser does
    assert t.frame == 100
    assert np.array_equal(t.raw, io.read_frame(CLIP, 100))
    assert t.preview.value != bytes0
    assert t.config == config  # a frame is not a setting

    t.frame = 0  # the property sets the slider
    assert s.value == 0 and t.preview.value == bytes0  # the same frame, the same preview

    t.picker.value = "straight"  # an image: no slider
    assert s.layout.display == "none" and not t.is_video and t.frame == 0
    assert np.array_equal(t.raw, io.read_image(STRAIGHT))
    with pytest.raises(InputError, match="straight_1.jpg: the picked item is an image, it has no "
                                         "frames; pick a video"):
        t.frame = 3

    t.picker.value = "clip"  # back to the video: from its first frame
    assert s.layout.display != "none" and t.frame == 0 and t.preview.value == bytes0


def test_a_control_change_on_a_video_frame_keeps_the_frame(items):
    t = widgets.ThresholdTuner(items)
    t.frame = 120
    t.controls["white.range1"].value = (215, 255)
    assert t.frame == 120 and np.array_equal(t.raw, io.read_frame(CLIP, 120))
    assert t.config.thresholds.white.low == (0, 215, 0)


def test_a_frame_outside_the_video_is_refused_with_the_range(items):
    t = widgets.HoughTuner(items)
    for bad in (250, -1, 2.5):
        with pytest.raises(InputError, match=r"project.mp4: frame .* is outside the video "
                                             r"\(frames 0\.\.249\); pass an index in that range"):
            t.frame = bad
    assert t.frame == 0


@pytest.mark.parametrize("cls", [widgets.ThresholdTuner, widgets.HoughTuner])
def test_a_corrupt_video_is_an_input_error_naming_the_file(cls, tmp_path):
    bad = tmp_path / "broken.mp4"
    bad.write_bytes(b"\x00" * 5000)
    with pytest.raises(InputError, match=r"broken.mp4: not a readable video \(.*\); pass a valid video"):
        cls({"broken": bad})
    t = cls({"straight": STRAIGHT, "broken": bad})
    t.picker.value = "broken"  # picked in the browser: the readout says why, the image stays
    assert t.image == "straight" and "broken.mp4: not a readable video" in t.error


def test_video_choices_lists_the_bundled_videos_and_image_choices_keeps_its_default():
    videos = widgets.video_choices()
    assert videos == {f"videos/{p.name}": p for p in sorted((REPO / "videos").glob("*.mp4"))}
    assert "videos/project.mp4" in videos
    images = widgets.image_choices()
    assert not any(widgets.base.is_video(p) for p in images.values())
    assert widgets.image_choices(videos=True) == {**images, **videos}


def test_the_other_tuners_take_a_video_too(items):
    for cls in (widgets.FitTuner, widgets.PerspectiveTuner):
        t = cls(items, image="clip")
        bytes0 = t.preview.value
        t.frame = 200
        assert np.array_equal(t.raw, io.read_frame(CLIP, 200)) and t.preview.value != bytes0, cls
