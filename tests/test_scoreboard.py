"""``lanelib.scoreboard``: the arithmetic of its rows on hand-made cases, and the command."""
from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from lanelib import data, evaluate, io, scoreboard
from lanelib.batch.video import VideoWriter
from lanelib.benchmarks import culane, tusimple
from lanelib.cli import main
from lanelib.errors import InputError


# --------------------------------------------------------------------------- the arithmetic

@pytest.mark.parametrize("counts, expected", [
    ((3, 1, 2), (75.0, 60.0, 66.7)),     # P 3/4, R 3/5, F1 2PR/(P+R) = 2/3
    ((5, 0, 0), (100.0, 100.0, 100.0)),
    ((0, 4, 445), (0.0, 0.0, 0.0)),      # nothing matched
    ((0, 0, 7), (0.0, 0.0, 0.0)),        # no prediction: precision 0/0 is 0
    ((0, 3, 0), (0.0, 0.0, 0.0)),        # no truth: recall 0/0 is 0
    ((0, 0, 0), (0.0, 0.0, 0.0)),        # nothing at all
    ((1, 2, 0), (33.3, 100.0, 50.0)),
])
def test_precision_recall_f1_of_line_counts(counts, expected):
    f = scoreboard.detection_figures(*counts)
    assert (f["precision_pct"], f["recall_pct"], f["f1_pct"]) == expected
    assert (f["tp"], f["fp"], f["fn"]) == counts


def test_tusimple_figures_are_rounded_to_what_they_mean():
    # F1 of precision 1 - FP and recall 1 - FN: 2 * (29/30) * (1/30) / (30/30) = 0.0644
    assert scoreboard.tusimple_figures(0.97536, 1 / 30, 29 / 30) == {
        "accuracy_pct": 97.5, "fp_rate": 0.03, "fn_rate": 0.97, "f1_pct": 6.4}
    assert scoreboard.tusimple_figures(0.0, 0.0, 1.0) == {"accuracy_pct": 0.0, "fp_rate": 0.0, "fn_rate": 1.0,
                                                          "f1_pct": 0.0}
    assert scoreboard.tusimple_figures(0.9, 0.2, 0.2)["f1_pct"] == 80.0   # equal rates: F1 = 1 - rate
    assert scoreboard.pct(float("nan")) is None and scoreboard.pct(None) is None


# ten frames: one without a lane, one too narrow, one too wide; the other seven plausible,
# their widths and offsets on and inside the bounds
FOUND = [False, True, True, True, True, True, True, True, True, True]
WIDTH = [math.nan, 2.95, 4.6, 3.0, 4.5, 3.7, 3.7, 3.5, 3.9, 3.7]
OFFSET = [math.nan, 0.0, 0.0, 0.0, -0.59, 0.59, 0.2, -0.3, 0.1, 0.0]


def test_plausible_frames_of_ten_frame_results():
    assert scoreboard.plausible(FOUND, WIDTH, OFFSET).tolist() == [False, False, False] + [True] * 7
    assert scoreboard.clip_figures(FOUND, WIDTH, OFFSET) == {
        "plausible_pct": 70.0, "found_pct": 90.0, "first_held_frame": 1}


def test_an_offset_of_the_bound_or_a_found_lane_without_width_is_not_plausible():
    # |offset| must be below 0.6 m; a lane "found" with NaN measurements is not plausible
    ok = scoreboard.plausible([True, True, True, True], [3.7, 3.7, math.nan, 3.7], [0.6, -0.6, 0.0, math.nan])
    assert ok.tolist() == [False, False, False, False]
    assert scoreboard.clip_figures([], [], []) == {"plausible_pct": None, "found_pct": None,
                                                   "first_held_frame": None}


@pytest.mark.parametrize("found, first", [
    ([True] * 5, 0),
    ([False, False, True, True, True], 2),
    ([True, False, True, False, True, True], 4),   # lost twice, held from frame 4 on
    ([True, True, True, False], None),             # lost on the last frame: never held
    ([False] * 3, None),
    ([], None),
])
def test_first_held_frame(found, first):
    assert scoreboard.first_held_frame(found) == first


