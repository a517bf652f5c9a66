"""benchmarks.why and why_images: each labelled line's class on hand-made lines and drawn frames,
the set's counts against the official scores on the dev frames, and the ``why`` command."""
from __future__ import annotations

import numpy as np
import pytest

from lanelib import data, io
from lanelib.benchmarks import culane, metrics, tusimple, why, why_images
from lanelib.cli import main
from lanelib.errors import InputError

VP = (755.0, 382.0)                   # about where the CULane camera's lines meet
ROWS = np.arange(580.0, 400.0, -10.0)  # label rows, bottom up
SIZE = (1640, 590)


def line_x(bottom_x: float, y):
    """Return x at rows ``y`` of the road line through (bottom_x, 590) and the vanishing point."""
    return VP[0] + (bottom_x - VP[0]) * (np.asarray(y, float) - VP[1]) / (590.0 - VP[1])


def label(bottom_x: float, rows=ROWS) -> np.ndarray:
    return np.column_stack([line_x(bottom_x, rows), rows])


def road(painted: tuple[float, ...]) -> np.ndarray:
    """Return a 1640x590 grey road with a sky, the lines through ``painted`` drawn in white,
    about 18 px wide at the bottom and narrowing towards the vanishing point."""
    rng = np.random.default_rng(0)
    img = np.clip(90 + rng.integers(-6, 7, (590, 1640, 3)), 0, 255).astype(np.uint8)
    img[:int(VP[1])] = (150, 170, 200)
    for bottom_x in painted:
        for y in range(395, 590):
            half = max(1, int(round(9 * (y - VP[1]) / (590 - VP[1]))))
            x = int(round(line_x(bottom_x, y)))
            img[y, x - half:x + half + 1] = 230
    return img


# --------------------------------------------------------------------------- classify, by hand

def categories(lines):
    return [(w.category, w.label, w.prediction) for w in lines]


def test_each_class_on_hand_made_culane_lines():
    labels = [label(x) for x in (200.0, 500.0, 1000.0, 1300.0, 1500.0)]
    exact = labels[0][:, 0].copy()
    beside = labels[1][:, 0] + 20.0                      # IoU (30-20)/(30+20): off
    short = labels[2][:, 0].copy()
    short[6:] = np.nan                                   # a third of the label's rows: off
    nowhere = np.full(len(ROWS), 1640.0 * 0.55)
    refused = [(labels[3][:, 0] + 8.0, "its paint scatters 0.16 m about the fit, more than max_scatter_m 0.13 m")]
    lines = why.classify("culane", labels, [exact, beside, short, nowhere], refused, ROWS, SIZE,
                         paint=[None, None, None, None, (0.02, 0.3)])
    assert categories(lines) == [(why.FOUND, 0, 0), (why.OFF, 1, 1), (why.OFF, 2, 2), (why.REFUSED, 3, None),
                                 (why.MISSED, 4, None), (why.FALSE, None, 1), (why.FALSE, None, 2),
                                 (why.FALSE, None, 3)]
    assert lines[1].reason.startswith("it runs 20 px beside it; IoU 0.")
    assert lines[2].reason.startswith("it stops short: reported over 33 % of the label's rows")
    assert lines[3].reason == refused[0][1]
    assert lines[4].reason == "no candidate near it: no paint in the mask along it"
    assert [w.reason for w in lines[5:]] == ["off label 2", "off label 3", "no label near it"]


def test_the_found_lines_are_the_official_true_positives():
    labels = [label(x) for x in (200.0, 700.0, 1300.0)]
    preds = [labels[2][:, 0] + 3.0, labels[0][:, 0] + 12.0, labels[1][:, 0] + 25.0]
    lines = why.classify("culane", labels, preds, [], ROWS, SIZE)
    official = metrics.culane_image(labels, [why.written_points(p, ROWS) for p in preds])
    assert len([w for w in lines if w.category == why.FOUND]) == official.tp == 2
    assert len([w for w in lines if w.category == why.FALSE]) == official.fp == 1
    assert len([w for w in lines if w.category != why.FOUND and w.label is not None]) == official.fn == 1


def test_missed_says_where_the_line_was_lost():
    labels = [label(x) for x in (200.0, 700.0, 1300.0, 1500.0)]
    paint = [None, (0.05, 0.4), (0.4, 0.35), (0.8, 0.2)]
    reasons = [w.reason for w in why.classify("culane", labels, [], [], ROWS, SIZE, paint)]
    assert reasons == ["no candidate near it: it lies outside the lines view",
                       "no candidate near it: no paint in the mask along it",
                       "no candidate near it: the mask is as busy beside it (paint along 40 % of it, 35 % beside it)",
                       "no candidate near it, though the mask has paint along it (paint along 80 % of it, 20 % beside it)"]
    assert len({why.reason_kind(r) for r in reasons}) == 4


def test_tusimple_lines_match_by_accuracy():
    rows = np.arange(240.0, 720.0, 10.0)
    lanes = [400.0 - 0.5 * (rows - 720), 900.0 + 0.5 * (rows - 720)]
    record = tusimple.TuSimpleRecord("clips/a/1/20.jpg", tuple(tuple(l) for l in lanes), tuple(rows))
    points, got_rows = why.label_lines("tusimple", record)
    half = lanes[1].copy()
    half[:24] = np.nan                                   # the near half only: accuracy 0.5
    lines = why.classify("tusimple", points, [lanes[0] + 5.0, half], [], got_rows, tusimple.IMAGE_SIZE)
    assert categories(lines) == [(why.FOUND, 0, 0), (why.OFF, 1, 1), (why.FALSE, None, 1)]
    assert lines[0].reason == "accuracy 1.00, needs 0.85"
    assert "accuracy 0.50" in lines[1].reason


