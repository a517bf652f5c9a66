"""``compare.compare_methods``: every method scored on every source, and the frames seen on the way."""
from __future__ import annotations

import numpy as np

from lanelib import compare, data
from lanelib.config import PipelineConfig, override
from lanelib.evaluate import calibration_from_truth, evaluate_video
from lanelib.pipeline import LanePipeline

ROOT = data.repo_root()
CLIP = ROOT / "videos" / "harder.mp4"
N = 6


def test_each_method_is_scored_and_each_frame_is_seen_with_every_methods_result():
    methods = {"default": (), "blind hold": ("tracking.blind_hold_frames=12",)}
    seen = []
    scores = compare.compare_methods(methods, [CLIP, ROOT / "test_images"], max_frames=N,
                                     on_frame=lambda src, i, raw, res: seen.append((src, i, raw.shape, res)))
    assert [(s.source, s.method) for s in scores] == [(str(CLIP), "default"), (str(CLIP), "blind hold"),
                                                      (str(ROOT / "test_images"), "default"),
                                                      (str(ROOT / "test_images"), "blind hold")]
    # a tracker-only switch is not run on single images, and says so
    assert scores[3].report is None and scores[3].skipped == "tracker only" and scores[2].report.frames == N
    # the callback sees the video's frames in order (not the images), each with both methods' results
    assert [i for _, i, _, _ in seen] == list(range(N)) and {s for s, _, _, _ in seen} == {CLIP}
    assert all(shape == (720, 1280, 3) and set(res) == set(methods) for _, _, shape, res in seen)
    # the results it sees are the ones scored: the same as the method's own evaluation, frame by frame
    found = np.array([res["default"][1].found for _, _, _, res in seen])
    assert np.array_equal(found, scores[0].report.found)
    alone = evaluate_video(CLIP, LanePipeline(PipelineConfig(), calibration_from_truth(CLIP)), max_frames=N)
    assert np.array_equal(alone.found, scores[0].report.found)
    assert np.allclose(alone.offset_err_cm, scores[0].report.offset_err_cm, equal_nan=True)
    pipe = seen[0][3]["blind hold"][0]
    assert pipe.config == override(PipelineConfig(), methods["blind hold"])