def test_mean_ms_in_whole_ms():
    assert scoreboard.mean_ms([20.4, 21.0, 22.1]) == 21
    assert scoreboard.mean_ms(np.array([0.4])) == 0
    assert scoreboard.mean_ms([]) is None


# --------------------------------------------------------------------------- rows and table

def test_rows_are_chosen_in_the_scoreboard_order_real_rows_first():
    keys = list(scoreboard.ROWS)
    assert keys[:8] == ["culane", "culane-moved", "tusimple", "tusimple-bilinear", "project", "challenge",
                        "p1-white", "p1-yellow"]
    assert all(k.startswith("synth") for k in keys[8:])
    assert scoreboard.select(None) == keys
    assert scoreboard.select(["synth-clip", "culane"]) == ["culane", "synth-clip"]
    with pytest.raises(InputError, match="--only nope: no such row; the rows are culane, culane-moved, tusimple"):
        scoreboard.select(["culane", "nope"])
    with pytest.raises(InputError, match="give one row or more"):
        scoreboard.select([])


def test_a_row_without_its_data_is_skipped_with_the_reason(monkeypatch, tmp_path):
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path / "data"))
    for key, missing in (("culane", "culane-dev/list.txt"), ("culane-moved", "culane-dev/list.txt"),
                         ("tusimple", "tusimple-dev/label_data_fullres.json"),
                         ("tusimple-bilinear", "tusimple-dev/label_data_fullres.json"),
                         ("challenge", "udacity-advanced/videos/challenge_video.mp4"),
                         ("p1-yellow", "udacity-lanelines-p1/test_videos/solidYellowLeft.mp4")):
        row = scoreboard.measure_row(key, tmp_path / "out")
        assert row.skipped == data.missing_reason(missing.split("/", 1)[1], missing.split("/")[0])
        assert row.skipped.startswith(f"{tmp_path / 'data' / missing} not found: set LANELIB_DATA")
        assert row.cells()[2] == f"skipped: {row.skipped}" and not row.error
    assert not (tmp_path / "out").exists()


def test_a_row_that_fails_keeps_its_error_and_the_table_says_so(monkeypatch, tmp_path):
    def broken(out, settings):
        raise InputError(f"{out}/x.jpg: not an image; replace it")

    monkeypatch.setitem(scoreboard.ROWS, "synth-clip", ("synthetic clip", broken))
    row = scoreboard.measure_row("synth-clip", tmp_path)
    assert row.error == f"{tmp_path}/x.jpg: not an image; replace it" and not row.skipped
    done = scoreboard.Row("culane", "CULane dev", "list.txt", 120, scoreboard.detection_figures(3, 1, 2), 84)
    table = scoreboard.format_table([done, row]).splitlines()
    assert table[0].split() == ["row", "frames", "figures", "ms/frame", "source"]
    assert table[1].split("  ")[0] == "CULane dev"
    assert "precision 75.0 %, recall 60.0 %, F1 66.7 %, TP 3, FP 1, FN 2" in table[1]
    assert table[1].endswith("84  list.txt")
    assert f"failed: {row.error}" in table[2]
    assert json.loads(json.dumps(done.to_dict()))["figures"]["f1_pct"] == 66.7


def test_the_predictions_of_an_earlier_run_are_replaced_and_nothing_else(tmp_path):
    earlier = tmp_path / "culane"
    (earlier / "a").mkdir(parents=True)
    (earlier / "predict.json").write_text("{}")
    assert scoreboard.fresh_folder(earlier) == earlier and not earlier.exists()
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(InputError, match="not predictions of an earlier scoreboard; pass another --out"):
        scoreboard.fresh_folder(tmp_path / "mine")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


def test_the_scoreboard_never_writes_into_the_real_data(monkeypatch, tmp_path):
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path))
    with pytest.raises(InputError, match="inside the real data's folder"):
        scoreboard.run(tmp_path / "out", ["synth-clip"])
    assert not (tmp_path / "out").exists()


