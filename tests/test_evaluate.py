"""Tests of lanelib.evaluate: TuSimple point accuracy, FP/FN, error arithmetic, the CLI."""
from __future__ import annotations

import json
from pathlib import Path
import math
import shutil

import cv2
import numpy as np
import pytest

from lanelib import cli
from lanelib.evaluate import (MATCH_ACCURACY, SUMMARY_KEYS, EvalReport, calibration_from_truth,
                              fit_x_in_raw, in_view, line_accuracy, line_threshold_px, score_frame,
                              score_lines, truth_calibration)
from lanelib.pipeline import LanePipeline
from lanelib.records import LineFit
from lanelib.result import FrameResult
from lanelib.synth.camera import Camera
from lanelib.synth.truth import LaneTruth, camera_truth, load_image_truth, load_video_truth

REPO = Path(__file__).resolve().parents[1]

ROWS = np.arange(420.0, 720.0, 10.0)  # 30 rows, as the synthetic truth's h_samples


# --------------------------------------------------------------------------- point accuracy

def test_perfect_prediction_has_accuracy_one():
    gt = 300.0 + 0.8 * (ROWS - 420)
    assert line_accuracy(gt.copy(), gt, line_threshold_px(gt, ROWS)) == 1.0


def test_vertical_line_shifted_25px_has_accuracy_zero_and_15px_one():
    gt = np.full(len(ROWS), 400.0)
    thr = line_threshold_px(gt, ROWS)
    assert thr == pytest.approx(20.0)
    assert line_accuracy(gt + 25.0, gt, thr) == 0.0
    assert line_accuracy(gt - 25.0, gt, thr) == 0.0
    assert line_accuracy(gt + 15.0, gt, thr) == 1.0


def test_threshold_widens_with_the_slant_of_the_truth_line():
    # a 45 degree line: 20 px across it is 20 / cos(45 deg) = 28.28 px along a row (TuSimple)
    gt = 200.0 + (ROWS - 420)
    thr = line_threshold_px(gt, ROWS)
    assert thr == pytest.approx(20.0 * math.sqrt(2.0))
    assert line_accuracy(gt + 25.0, gt, thr) == 1.0
    assert line_accuracy(gt + 30.0, gt, thr) == 0.0


def test_accuracy_counts_only_scored_truth_points_and_misses_where_prediction_ends():
    gt = np.full(len(ROWS), 400.0)
    gt[:10] = np.nan                      # 20 scored points
    pred = gt.copy()
    pred[10:15] = np.nan                  # prediction does not reach 5 of them
    pred[15:20] += 40.0                   # 5 more are off
    assert line_accuracy(pred, gt, 20.0) == pytest.approx(10 / 20)
    assert math.isnan(line_accuracy(pred, np.full(len(ROWS), np.nan), 20.0))


# --------------------------------------------------------------------------- FP / FN

def _lines():
    left = np.full(len(ROWS), 300.0)
    right = np.full(len(ROWS), 900.0)
    return left, right


def test_both_lines_found_no_fp_no_fn():
    left, right = _lines()
    s = score_lines([left + 3, right - 3], [left, right], ROWS)
    assert s.accuracy == (1.0, 1.0)
    assert (s.pred_lines, s.gt_lines, s.fp_lines, s.fn_lines) == (2, 2, 0, 0)


def test_missing_line_is_a_false_negative():
    left, right = _lines()
    s = score_lines([left], [left, right], ROWS)
    assert s.accuracy == (1.0, 0.0)
    assert (s.pred_lines, s.gt_lines, s.fp_lines, s.fn_lines) == (1, 2, 0, 1)
    s = score_lines([], [left, right], ROWS)
    assert (s.fp_lines, s.fn_lines) == (0, 2)


def test_line_in_the_wrong_place_is_both_fp_and_fn():
    left, right = _lines()
    s = score_lines([left, right + 100.0], [left, right], ROWS)
    assert s.accuracy == (1.0, 0.0)
    assert (s.fp_lines, s.fn_lines) == (1, 1)