def test_tusimple_labels_must_be_a_record():
    with pytest.raises(InputError, match="TuSimpleRecord"):
        why.explain_frame("tusimple", np.zeros((720, 1280, 3), np.uint8), [label(200.0)])


# --------------------------------------------------------------------------- drawn frames

def test_a_drawn_frame_found_missed_and_false():
    """One label drawn (found), one label on bare road (missed: no paint), one line drawn where
    no label is (a false line)."""
    frame = why.explain_frame("culane", road((200.0, 1300.0)), [label(200.0), label(700.0)])
    assert frame.summary() == ["label 1: found - IoU 1.00, needs above 0.5",
                               "label 2: missed - no candidate near it: no paint in the mask along it",
                               "line 2: false line - no label near it"]
    image = why_images.draw_why(road((200.0, 1300.0)), frame)
    assert image.shape == (590, 1640, 3) and image.dtype == np.uint8
    x = int(round(line_x(700.0, 500.0)))
    assert tuple(image[500, x]) == why_images.COLOURS["label"]        # the missed label, green
    x = int(round(line_x(1300.0, 500.0)))
    assert tuple(image[500, x]) == why_images.COLOURS[why.FALSE]      # the false line, orange


def write_frame(root, name="driver_1/a.MP4/00000.jpg"):
    """Write the drawn frame with its two labels as a CULane dataset of one frame; return its path."""
    image = root.joinpath(*name.split("/"))
    io.write_image(image, road((200.0, 1300.0)), jpeg_quality=98)
    culane.write_labels(root, {"/" + name: [label(200.0), label(700.0)]})
    culane.write_list(root / "list.txt", ["/" + name])
    return image


def test_the_command_writes_a_png_per_frame_and_prints_each_line(tmp_path, capsys):
    image = write_frame(tmp_path / "set")
    out = tmp_path / "why"
    assert main(["why", "culane", str(image), "-o", str(out), "--root", str(tmp_path / "set")]) == 0
    printed = capsys.readouterr().out
    assert "label 1: found" in printed and "label 2: missed" in printed and "line 2: false line" in printed
    png = out / "driver_1_a.MP4_00000.png"
    assert io.read_image(png).shape == (590, 1640, 3)
    # a frame named under the root gives the same image name
    assert main(["why", "culane", "driver_1/a.MP4/00000.jpg", "-o", str(out), "--root", str(tmp_path / "set")]) == 0


def test_the_command_refuses_the_input_folder_as_output(tmp_path, capsys):
    image = write_frame(tmp_path / "set")
    before = sorted(image.parent.iterdir())
    assert main(["why", "culane", str(image), "-o", str(image.parent)]) == 2
    assert "choose another output folder" in capsys.readouterr().err
    assert main(["why", "culane", str(image), "-o", str(tmp_path / "set"), "--root", str(tmp_path / "set")]) == 2
    assert sorted(image.parent.iterdir()) == before


def test_the_command_counts_a_set(tmp_path, capsys):
    write_frame(tmp_path / "set")
    assert main(["why", "culane", "--root", str(tmp_path / "set"), "-o", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    table = {line.rsplit(None, 2)[0].strip(): line.split()[-2:] for line in printed.splitlines()[2:-1]}
    assert table["found"] == ["1", "1"] and table["missed"] == ["1", "1"] and table["false line"] == ["1", "1"]
    assert table["refused"] == ["0", "0"] and table["reported but off"] == ["0", "0"]
    saved = io.read_json(tmp_path / "out" / "why_culane.json")
    assert saved["classes"]["missed"]["frame_names"] == ["/driver_1/a.MP4/00000.jpg"]


# --------------------------------------------------------------------------- the dev frames

def test_culane_dev_classes_add_up_to_the_official_counts():
    root = data.culane_dev()
    if root is None:
        pytest.skip(data.missing_reason("", data.CULANE_DEV))
    frames = why.set_frames("culane", root)[::12]
    for name, image, labels in frames:
        frame = why.explain_frame("culane", image, labels, name=name, keep_mask=False)
        official = metrics.culane_image(list(labels), [why.written_points(p, frame.rows_px)
                                                      for p in frame.predictions])
        assert len(frame.of(why.FOUND)) == official.tp, name
        assert len(frame.of(why.FALSE)) == official.fp, name
        assert sum(len(frame.of(c)) for c in (why.OFF, why.REFUSED, why.MISSED)) == official.fn, name


def test_tusimple_dev_set_counts_every_line():
    root = data.tusimple_dev()
    if root is None:
        pytest.skip(data.missing_reason("", data.TUSIMPLE_DEV))
    result = why.explain_set("tusimple", root)
    counts = result.counts()
    labels = sum(len(f.labels) for f in result.frames)
    assert len(result.frames) == 10 and labels == 38
    assert sum(counts[c][0] for c in why.CLASSES if c != why.FALSE) == labels
    assert counts[why.FALSE][0] == sum(len(f.predictions) for f in result.frames) - sum(
        len({w.prediction for w in f.of(why.FOUND)}) for f in result.frames)
    assert "class / reason" in result.table()