def test_tusimple_frames_upscaled_once_as_png_with_their_labels(tmp_path):
    root, cache = tmp_path / "dev", tmp_path / "cache"
    small = np.zeros((288, 512, 3), np.uint8)
    small[:, 200:205] = 255  # a line at x 200..204 (512 px) is at 500..512 (1280 px)
    io.write_image(root / "clips" / "a" / "1" / "20.jpg", small)
    rows = tuple(float(y) for y in range(240, 720, 10))
    label = tusimple.TuSimpleRecord("clips/a/1/20.jpg", ((506.0,) * len(rows),), rows)
    tusimple.write_labels(root / "label_data_fullres.json", [label])
    labels = scoreboard.upscaled_tusimple(root, cache)
    assert labels == cache / "label_data_fullres.json"
    (copied,) = tusimple.read_labels(labels)
    assert copied == tusimple.TuSimpleRecord("clips/a/1/20.png", label.lanes, rows)
    png = cache / "clips" / "a" / "1" / "20.png"
    big = io.read_image(png)
    assert big.shape == (720, 1280, 3) and big[400, 506, 0] > 200 and big[400, 480, 0] < 30
    stamp = png.stat().st_mtime_ns  # the frame is written once: a second call keeps it
    scoreboard.upscaled_tusimple(root, cache)
    assert png.stat().st_mtime_ns == stamp
    assert sorted(p.name for p in root.rglob("*")) == ["1", "20.jpg", "a", "clips", "label_data_fullres.json"]
    # bilinear: the same frame as OpenCV's bilinear resize of it, blurrier than the bicubic one
    soft_labels = scoreboard.upscaled_tusimple(root, tmp_path / "soft", cv2.INTER_LINEAR)
    soft = io.read_image(soft_labels.parent / png.relative_to(cache))
    source = io.read_image(root / "clips" / "a" / "1" / "20.jpg")
    assert np.array_equal(soft, cv2.resize(source, (1280, 720), interpolation=cv2.INTER_LINEAR))
    assert np.abs(np.diff(soft[400].astype(int), axis=0)).max() < np.abs(np.diff(big[400].astype(int), axis=0)).max()


def test_culane_frames_moved_once_with_their_labels_sequence_by_sequence(tmp_path):
    root, cache = tmp_path / "dev", tmp_path / "cache"
    entries = ["/d/a.MP4/00000.jpg", "/d/a.MP4/00090.jpg", "/d/b.MP4/00000.jpg"]
    frame = np.zeros((590, 1640, 3), np.uint8)
    frame[:, 800:806] = 255  # a line at x 800..805, labelled at 802.5
    line = np.array([[802.5, 590.0], [802.5, 300.0], [802.5, 5.0]])
    for entry in entries:
        io.write_image(root / entry.lstrip("/"), frame)
    culane.write_labels(root, {e: [line] for e in entries})
    listed = scoreboard.moved_culane(root, culane.write_list(root / "list.txt", entries), cache,
                                     moves=((0, 15), (-40, -10)))
    moved = culane.read_list(listed)
    assert listed == cache / "list.txt" and moved == [e.replace(".jpg", ".png") for e in entries]
    for entry, (dx, dy) in zip(moved, [(0, 15), (0, 15), (-40, -10)]):
        image = io.read_image(cache / entry.lstrip("/"))
        assert image[300, 802 + dx, 0] == 255 and image[300, 796 + dx, 0] == 0
        (label,) = culane.read_lines(culane.lines_path(cache, entry))
        inside = line + (dx, dy)  # the point moved out of the image is left out
        assert np.array_equal(label, inside[(inside[:, 1] >= 0) & (inside[:, 1] <= 590)])
    png = cache / moved[0].lstrip("/")
    stamp = png.stat().st_mtime_ns  # written once: a second call keeps it
    scoreboard.moved_culane(root, root / "list.txt", cache)
    assert png.stat().st_mtime_ns == stamp
    assert not list(root.rglob("*.png"))