def test_match_needs_tusimple_share_of_points():
    left, right = _lines()
    n = len(ROWS)
    k = math.ceil(MATCH_ACCURACY * n)     # 26 of 30 points hit: matched
    pred = right.copy()
    pred[k:] += 50.0
    assert score_lines([left, pred], [left, right], ROWS).fn_lines == 0
    pred = right.copy()
    pred[k - 1:] += 50.0                  # 25 of 30 (0.833): not matched
    s = score_lines([left, pred], [left, right], ROWS)
    assert s.accuracy[1] == pytest.approx((k - 1) / n)
    assert (s.fp_lines, s.fn_lines) == (1, 1)


def test_truth_line_out_of_view_is_not_counted_and_a_line_there_is_a_fp():
    left, right = _lines()
    s = score_lines([left, right], [left, np.full(len(ROWS), np.nan)], ROWS)
    assert math.isnan(s.accuracy[1])
    assert (s.pred_lines, s.gt_lines, s.fp_lines, s.fn_lines) == (2, 1, 1, 0)


# --------------------------------------------------------------------------- raw-image mapping

@pytest.fixture(scope="module")
def true_pipeline():
    """A pipeline with the synthetic camera's true calibration and exact perspective points."""
    from lanelib.config import PipelineConfig

    cam = camera_truth(Camera())
    config = PipelineConfig(perspective=cam.perspective.config())
    return LanePipeline(config, cam.calibration())


def _projected_line_x(x_m: float, rows: np.ndarray) -> np.ndarray:
    """Return the raw-image x of the road line x = x_m (car frame, straight ahead) at ``rows``."""
    z = np.linspace(4.0, 60.0, 4000)
    uv = Camera().project(np.column_stack([np.full_like(z, x_m), np.zeros_like(z), z]))
    order = np.argsort(uv[:, 1])
    return np.interp(rows, uv[order, 1], uv[order, 0], left=np.nan, right=np.nan)


def test_birdseye_fit_maps_onto_the_cameras_projection_of_the_line(true_pipeline):
    # The exact src points put a straight 3.7 m lane centred on the car at dst x = 320 and 960.
    rows = np.arange(470.0, 700.0, 10.0)
    for x_m, x_px in ((-1.85, 320.0), (1.85, 960.0)):
        truth = _projected_line_x(x_m, rows)
        pred = fit_x_in_raw((0.0, 0.0, x_px), true_pipeline, rows)
        assert np.all(np.isfinite(truth))
        assert np.max(np.abs(pred - truth)) < 0.5


def test_fit_has_no_x_above_the_birdseye_view(true_pipeline):
    pred = fit_x_in_raw((0.0, 0.0, 320.0), true_pipeline, np.array([420.0, 440.0, 500.0]))
    assert np.isnan(pred[:2]).all() and np.isfinite(pred[2])


def test_fit_leaves_out_what_the_lens_folds_back(true_pipeline):
    # 3000 px left of the bird's-eye view: most of the line lies far outside the frame, where the
    # lens polynomial turns back and folds points into the raw frame
    rows = np.arange(420.0, 720.0, 10.0)
    h = true_pipeline.size[1]
    yb = np.linspace(-0.05 * h, 1.05 * h, 2 * h)
    pts = np.column_stack([np.full_like(yb, -3000.0), yb])
    raw = true_pipeline.lens(true_pipeline.perspective.inverse(pts))  # no rule
    ok = true_pipeline.birdseye_to_raw.valid(pts)
    inside = (raw[:, 0] >= 0) & (raw[:, 0] < 1280) & (raw[:, 1] >= 0) & (raw[:, 1] < 720)
    assert (inside & ~ok).sum() > 50  # folded back into the frame
    # read without the rule, the line would have an x on most rows; with it, on none
    order = np.argsort(raw[:, 1])
    unguarded = np.interp(rows, raw[order, 1], raw[order, 0], left=np.nan, right=np.nan)
    assert np.isfinite(unguarded).sum() > 20
    assert np.isnan(fit_x_in_raw((0.0, 0.0, -3000.0), true_pipeline, rows)).all()
    # the rule is the lens's, on the undistorted points of the chain bird's-eye -> raw
    assert np.array_equal(ok, true_pipeline.lens.valid(true_pipeline.perspective.inverse(pts)))
    assert 0 < ok.sum() < len(pts)


