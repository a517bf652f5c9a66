"""Tests of the bird's-eye points refined from the lines a camera sees (``batch.refine``,
``lines.refine_points_px``): on rendered CULane frames whose camera is known exactly, points set
for a camera pitched or turned otherwise are moved back to where the camera's road vanishes, the
true points are kept, and ``predict`` says what it did and finds more of the labelled lines."""
from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from lanelib import batch, config, io
from lanelib.batch.refine import MIN_LINES, PointsRefinement, refine_points, sequence_refinement, shifted_points
from lanelib.camera import Calibration
from lanelib.benchmarks import culane, why
from lanelib.cli import main
from lanelib.config import PipelineConfig
from lanelib.synth.datasets import CULANE_DESIGNS, CULANE_SIZE, write_dataset
from lanelib.synth.truth import perspective_truth


@pytest.fixture(scope="module")
def sample(tmp_path_factory) -> Path:
    """Six rendered CULane frames of one sequence (the camera of ``CULANE_DESIGNS[0]``)."""
    root = tmp_path_factory.mktemp("culane_one")
    write_dataset("culane", root, 6, per_sequence=6)
    return root


@pytest.fixture(scope="module")
def frames(sample) -> list[np.ndarray]:
    return [io.read_image(p) for p in sorted(sample.rglob("*.jpg"))]


@pytest.fixture(scope="module")
def true_config() -> PipelineConfig:
    """The culane preset's search with the rendered camera's exact bird's-eye points."""
    design = CULANE_DESIGNS[0]
    truth = perspective_truth(design.camera(CULANE_SIZE), design.lane_width_m).config()
    preset = config.preset("culane")
    return replace(preset, perspective=truth, lines=replace(preset.lines, refine_points_px=6.0))


def test_the_true_points_are_kept(frames, true_config):
    r = refine_points(frames, true_config, None, "seq")
    assert not r.moved and r.shift_px == (0.0, 0.0) and r.lines >= MIN_LINES
    dx, dy = r.meeting_px
    assert abs(dx) <= 6 and abs(dy) <= 2, r  # the lines meet where the road vanishes
    assert "within 6 px" in r.note() and r.note().startswith("seq: bird's-eye points kept")


@pytest.mark.parametrize("off", [(0.0, -15.0), (0.0, 15.0), (40.0, 0.0)])
def test_points_of_a_camera_pitched_or_turned_otherwise_move_back(frames, true_config, off):
    # points set 15 px too high (or low), or 40 px aside: the camera sees its road vanish there
    r = refine_points(frames, shifted_points(true_config, off), None, "seq")
    assert r.moved and r.shift_px == r.meeting_px
    assert abs(r.shift_px[0] + off[0]) <= 6 and abs(r.shift_px[1] + off[1]) <= 2, r
    assert "bird's-eye points moved by" in r.note()


def test_frames_without_lines_keep_the_points(true_config):
    road = [np.full((590, 1640, 3), 90, np.uint8)] * 3
    r = refine_points(road, true_config, None, "seq")
    assert r == PointsRefinement("seq", None, (0.0, 0.0), 0, f"0 lines to tell from, fewer than {MIN_LINES}")


def test_frames_the_calibration_does_not_fit_keep_the_points_with_the_reason(sample, true_config):
    images = sorted(sample.rglob("*.jpg"))
    square = Calibration(np.eye(3) * [1000, 1000, 1], np.zeros(5), (1000, 1000))  # another aspect
    r = sequence_refinement(images, true_config, square, "seq")
    assert not r.moved and r.meeting_px is None
    assert r.reason.startswith("frame is 1640x590 but the calibration is for 1000x1000 with another aspect")
    assert sequence_refinement([sample / "missing.jpg"], true_config, None, "seq").reason == (
        "none of its images could be read")


def test_predict_moves_each_sequences_points_and_finds_more_lines(tmp_path, sample, true_config, capsys):
    wrong = shifted_points(true_config, (0.0, -15.0))
    (tmp_path / "wrong.json").write_text(json.dumps(config.to_dict(wrong)))
    listed = sample / "list" / "test.txt"

    def predicted(name: str, *extra: str) -> int:
        out = tmp_path / name
        assert main(["predict", "culane", str(sample), "-o", str(out), "--no-progress",
                     "--config", str(tmp_path / "wrong.json"), *extra]) == 0
        return culane.evaluate(sample, listed, out).counts.tp

    refined = predicted("refined")
    printed = capsys.readouterr().out
    assert re.search(r"bird's-eye points moved by \([+-]\d+, \+1[4-6]\) px \(its lines meet", printed), printed
    fixed = predicted("fixed", "--set", "lines.refine_points_px=0")
    assert "bird's-eye points" not in capsys.readouterr().out
    assert refined > fixed
    run = batch.predict_benchmark("culane", sample, tmp_path / "library", config=wrong, progress=False)
    assert [r.moved for r in run.refinements] == [True]


def test_why_sees_each_sequence_through_the_points_predict_gives_it(tmp_path, sample, true_config, capsys):
    """``why`` moves the points as ``predict`` does: the frames it explains find as many labelled
    lines as ``predict`` with the refinement, more than with the points kept, and it prints the
    move, for the set and for one frame named."""
    wrong = shifted_points(true_config, (0.0, -15.0))
    (tmp_path / "wrong.json").write_text(json.dumps(config.to_dict(wrong)))
    listed = sample / "list" / "test.txt"
    assert main(["predict", "culane", str(sample), "-o", str(tmp_path / "pred"), "--no-progress",
                 "--config", str(tmp_path / "wrong.json")]) == 0
    tp = culane.evaluate(sample, listed, tmp_path / "pred").counts.tp
    capsys.readouterr()
    explained = why.explain_set("culane", sample, wrong, listed, on_points=lambda r: print(r.note()))
    assert re.search(r"bird's-eye points moved by \([+-]\d+, \+1[4-6]\) px", capsys.readouterr().out)
    assert explained.counts()[why.FOUND][0] == tp
    kept = why.explain_set("culane", sample, replace(wrong, lines=replace(wrong.lines, refine_points_px=0)), listed)
    assert kept.counts()[why.FOUND][0] < tp
    frame = sorted(sample.rglob("*.jpg"))[0]
    assert main(["why", "culane", str(frame), "--root", str(sample), "-o", str(tmp_path / "png"),
                 "--config", str(tmp_path / "wrong.json")]) == 0
    assert re.search(r"bird's-eye points moved by \([+-]\d+, \+1[4-6]\) px", capsys.readouterr().out)