def test_a_clip_is_tracked_as_the_video_command_tracks_it(tmp_path):
    clip = tmp_path / "cut.mp4"
    source = data.bundled("videos") / "project.mp4"
    with io.VideoReader(source) as reader, VideoWriter(clip, reader.info.fps) as writer:
        for i, frame in zip(range(20), reader):
            writer.write(frame)
    run = scoreboard.track_clip(clip, calibration=evaluate.calibration_from_truth(source))
    assert len(run.found) == len(run.ms) == 20 and run.found.all() and (run.ms > 0).all()
    figures = scoreboard.clip_figures(run.found, run.width_m, run.offset_m)
    assert figures == {"plausible_pct": 100.0, "found_pct": 100.0, "first_held_frame": 0}


# --------------------------------------------------------------------------- the command

def test_scoreboard_help_parses(capsys):
    with pytest.raises(SystemExit) as e:
        main(["scoreboard", "--help"])
    assert e.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert out.startswith("usage: python -m lanelib scoreboard [-h] [--json FILE] [--out DIR] [--only ROW,...]")
    assert "run only these rows: culane (CULane dev), culane-moved (CULane dev, cameras moved), tusimple" in out


def test_scoreboard_only_the_synthetic_clip(tmp_path, capsys):
    out = tmp_path / "sb.json"
    assert main(["scoreboard", "--only", "synth-clip", "--out", str(tmp_path / "sb"), "--json", str(out)]) == 0
    text = capsys.readouterr().out.splitlines()
    assert text[0].split() == ["row", "frames", "figures", "ms/frame", "source"]
    assert text[1].startswith("synthetic clip project.mp4") and "point accuracy" in text[1]
    assert len(text) == 3 and text[2] == f"figures written to {out}"
    (row,) = json.loads(out.read_text())["rows"]
    assert row["key"] == "synth-clip" and row["frames"] == 250 and row["figures"]["point_accuracy_pct"] >= 95.0


def test_scoreboard_unknown_row_is_one_line_and_exit_2(capsys, tmp_path):
    assert main(["scoreboard", "--only", "culane,nope", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --only nope: no such row")


@pytest.mark.udacity
@pytest.mark.slow
def test_scoreboard_real_rows_run_on_the_dev_data(culane_dev, tusimple_dev, udacity_p1, tmp_path):
    rows = scoreboard.run(tmp_path, ["culane", "tusimple", "p1-white"])
    cu, ts, p1 = rows
    assert (cu.frames, ts.frames, p1.frames) == (120, 10, 221)
    assert not any(r.error or r.skipped for r in rows)
    assert set(cu.figures) == {"precision_pct", "recall_pct", "f1_pct", "tp", "fp", "fn"}
    assert cu.figures["tp"] + cu.figures["fn"] == 445  # the labelled lines of culane-dev
    # "over_200ms" only when a frame took longer than TuSimple's limit (a loaded machine)
    assert set(ts.figures) - {"over_200ms"} == {"accuracy_pct", "fp_rate", "fn_rate", "f1_pct"}
    assert p1.figures["found_pct"] > 90.0
    assert all(isinstance(r.ms_per_frame, int) and r.ms_per_frame > 0 for r in rows)
    assert len(list((tmp_path / scoreboard.TUSIMPLE_CACHE).rglob("*.png"))) == 10


def test_scoreboard_with_a_failed_row_prints_the_others_and_exits_1(monkeypatch, tmp_path, capsys):
    def broken(out, settings):
        raise InputError("x.mp4: the video stopped decoding at frame 3; pass a complete video")

    monkeypatch.setitem(scoreboard.ROWS, "synth-clip", ("synthetic clip", broken))
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path / "nothing"))
    assert main(["scoreboard", "--only", "culane,synth-clip", "--out", str(tmp_path / "sb")]) == 1
    captured = capsys.readouterr()
    table = captured.out.splitlines()
    assert "skipped: " in table[1] and "failed: x.mp4: the video stopped" in table[2]
    errors = [line for line in captured.err.splitlines() if line.startswith("error:")]
    assert errors == ["error: synth-clip: x.mp4: the video stopped decoding at frame 3; pass a complete video"]