def test_calibration_from_truth_is_the_truths_camera():
    first = load_image_truth(sorted((REPO / "test_images").glob("*.jpg"))[0]).camera
    for cal in (calibration_from_truth(REPO / "test_images"), truth_calibration(first)):
        assert np.array_equal(cal.camera_matrix, first.calibration().camera_matrix)
        assert np.array_equal(cal.dist_coeffs, first.calibration().dist_coeffs)
        assert cal.image_size == (1280, 720)
    clip = REPO / "videos" / "project.mp4"
    assert np.array_equal(calibration_from_truth(clip).camera_matrix,
                          load_video_truth(clip).camera.calibration().camera_matrix)


def test_only_truth_points_inside_the_birdseye_view_are_scored(true_pipeline):
    rows = np.array([430.0, 450.0, 500.0, 600.0, 600.0])
    xs = np.array([600.0, 600.0, 500.0, 400.0, 5.0])  # above the view, above, in, in, left of it
    assert in_view(true_pipeline, xs, rows).tolist() == [False, False, True, True, False]


def _truth_of_straight_lane(offset_m: float = 0.0) -> LaneTruth:
    """Return the LaneTruth of a straight 3.7 m lane, projected by the synthetic camera."""
    rows = tuple(int(r) for r in ROWS)
    lines = [tuple(float(v) if np.isfinite(v) else -2.0
                   for v in _projected_line_x(x_m - offset_m, ROWS)) for x_m in (-1.85, 1.85)]
    return LaneTruth(0.0, math.inf, offset_m, 0.0, 3.7, rows, lines[0], lines[1])


def _result(pipe, left, right) -> FrameResult:
    fits = [LineFit(c, 1000, 700.0) if c is not None else LineFit(None, reason="test") for c in (left, right)]
    return FrameResult(fits[0], fits[1], pipe.measure(*fits), "windows", 1.0, 1.0)


def test_score_frame_perfect_and_shifted_prediction(true_pipeline):
    lane = _truth_of_straight_lane()
    perfect = score_frame(true_pipeline, _result(true_pipeline, (0, 0, 320.0), (0, 0, 960.0)), lane)
    assert perfect.accuracy == (1.0, 1.0)
    assert (perfect.fp_lines, perfect.fn_lines, perfect.gt_lines) == (0, 0, 2)
    # 60 bird's-eye px (0.35 m) to the right: far more than 20 px across the line near the car
    shifted = score_frame(true_pipeline, _result(true_pipeline, (0, 0, 380.0), None), lane)
    assert shifted.accuracy[0] < MATCH_ACCURACY and shifted.accuracy[1] == 0.0
    assert (shifted.pred_lines, shifted.fp_lines, shifted.fn_lines) == (1, 1, 2)


# --------------------------------------------------------------------------- error arithmetic

def _report(**over) -> EvalReport:
    n = 5
    base = dict(
        source="set", detector="frame", names=tuple(str(i) for i in range(n)),
        found=np.array([True, True, True, True, False]),
        offset_true_m=np.array([0.10, -0.20, 0.00, 0.30, 0.0]),
        offset_pred_m=np.array([0.13, -0.25, 0.00, 0.20, np.nan]),
        curvature_true_per_m=np.array([0.002, -0.0005, 0.0, 1e-4, 0.0]),
        curvature_pred_per_m=np.array([0.0022, -0.0004, 3e-5, 1e-4, np.nan]),
        radius_true_m=np.array([500.0, 2000.0, math.inf, 10000.0, math.inf]),
        radius_pred_m=np.array([550.0, 1500.0, 33333.0, 10000.0, np.nan]),
        lane_width_true_m=np.full(n, 3.7), lane_width_pred_m=np.full(n, 3.7),
        line_accuracy=np.array([[1.0, 1.0], [1.0, 0.5], [np.nan, 1.0], [1.0, 1.0], [0.0, 0.0]]),
        pred_lines=np.array([2, 2, 2, 2, 0]), gt_lines=np.array([2, 2, 1, 2, 2]),
        fp_lines=np.array([0, 1, 1, 0, 0]), fn_lines=np.array([0, 1, 0, 0, 2]))
    base.update(over)
    return EvalReport(**base)


