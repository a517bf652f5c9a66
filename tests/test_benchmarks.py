"""Tests of lanelib.benchmarks: the official TuSimple and CULane metrics on hand-computed cases,
the benchmark files (read, write, round trips, bad input) and ``evaluate tusimple|culane``."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from lanelib import cli, evaluate
from lanelib.benchmarks import culane, metrics, tusimple
from lanelib.benchmarks.metrics import (CULaneCounts, culane_image, interpolate_lane, iou_matrix,
                                        lane_mask, matched_pairs, tusimple_image, tusimple_score)
from lanelib.errors import InputError

H = list(range(160, 720, 10))  # 56 rows, TuSimple's h_samples for 1280x720
Y = np.asarray(H, float)


def vertical(x: float, missing_top: int = 0) -> list[float]:
    """A vertical TuSimple lane at ``x``, -2 on the first ``missing_top`` rows."""
    return [-2.0] * missing_top + [float(x)] * (len(H) - missing_top)


def slanted(x0: float, k: float, shift: float = 0.0) -> list[float]:
    """A straight TuSimple lane x = x0 + k*(y - 160) + shift."""
    return list(x0 + k * (Y - 160.0) + shift)


# --------------------------------------------------------------------------- TuSimple metric

def test_evaluate_shares_the_one_point_matching():
    assert evaluate.score_lines is metrics.score_lines
    assert evaluate.line_accuracy is metrics.line_accuracy
    assert evaluate.line_threshold_px is metrics.line_threshold_px


def test_tusimple_perfect_prediction():
    gt = [vertical(x) for x in (200, 500, 800, 1100)]
    assert tusimple_image(gt, gt, H, 10.0) == metrics.TuSimpleImage(1.0, 0.0, 0.0)


@pytest.mark.parametrize("shift, hit", [(19.0, True), (-19.0, True), (21.0, False), (-21.0, False)])
def test_tusimple_vertical_lane_shifted_19_px_is_hit_21_px_missed(shift, hit):
    gt = [vertical(400)]
    r = tusimple_image([vertical(400 + shift)], gt, H)
    # hit: every row within 20 px; missed: no row, the truth lane is FN and the prediction FP
    assert (r.accuracy, r.fp, r.fn) == ((1.0, 0.0, 0.0) if hit else (0.0, 1.0, 1.0))


def test_tusimple_threshold_widens_with_the_slant():
    # x = 300 + y: 45 degrees from vertical, so the hit distance is 20 / cos(45) = 28.28 px
    gt = slanted(300.0, 1.0)
    assert metrics.line_threshold_px(np.asarray(gt), Y) == pytest.approx(20.0 * math.sqrt(2.0))
    assert tusimple_image([slanted(300.0, 1.0, 27.0)], [gt], H).accuracy == 1.0
    assert tusimple_image([slanted(300.0, 1.0, 29.0)], [gt], H).accuracy == 0.0
    # the same 27 px on a vertical lane is a miss
    assert tusimple_image([vertical(327)], [vertical(300)], H).accuracy == 0.0


def test_tusimple_angle_is_fitted_on_the_points_only():
    # -2 rows are left out of the fit: the lane stays at 45 degrees
    gt = np.asarray([-2.0] * 10 + slanted(300.0, 1.0)[10:])
    assert metrics.line_threshold_px(metrics.tusimple_x(gt), Y) == pytest.approx(20.0 * math.sqrt(2.0))


def test_tusimple_counts_every_row_and_rows_without_points_on_both_sides_hit():
    gt = [vertical(400, missing_top=16)]  # 40 labelled rows of 56
    # the prediction has no point where the label has none: 56 of 56 rows hit
    assert tusimple_image([vertical(400, missing_top=16)], gt, H).accuracy == 1.0
    # a prediction that also draws the 16 unlabelled rows misses them: 40 / 56
    r = tusimple_image([vertical(400)], gt, H)
    assert r.accuracy == pytest.approx(40 / 56) and (r.fp, r.fn) == (1.0, 1.0)  # < 0.85
    # a prediction reaching 8 rows less far misses 8 rows: 48 / 56 = 0.857 >= 0.85, matched
    r = tusimple_image([vertical(400, missing_top=24)], gt, H)
    assert r.accuracy == pytest.approx(48 / 56) and (r.fp, r.fn) == (0.0, 0.0)


def test_tusimple_missing_lane():
    gt = [vertical(x) for x in (200, 500, 800, 1100)]
    r = tusimple_image(gt[:3], gt, H)
    assert (r.accuracy, r.fp, r.fn) == (0.75, 0.0, 0.25)


def test_tusimple_extra_lane():
    gt = [vertical(500), vertical(800)]
    r = tusimple_image(gt + [vertical(1100)], gt, H)
    assert (r.accuracy, r.fn) == (1.0, 0.0) and r.fp == pytest.approx(1 / 3)


def test_tusimple_no_prediction():
    r = tusimple_image([], [vertical(500), vertical(800)], H)
    assert (r.accuracy, r.fp, r.fn) == (0.0, 0.0, 1.0)


def test_tusimple_more_than_two_extra_lanes_or_slow_scores_zero():
    gt = [vertical(500), vertical(800)]
    four = gt + [vertical(100), vertical(1100)]
    assert tusimple_image(four, gt, H).accuracy == 1.0  # 2 extra lanes are allowed
    assert tusimple_image(four + [vertical(1200)], gt, H) == metrics.TuSimpleImage(0.0, 0.0, 1.0)
    assert tusimple_image(gt, gt, H, run_time_ms=200.0).accuracy == 1.0
    assert tusimple_image(gt, gt, H, run_time_ms=200.5) == metrics.TuSimpleImage(0.0, 0.0, 1.0)


def test_tusimple_five_labelled_lanes_drop_the_worst_and_one_fn():
    gt = [vertical(x) for x in (100, 350, 600, 850, 1100)]
    r = tusimple_image(gt[:4], gt, H)  # the fifth is missed: accuracy 0, dropped; its FN forgiven
    assert (r.accuracy, r.fp, r.fn) == (1.0, 0.0, 0.0)
    r = tusimple_image(gt[:3], gt, H)  # two missed: (3 + 0 + 0 - 0) / 4, one FN of two forgiven
    assert (r.accuracy, r.fp, r.fn) == (0.75, 0.0, 0.25)


def test_tusimple_wrong_lane_length_is_an_error():
    with pytest.raises(ValueError, match="predicted lane 1 has 3 x values for 56 h_samples"):
        tusimple_image([[1.0, 2.0, 3.0]], [vertical(500)], H)


def test_tusimple_set_divides_by_the_labelled_images():
    a = metrics.TuSimpleImage(1.0, 0.0, 0.0)
    b = metrics.TuSimpleImage(0.5, 0.5, 0.25)
    s = tusimple_score([("a", a), ("b", b)], 2)
    assert (s.accuracy, s.fp, s.fn) == (0.75, 0.25, 0.125)
    assert s.to_dict() == {"benchmark": "tusimple", "images": 2, "Accuracy": 0.75, "FP": 0.25,
                           "FN": 0.125, "F1": 2 * 0.75 * 0.875 / (0.75 + 0.875)}
    assert "Accuracy  75.00 %" in s.table()


def test_lanelib_mode_scores_only_truth_points():
    # lanelib's own truth (every_row=False): rows without a truth point do not count
    gt = metrics.tusimple_x(vertical(400, missing_top=16))
    assert metrics.line_accuracy(np.asarray(vertical(400), float), gt, 20.0) == 1.0
    assert metrics.line_accuracy(np.asarray(vertical(400), float), gt, 20.0, every_row=True) == \
        pytest.approx(40 / 56)


# --------------------------------------------------------------------------- CULane metric

def strip(x: float) -> np.ndarray:
    """A vertical CULane lane at ``x`` from above the canvas to below it (no end caps inside)."""
    return np.array([[x, -60.0], [x, 650.0]])


def test_culane_draws_31_px_strips_for_30_px_lines():
    m = lane_mask(strip(800))
    assert m.shape == (590, 1640) and set(np.unique(m)) == {0, 1}
    # OpenCV's 30-thick line covers x - 15 .. x + 15: 31 px on every row
    assert (m.sum(axis=1) == 31).all()
    assert np.flatnonzero(m[300]).tolist() == list(range(785, 816))


@pytest.mark.parametrize("d", [0, 5, 10, 11, 20, 31, 40])
def test_culane_iou_of_shifted_strips_is_analytic(d):
    # two 31 px strips d px apart on every row: IoU = (31 - d) / (31 + d), 0 once apart
    expected = max(31 - d, 0) / (31 + d) if d < 31 else 0.0
    assert iou_matrix([strip(800)], [strip(800 + d)])[0, 0] == pytest.approx(expected)


def test_culane_shift_10_px_is_a_match_11_px_is_not():
    # (31 - 10) / 41 = 0.512 > 0.5; (31 - 11) / 42 = 0.476
    assert culane_image([strip(800)], [strip(810)]) == CULaneCounts(1, 0, 0, 1)
    assert culane_image([strip(800)], [strip(811)]) == CULaneCounts(0, 1, 1, 1)


def test_culane_iou_exactly_at_threshold_is_not_a_match():
    assert matched_pairs(np.array([[0.5]])) == 0
    assert matched_pairs(np.array([[0.5001]])) == 1


def test_culane_hungarian_beats_greedy():
    # greedy would pair truth 0 with pred 0 (0.9) and leave truth 1 unmatched (0.1)
    ious = np.array([[0.9, 0.8],
                     [0.7, 0.1]])
    assert matched_pairs(ious) == 2  # 0 - 1 (0.8) and 1 - 0 (0.7)


def test_culane_perfect_missing_and_extra_lanes():
    gt = [strip(300), strip(800), strip(1300)]
    perfect = culane_image(gt, gt)
    assert perfect == CULaneCounts(3, 0, 0, 1) and perfect.f1 == 1.0
    missing = culane_image(gt, gt[:2])
    assert missing == CULaneCounts(2, 0, 1, 1)
    assert (missing.precision, missing.recall) == (1.0, 2 / 3) and missing.f1 == pytest.approx(0.8)
    extra = culane_image(gt[:1], gt[:1] + [strip(1000)])
    assert extra == CULaneCounts(1, 1, 0, 1) and extra.precision == 0.5
    assert culane_image([], gt) == CULaneCounts(0, 3, 0, 1)
    assert culane_image(gt, []) == CULaneCounts(0, 0, 3, 1)


def test_culane_sums_and_zero_denominators():
    total = CULaneCounts(2, 0, 1, 1) + CULaneCounts(1, 1, 0, 1)
    assert total == CULaneCounts(3, 1, 1, 2)
    assert (total.precision, total.recall, total.f1) == (0.75, 0.75, 0.75)
    assert (CULaneCounts().precision, CULaneCounts().recall, CULaneCounts().f1) == (0.0, 0.0, 0.0)
    assert total.to_dict()["F1"] == 0.75 and "F1         75.00 %" in total.table()


def test_culane_lane_of_one_point_matches_nothing():
    assert iou_matrix([np.array([[800.0, 300.0]])], [strip(800)])[0, 0] == 0.0
    assert culane_image([np.array([[800.0, 300.0]])], [strip(800)]) == CULaneCounts(0, 1, 1, 1)


def test_culane_spline_keeps_two_points_and_resamples_more():
    two = np.array([[100.0, 500.0], [300.0, 300.0]])
    assert np.array_equal(interpolate_lane(two), two)
    # collinear points: the natural spline is the straight line, 50 samples per segment + the end
    three = np.array([[100.0, 500.0], [200.0, 400.0], [300.0, 300.0]])
    out = interpolate_lane(three)
    assert out.shape == (101, 2)
    assert np.allclose(out[:, 0] + out[:, 1], 600.0) and np.allclose(out[[0, 50, 100]], three)
    # a bent lane passes through its points, and a repeated point is dropped first
    bent = np.array([[100.0, 500.0], [180.0, 400.0], [300.0, 300.0], [300.0, 300.0]])
    out = interpolate_lane(bent)
    assert out.shape == (101, 2) and np.allclose(out[[0, 50, 100]], bent[:3])


def test_culane_natural_spline_is_the_textbook_one():
    # knots 0, 1, 2 with values 0, 1, 0: M1 = 6 (-1 - 1) / (2 (1 + 1)) = -3, and at the middle of
    # the first segment y = 0.5 + (1/6) (0.125 - 0.5) (-3) = 0.6875; the ends have y'' = 0
    out = metrics.natural_cubic_spline(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 0.0]),
                                       np.array([0.0, 0.5]))
    assert np.allclose(out.ravel(), [0.0, 0.6875, 1.0, 0.6875])
    # and scipy's natural CubicSpline (a dependency for the Hungarian matching) on random lanes
    from scipy.interpolate import CubicSpline
    rng = np.random.default_rng(5)
    k = np.arange(50) / 50
    for n in (2, 3, 6, 18):
        p = np.cumsum(rng.uniform(1, 40, (n, 2)), axis=0)
        t = np.r_[0.0, np.cumsum(np.hypot(*np.diff(p, axis=0).T))]
        ts = (t[:-1, None] + np.diff(t)[:, None] * k[None, :]).ravel()
        assert np.allclose(metrics.natural_cubic_spline(t, p, k), CubicSpline(t, p, bc_type="natural")(ts),
                           atol=1e-9)


def test_culane_slanted_lane_shifted_along_x():
    # a 45-degree lane shifted 10 px sideways is 7.1 px away across: a match; 30 px is not
    lane = np.array([[400.0, 590.0], [700.0, 290.0], [1000.0, -10.0]])
    near = iou_matrix([lane], [lane + [10.0, 0.0]])[0, 0]
    far = iou_matrix([lane], [lane + [30.0, 0.0]])[0, 0]
    assert near > 0.5 > far > 0.0


# --------------------------------------------------------------------------- TuSimple files

def label_line(raw_file: str, lanes) -> str:
    return json.dumps({"lanes": lanes, "h_samples": H, "raw_file": raw_file})


def write_tusimple_set(folder: Path) -> tuple[Path, Path]:
    """Two labelled images and their predictions: one perfect, one missing a lane of two."""
    folder.mkdir(parents=True, exist_ok=True)
    a = [vertical(500, missing_top=10), vertical(800, missing_top=10)]
    b = [slanted(300.0, -0.5), slanted(900.0, 0.5)]
    labels = folder / "label_data_0531.json"
    labels.write_text(label_line("clips/a/20.jpg", a) + "\n" + label_line("clips/b/20.jpg", b) + "\n")
    preds = [tusimple.TuSimpleRecord("clips/a/20.jpg", tuple(map(tuple, a)), tuple(H), 12.5),
             tusimple.TuSimpleRecord("clips/b/20.jpg", (tuple(b[0]),), tuple(H), 8.0)]
    pred = tusimple.write_predictions(folder / "pred.json", preds, inputs=[labels])
    return labels, pred


def test_tusimple_files_round_trip_and_score(tmp_path):
    labels, pred = write_tusimple_set(tmp_path)
    first = json.loads(pred.read_text().splitlines()[0])
    assert set(first) == {"raw_file", "lanes", "h_samples", "run_time"}
    assert first["lanes"][0][:11] == [-2] * 10 + [500] and first["run_time"] == 12.5
    read = tusimple.read_predictions(pred)
    assert [r.raw_file for r in read] == ["clips/a/20.jpg", "clips/b/20.jpg"]
    assert read[0].lanes[1][10] == 800.0 and read[1].run_time_ms == 8.0
    gt = tusimple.read_labels(tmp_path)  # the folder: its label_data*.json
    assert len(gt) == 2 and gt[0].run_time_ms is None and gt[0].h_samples == tuple(map(float, H))
    s = tusimple.evaluate(labels, pred)
    # a: 1, FP 0, FN 0; b: one lane of two, accuracy 1/2, FP 0, FN 1/2
    assert (s.images, s.accuracy, s.fp, s.fn) == (2, 0.75, 0.0, 0.25)


def test_tusimple_write_never_over_an_input(tmp_path):
    labels, _ = write_tusimple_set(tmp_path)
    before = labels.read_text()
    with pytest.raises(InputError, match="would overwrite an input"):
        tusimple.write_predictions(labels, tusimple.read_predictions(tmp_path / "pred.json"),
                                   inputs=[labels])
    assert labels.read_text() == before and not list(tmp_path.glob(".*part*"))


@pytest.mark.parametrize("line, message", [
    ("{not json", r"f.json:2: not a JSON object"),
    ('{"raw_file": "x.jpg", "lanes": []}', r"f.json:2: no h_samples; each line needs raw_file, lanes, h_samples"),
    ('{"raw_file": "x.jpg", "lanes": [[1, 2]], "h_samples": [1, 2, 3]}',
     r"f.json:2: lane 1 has 2 x values for 3 h_samples; give one x per row"),
    ('{"raw_file": "x.jpg", "lanes": [[1, "a"]], "h_samples": [1, 2]}',
     r"f.json:2: lane 1 must be a list of numbers"),
    ('{"raw_file": "x.jpg", "lanes": [], "h_samples": []}', r"f.json:2: h_samples is empty"),
])
def test_tusimple_bad_label_lines_name_file_and_line(tmp_path, line, message):
    f = tmp_path / "f.json"
    f.write_text(label_line("ok.jpg", [vertical(1)]) + "\n" + line + "\n")
    with pytest.raises(InputError, match=message):
        tusimple.read_labels(f)


def test_tusimple_bad_prediction_sets(tmp_path):
    labels, pred = write_tusimple_set(tmp_path)
    lines = pred.read_text().splitlines()
    no_time = tmp_path / "no_time.json"
    no_time.write_text(json.dumps({"raw_file": "clips/a/20.jpg", "lanes": []}) + "\n")
    with pytest.raises(InputError, match=r"no_time.json:1: no run_time"):
        tusimple.read_predictions(no_time)
    short = tmp_path / "short.json"
    short.write_text(lines[0] + "\n")
    with pytest.raises(InputError, match=r"short.json: no prediction for 1 of the 2 labelled images "
                                         r"\(first: clips/b/20.jpg\)"):
        tusimple.evaluate(labels, short)
    twice = tmp_path / "twice.json"
    twice.write_text(lines[0] + "\n" + lines[0] + "\n")
    with pytest.raises(InputError, match=r"clips/a/20.jpg is given twice \(records 1 and 2\)"):
        tusimple.read_predictions(twice)
    wrong = tmp_path / "wrong.json"
    rec = json.loads(lines[1])
    rec["lanes"] = [[1, 2, 3]]
    del rec["h_samples"]
    wrong.write_text(lines[0] + "\n" + json.dumps(rec) + "\n")
    with pytest.raises(InputError, match=r"wrong.json: clips/b/20.jpg: predicted lane 1 has 3 x values"):
        tusimple.evaluate(labels, wrong)
    with pytest.raises(InputError, match=r"missing.json: no such TuSimple prediction file"):
        tusimple.evaluate(labels, tmp_path / "missing.json")


# --------------------------------------------------------------------------- CULane files

ENTRIES = ["/driver_23_30frame/05151640_0419.MP4/00000.jpg",
           "/driver_23_30frame/05151640_0419.MP4/00030.jpg"]


def write_culane_set(root: Path) -> Path:
    """Two labelled images under ``root`` and their list: 2 lanes, then 1 lane."""
    gt = [[strip(600), strip(1000)], [np.array([[400.0, 590.0], [550.0, 440.0], [700.0, 290.0]])]]
    for entry, lanes in zip(ENTRIES, gt):
        f = culane.lines_path(root, entry)
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(culane.format_lines(lanes))
    (root / "list").mkdir(exist_ok=True)
    lst = root / "list" / "test.txt"
    lst.write_text("\n".join(ENTRIES) + "\n")
    return lst


def test_culane_paths_and_lines_round_trip(tmp_path):
    assert culane.lines_path(tmp_path, ENTRIES[0]) == \
        tmp_path / "driver_23_30frame" / "05151640_0419.MP4" / "00000.lines.txt"
    lanes = [np.array([[1.5, 589.0], [20.25, 580.0]]), np.array([[100.0, 300.0], [110.0, 290.0],
                                                                 [120.0, 280.0]])]
    text = culane.format_lines(lanes)
    assert text.splitlines()[0] == "1.5 589 20.25 580"
    back = culane.parse_lines(text, "x.lines.txt")
    assert len(back) == 2 and all(np.array_equal(a, b) for a, b in zip(back, lanes))


def test_culane_write_predictions_mirrors_the_list_and_scores(tmp_path):
    lst = write_culane_set(tmp_path / "CULane")
    labels = culane.read_labels(tmp_path / "CULane", lst)
    assert labels.entries == tuple(ENTRIES) and [len(l) for l in labels.lanes] == [2, 1]
    # image 1: both lanes, one 10 px off (IoU 21/41 > 0.5); image 2: its lane and an extra one
    preds = {ENTRIES[0]: [strip(600), strip(1010)],
             ENTRIES[1]: [labels.lanes[1][0], strip(1400)]}
    written = culane.write_predictions(tmp_path / "pred", preds, inputs=[lst])
    assert written[0] == tmp_path / "pred" / "driver_23_30frame" / "05151640_0419.MP4" / "00000.lines.txt"
    s = culane.evaluate(tmp_path / "CULane", lst, tmp_path / "pred")
    assert s.counts == CULaneCounts(3, 1, 0, 2) and s.missing_predictions == 0
    assert s.counts.f1 == pytest.approx(2 * 0.75 / 1.75)
    # a wider IoU bar: the 10 px pair no longer counts
    assert culane.evaluate(tmp_path / "CULane", lst, tmp_path / "pred", iou_threshold=0.6).counts == \
        CULaneCounts(2, 2, 1, 2)


def test_culane_missing_prediction_file_counts_as_no_lanes(tmp_path):
    lst = write_culane_set(tmp_path / "CULane")
    culane.write_predictions(tmp_path / "pred", {ENTRIES[0]: [strip(600), strip(1000)]})
    s = culane.evaluate(tmp_path / "CULane", lst, tmp_path / "pred")
    assert s.counts == CULaneCounts(2, 0, 1, 2) and s.missing_predictions == 1
    assert "1 images had no prediction file" in s.table()
    with pytest.raises(InputError, match=r"empty: holds no prediction for any listed image"):
        (tmp_path / "empty").mkdir()
        culane.evaluate(tmp_path / "CULane", lst, tmp_path / "empty")


def test_culane_bad_inputs_name_the_file_and_the_fix(tmp_path):
    root = tmp_path / "CULane"
    lst = write_culane_set(root)
    culane.lines_path(root, ENTRIES[1]).unlink()
    with pytest.raises(InputError, match=r"test.txt: entry 2 \(/driver_23_30frame/05151640_0419.MP4/"
                                         r"00030.jpg\) has no labels: .*00030.lines.txt is missing"):
        culane.read_labels(root, lst)
    write_culane_set(root)
    bad = culane.lines_path(root, ENTRIES[0])
    bad.write_text("600 0 600 590\n1000 0 1000\n")
    with pytest.raises(InputError, match=r"00000.lines.txt:2: 3 numbers; each line is one lane as pairs"):
        culane.read_labels(root, lst)
    bad.write_text("600 0 600 abc\n")
    with pytest.raises(InputError, match=r"00000.lines.txt:1: not a list of numbers"):
        culane.read_labels(root, lst)
    lst.write_text(ENTRIES[0] + "\n/driver_23_30frame/\n")
    with pytest.raises(InputError, match=r"test.txt:2: '/driver_23_30frame/' is not an image path"):
        culane.read_list(lst)
    with pytest.raises(InputError, match=r"nowhere: no such folder; pass the CULane dataset root"):
        culane.read_labels(tmp_path / "nowhere", lst)
    with pytest.raises(InputError, match=r"no such CULane list file"):
        culane.read_list(tmp_path / "none.txt")


# --------------------------------------------------------------------------- the CLI

def test_cli_evaluate_tusimple_prints_and_writes_the_official_figures(tmp_path, capsys):
    labels, pred = write_tusimple_set(tmp_path)
    out = tmp_path / "figures.json"
    assert cli.main(["evaluate", "tusimple", "--gt", str(labels), "--pred", str(pred),
                     "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "TuSimple, 2 images" in text and "Accuracy  75.00 %" in text
    assert "FP        0.0000" in text and "FN        0.2500" in text and "F1        85.71 %" in text
    assert json.loads(out.read_text()) == {"benchmark": "tusimple", "images": 2, "Accuracy": 0.75,
                                           "FP": 0.0, "FN": 0.25, "F1": 2 * 0.75 / 1.75}


def test_cli_evaluate_culane_prints_and_writes_the_official_figures(tmp_path, capsys):
    lst = write_culane_set(tmp_path / "CULane")
    culane.write_predictions(tmp_path / "pred", {ENTRIES[0]: [strip(600), strip(1010)],
                                                 ENTRIES[1]: [strip(1400)]})
    out = tmp_path / "f.json"
    assert cli.main(["evaluate", "culane", "--gt", str(tmp_path / "CULane"), "--list", str(lst),
                     "--pred", str(tmp_path / "pred"), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "TP 2  FP 1  FN 1" in text and "F1         66.67 %" in text
    figures = json.loads(out.read_text())
    assert (figures["TP"], figures["FP"], figures["FN"], figures["missing_predictions"]) == (2, 1, 1, 0)
    assert figures["precision"] == pytest.approx(2 / 3) and figures["F1"] == pytest.approx(2 / 3)
    # the 10 px pair fails a higher IoU bar
    assert cli.main(["evaluate", "culane", "--gt", str(tmp_path / "CULane"), "--list", str(lst),
                     "--pred", str(tmp_path / "pred"), "--iou", "0.6"]) == 0
    assert "TP 1  FP 2  FN 2" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["evaluate", "tusimple", "--gt", "{labels}"], "evaluate tusimple: --pred missing; give --gt "
                                                   "LABELS.json --pred PRED.json"),
    (["evaluate", "culane", "--gt", "{dir}", "--pred", "{dir}"], "evaluate culane: --list missing"),
    (["evaluate", "tusimple", "--gt", "{labels}", "--pred", "{pred}", "--max-frames", "3"],
     "--max-frames: not for `evaluate tusimple`"),
    (["evaluate", "images", "{dir}", "--pred", "{pred}"], "--pred: for `evaluate tusimple|culane` only"),
    (["evaluate", "video"], "evaluate video: give the PATH to score"),
    (["evaluate", "tusimple", "--gt", "{labels}", "--pred", "{pred}", "--json", "{labels}"],
     "label_data_0531.json: output would overwrite an input"),
    (["evaluate", "tusimple", "--gt", "{labels}", "--pred", "{dir}/nope.json"],
     "nope.json: no such TuSimple prediction file"),
])
def test_cli_evaluate_benchmark_errors_exit_2_with_one_line(tmp_path, capsys, argv, message):
    labels, pred = write_tusimple_set(tmp_path)
    before = labels.read_text()
    argv = [a.format(labels=labels, pred=pred, dir=tmp_path) for a in argv]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and message in err[0]
    assert labels.read_text() == before