def test_summary_arithmetic_on_constructed_errors():
    s = _report().summary()
    assert s["frames"] == 5
    assert s["found_rate"] == pytest.approx(0.8)
    # |offset errors| 3, 5, 0, 10 cm on the found frames
    assert s["offset_err_cm_median"] == pytest.approx(4.0)
    assert s["offset_err_cm_p95"] == pytest.approx(np.percentile([3.0, 5.0, 0.0, 10.0], 95))
    # |curvature errors| 2e-4, 1e-4, 3e-5, 0
    assert s["curvature_err_median"] == pytest.approx(6.5e-5)
    # radius error only on curves (true radius <= 3 km): 10 % and 25 %
    assert s["radius_err_pct_median"] == pytest.approx(17.5)
    # frame accuracies 1, 0.75, 1, 1, 0
    assert s["point_accuracy"] == pytest.approx(3.75 / 5)
    # per-frame FP rate 0, 1/2, 1/2, 0, 0 (no predicted line); FN 0, 1/2, 0, 0, 1
    assert s["fp_rate"] == pytest.approx(0.2)
    assert s["fn_rate"] == pytest.approx(0.3)


def test_offset_sign_errors_are_not_hidden():
    # truth right of centre, prediction as far left: the error is the full 40 cm
    r = _report(offset_true_m=np.full(5, 0.2), offset_pred_m=np.array([-0.2] * 4 + [np.nan]))
    assert r.summary()["offset_err_cm_median"] == pytest.approx(40.0)


def test_to_dict_has_the_keys_and_null_for_nothing_scored():
    d = _report(found=np.zeros(5, bool), offset_pred_m=np.full(5, np.nan),
                curvature_pred_per_m=np.full(5, np.nan), radius_pred_m=np.full(5, np.nan)).to_dict()
    assert tuple(d) == SUMMARY_KEYS
    assert d["found_rate"] == 0.0 and d["offset_err_cm_median"] is None
    json.dumps(d, allow_nan=False)


def test_table_shows_every_figure():
    text = _report().table()
    for label in ("frames", "lane found (%)", "80.0", "4.0", "6.5e-05", "17.5", "75.0", "20.0", "30.0"):
        assert label in text


# --------------------------------------------------------------------------- CLI on bundled data

TEST_IMAGES = REPO / "test_images"
PROJECT_VIDEO = REPO / "videos" / "project.mp4"


def _need(path):
    if not path.exists():
        pytest.fail(f"{path} is missing: the bundled synthetic data should be in the repo "
                    "(`python -m lanelib synth --all` makes it)")


def test_cli_images_prints_table_and_writes_json(tmp_path, capsys):
    _need(TEST_IMAGES)
    out = tmp_path / "eval.json"
    code = cli.main(["evaluate", "images", str(TEST_IMAGES), "--max-frames", "2", "--json", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert "point accuracy (%)" in printed and "false-negative lines (%)" in printed
    d = json.loads(out.read_text())
    assert tuple(d) == SUMMARY_KEYS
    assert d["frames"] == 2
    for k in ("found_rate", "point_accuracy", "fp_rate", "fn_rate"):
        assert 0.0 <= d[k] <= 1.0


def test_cli_video_per_frame_and_tracker(tmp_path, capsys):
    _need(PROJECT_VIDEO)
    for detector in ("frame", "tracker"):
        out = tmp_path / f"{detector}.json"
        code = cli.main(["evaluate", "video", str(PROJECT_VIDEO), "--max-frames", "25",
                         "--detector", detector, "--json", str(out)])
        assert code == 0
        assert f"({detector})" in capsys.readouterr().out
        assert json.loads(out.read_text())["frames"] == 25


def test_cli_missing_truth_exits_2_naming_the_file(tmp_path, capsys):
    _need(TEST_IMAGES)
    image = sorted(TEST_IMAGES.glob("*.jpg"))[0]
    shutil.copy(image, tmp_path / image.name)
    code = cli.main(["evaluate", "images", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert str(tmp_path / image.with_suffix(".json").name) in err


def test_cli_json_may_not_overwrite_a_truth_file(tmp_path, capsys):
    _need(TEST_IMAGES)
    image = sorted(TEST_IMAGES.glob("*.jpg"))[0]
    for f in (image, image.with_suffix(".json")):
        shutil.copy(f, tmp_path / f.name)
    truth = tmp_path / image.with_suffix(".json").name
    before = truth.read_bytes()
    code = cli.main(["evaluate", "images", str(tmp_path), "--json", str(truth)])
    assert code == 2 and "overwrite an input" in capsys.readouterr().err
    assert truth.read_bytes() == before


def test_cli_images_leaves_bad_files_out_of_the_scores_and_exits_1(tmp_path, capsys):
    _need(TEST_IMAGES)
    good = sorted(TEST_IMAGES.glob("*.jpg"))[:2]
    for image in good:
        for f in (image, image.with_suffix(".json")):
            shutil.copy(f, tmp_path / f.name)
    truth = good[0].with_suffix(".json")
    (tmp_path / "a_corrupt.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    shutil.copy(truth, tmp_path / "a_corrupt.json")
    shutil.copy(good[0], tmp_path / "b_no_truth.jpg")
    shutil.copy(good[0], tmp_path / "c_bad_truth.jpg")
    (tmp_path / "c_bad_truth.json").write_text('{"radius_m": ')
    shutil.copy(truth, tmp_path / "d_small.json")
    cv2.imwrite(str(tmp_path / "d_small.png"), np.zeros((72, 128, 3), np.uint8))
    out = tmp_path.parent / f"{tmp_path.name}.json"
    code = cli.main(["evaluate", "images", str(tmp_path), "--json", str(out)])
    captured = capsys.readouterr()
    assert code == 1
    errors = captured.err.strip().splitlines()
    assert len(errors) == 4 and all(e.startswith(f"error: {tmp_path}/") for e in errors)
    assert errors[0].startswith(f"error: {tmp_path / 'a_corrupt.jpg'}: not a readable image")
    assert errors[1].startswith(f"error: {tmp_path / 'b_no_truth.json'}: no ground truth beside "
                                "b_no_truth.jpg")
    assert errors[2].startswith(f"error: {tmp_path / 'c_bad_truth.json'}: not valid JSON")
    assert errors[3] == (f"error: {tmp_path / 'd_small.png'}: is 128x72 but the ground truth's camera "
                         "is 1280x720; score images rendered by that camera (regenerate them with "
                         "`python -m lanelib synth images`)")
    assert "4 of 6 files failed and are left out of the scores" in captured.out
    d = json.loads(out.read_text())
    assert tuple(d) == SUMMARY_KEYS and d["frames"] == 2 and d["files_failed"] == 4
    # the scores are those of the two good images alone
    clean = tmp_path.parent / f"{tmp_path.name}_clean"
    clean.mkdir()
    for image in good:
        for f in (image, image.with_suffix(".json")):
            shutil.copy(f, clean / f.name)
    assert cli.main(["evaluate", "images", str(clean), "--json", str(clean / "e.json")]) == 0
    clean_d = json.loads((clean / "e.json").read_text())
    assert clean_d == {**d, "files_failed": 0}
    assert "failed" not in capsys.readouterr().out


def test_table_counts_failed_files_only_when_there_are_some():
    assert "failed" not in _report().table()
    text = _report(failed=(("x.jpg", "x.jpg: broken"),)).table()
    assert text.splitlines()[-1] == "1 of 6 files failed and are left out of the scores"
    assert _report(failed=(("x.jpg", "x.jpg: broken"),)).to_dict()["files_failed"] == 1


def test_cli_set_overrides_the_config_of_a_run(tmp_path, capsys):
    _need(TEST_IMAGES)
    outs = {}
    for name, extra in (("plain", []), ("narrow", ["--set", "checks.max_width_m=3.2"])):
        outs[name] = tmp_path / f"{name}.json"
        code = cli.main(["evaluate", "images", str(TEST_IMAGES), "--max-frames", "2",
                         "--json", str(outs[name]), *extra])
        assert code == 0
    capsys.readouterr()
    # the bundled lanes are 3.7 m wide: a 3.2 m upper bound refuses every one of them
    assert json.loads(outs["plain"].read_text())["found_rate"] == 1.0
    assert json.loads(outs["narrow"].read_text())["found_rate"] == 0.0
    assert cli.main(["evaluate", "images", str(TEST_IMAGES), "--set", "checks.max_width=3"]) == 2
    assert "checks.max_width is not a key" in capsys.readouterr().err
