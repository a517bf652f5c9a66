"""The command line: help, exit codes, outputs of calibrate and images."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from lanelib import io
from lanelib.cli import build_parser, main
from lanelib.cli.camera import parse_pattern
from lanelib.errors import InputError


def run(*args):
    return subprocess.run([sys.executable, "-m", "lanelib", *map(str, args)], capture_output=True, text=True)


def subcommands():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return sorted(action.choices)


def test_every_subcommand_has_help(capsys):
    names = subcommands()
    assert {"calibrate", "images"} <= set(names)
    for name in names:
        with pytest.raises(SystemExit) as e:
            main([name, "--help"])
        assert e.value.code == 0
        assert "usage: python -m lanelib " + name in capsys.readouterr().out


def test_missing_input_is_one_line_and_exit_2(tmp_path):
    for args in (["images", tmp_path / "nope", "-o", tmp_path / "out"],
                 ["calibrate", tmp_path / "nope", "-o", tmp_path / "c.json"]):
        p = run(*args)
        assert p.returncode == 2
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and "nope: no such folder" in lines[0], p.stderr


def test_bad_config_and_calibration_files_exit_2(tmp_path):
    io.write_image(tmp_path / "in" / "a.png", np.zeros((720, 1280, 3), np.uint8))
    (tmp_path / "c.json").write_text(json.dumps({"search": {"windows": 3}}))
    p = run("images", tmp_path / "in", "-o", tmp_path / "out", "--config", tmp_path / "c.json")
    assert p.returncode == 2 and "search.windows: unknown key" in p.stderr
    (tmp_path / "cal.json").write_text(json.dumps({"camera_matrix": [[1, 0, 0]]}))
    p = run("images", tmp_path / "in", "-o", tmp_path / "out", "--calibration", tmp_path / "cal.json")
    assert p.returncode == 2 and "missing key 'dist_coeffs'" in p.stderr


def test_images_refuses_to_write_into_its_input_folder(tmp_path):
    io.write_image(tmp_path / "a.png", np.zeros((720, 1280, 3), np.uint8))
    p = run("images", tmp_path, "-o", tmp_path)
    assert p.returncode == 2 and "output folder is the input folder" in p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["a.png"]


def test_calibrate_and_images_on_udacity(udacity_advanced, tmp_path):
    cal = tmp_path / "cal.json"
    p = run("calibrate", udacity_advanced / "camera_cal", "-o", cal)
    assert p.returncode == 0, p.stderr
    data = json.loads(cal.read_text())
    assert set(data) >= {"camera_matrix", "dist_coeffs", "image_size", "rms_px", "used", "skipped"}
    assert data["image_size"] == [1280, 720] and len(data["used"]) == 17 and data["rms_px"] < 1.5
    assert "skipped" in p.stderr and "calibration1.jpg" in p.stderr  # each skipped board named, with why
    out = tmp_path / "out"
    p = run("images", udacity_advanced / "test_images", "-o", out, "--calibration", cal, "--debug")
    assert p.returncode == 0, p.stderr
    rows = json.loads((out / "results.json").read_text())
    assert len(rows) == 8 and all(r["found"] for r in rows)
    assert all(set(r) >= {"file", "found", "left_found", "right_found", "radius_m", "offset_m",
                          "lane_width_m"} for r in rows)
    assert len(list(out.glob("*.jpg"))) == 8


# --------------------------------------------------------------------------- a batch survives a bad file

REPO = Path(__file__).resolve().parents[1]
ROAD = REPO / "test_images" / "straight_1.jpg"  # both pipelines find its lane (Hough: both lines)
GREY_NOTE = "grayscale image: the colour masks (yellow) find nothing; gradient and lightness masks still work"


def mixed_folder(folder: Path) -> dict[str, str]:
    """Write good, odd and bad images into ``folder``; return {name: expected error ('' = runs)}."""
    folder.mkdir()
    rgb = io.read_image(ROAD)
    bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
    shutil.copy(ROAD, folder / "a_road.jpg")
    cv2.imwrite(str(folder / "b_grey.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))
    cv2.imwrite(str(folder / "c_rgba.png"), cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA))
    cv2.imwrite(str(folder / "d_16bit.png"), bgr.astype(np.uint16) * 257)  # >> 8 gives back bgr
    (folder / "e_empty.jpg").write_bytes(b"")
    (folder / "f_text.jpg").write_text("not an image\n")
    data = ROAD.read_bytes()
    (folder / "g_cut.jpg").write_bytes(data[:len(data) // 3])
    (folder / "h_dir.jpg").mkdir()  # unreadable as a file, also for root
    return {"a_road.jpg": "", "b_grey.png": "", "c_rgba.png": "", "d_16bit.png": "",
            "e_empty.jpg": "the file is empty (0 bytes)", "f_text.jpg": "not a readable image",
            "g_cut.jpg": "not a readable image", "h_dir.jpg": "not a file"}


def check_failed_rows(folder: Path, rows: list[dict], expected: dict[str, str], code: int, err: str):
    """Assert one row per file, an error row and one stderr line per bad file, and exit code 1."""
    assert [r["file"] for r in rows] == sorted(expected)
    bad = {name for name, e in expected.items() if e}
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == len(bad), err
    for r in rows:
        if r["file"] in bad:
            assert set(r) == {"file", "error"}
            assert r["error"].startswith(f"{folder / r['file']}: {expected[r['file']]}")
            assert f"error: {r['error']}" in lines
        else:
            assert "error" not in r


def test_images_goes_on_past_bad_files_and_exits_1(tmp_path, capsys):
    expected = mixed_folder(tmp_path / "in")
    out = tmp_path / "out"
    code = main(["images", str(tmp_path / "in"), "-o", str(out)])
    captured = capsys.readouterr()
    rows = json.loads((out / "results.json").read_text())
    check_failed_rows(tmp_path / "in", rows, expected, code, captured.err)
    by = {r["file"]: r for r in rows}
    road = by["a_road.jpg"]
    assert road["found"] and "note" not in road
    # RGBA drops alpha and 16 bits scale back exactly: the same numbers as the road image
    for name in ("c_rgba.png", "d_16bit.png"):
        assert {k: by[name][k] for k in road if k != "file"} == {k: v for k, v in road.items() if k != "file"}
    assert by["d_16bit.png"]["note"] == "16-bit image: scaled to 8 bits (value >> 8)"
    assert by["b_grey.png"]["note"] == GREY_NOTE and by["b_grey.png"]["found"]  # the white lines
    assert sorted(p.name for p in out.iterdir()) == ["a_road.jpg", "b_grey.png", "c_rgba.png",
                                                     "d_16bit.png", "results.json"]
    assert captured.out.strip().splitlines()[-1] == (f"4 of 8 images: lane found; 4 failed; results in "
                                                     f"{out / 'results.json'}")
    assert "b_grey.png: radius" in captured.out and f"(note: {GREY_NOTE})" in captured.out


def test_hough_goes_on_past_bad_files_and_exits_1(tmp_path, capsys):
    expected = mixed_folder(tmp_path / "in")
    out = tmp_path / "out"
    code = main(["hough", str(tmp_path / "in"), "-o", str(out)])
    captured = capsys.readouterr()
    rows = json.loads((out / "results.json").read_text())
    check_failed_rows(tmp_path / "in", rows, expected, code, captured.err)
    by = {r["file"]: r for r in rows}
    assert by["a_road.jpg"]["left_found"] and by["a_road.jpg"]["right_found"]
    # the yellow left line has no colour left in grey: the note says why it is missing
    assert not by["b_grey.png"]["left_found"] and by["b_grey.png"]["note"] == GREY_NOTE
    assert "3 of 8 images: both lines found; 4 failed" in captured.out


def test_a_run_with_only_good_files_exits_0_and_usage_errors_exit_2(tmp_path, capsys):
    (tmp_path / "in").mkdir()
    shutil.copy(ROAD, tmp_path / "in" / "road.jpg")
    assert main(["images", str(tmp_path / "in"), "-o", str(tmp_path / "out")]) == 0
    assert capsys.readouterr().err == ""
    (tmp_path / "empty").mkdir()
    for args in (["images", str(tmp_path / "empty"), "-o", str(tmp_path / "o2")],
                 ["hough", str(tmp_path / "nope"), "-o", str(tmp_path / "o3")]):
        assert main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ")
    assert not (tmp_path / "o2").exists() and not (tmp_path / "o3").exists()


def test_an_image_the_calibration_does_not_fit_is_its_own_error_row(tmp_path, capsys):
    from lanelib.camera import Calibration

    Calibration(np.array([[1000.0, 0, 640], [0, 1000.0, 360], [0, 0, 1]]), np.zeros(5),
                (1280, 720)).save(tmp_path / "cal.json")
    (tmp_path / "in").mkdir()
    shutil.copy(ROAD, tmp_path / "in" / "road.jpg")
    io.write_image(tmp_path / "in" / "square.png", np.full((500, 500, 3), 80, np.uint8))
    io.write_image(tmp_path / "in" / "tiny.png", np.full((1, 1, 3), 80, np.uint8))
    code = main(["images", str(tmp_path / "in"), "-o", str(tmp_path / "out"),
                 "--calibration", str(tmp_path / "cal.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 2
    assert err[0] == (f"error: {tmp_path / 'in' / 'square.png'}: frame is 500x500 but the calibration "
                      "is for 1280x720 with another aspect ratio; calibrate this camera at this size "
                      "(`python -m lanelib calibrate`)")
    assert err[1].startswith(f"error: {tmp_path / 'in' / 'tiny.png'}: the image is 1x1 px, too small for "
                             "the bird's-eye view")
    rows = json.loads((tmp_path / "out" / "results.json").read_text())
    assert rows[0]["file"] == "road.jpg" and rows[0]["found"]


def test_every_subcommand_documents_its_exit_codes(capsys):
    for name in subcommands():
        with pytest.raises(SystemExit):
            main([name, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "exit codes: 0 every input ran;" in text and "2 nothing was run" in text
        assert "130 interrupted by Ctrl-C" in text
        assert ("every input ran; 1 " in text) == (name in ("images", "hough", "video", "evaluate", "predict",
                                                                 "scoreboard", "ablation"))
    assert "1 : the run finished but some inputs failed" in main.__doc__


def test_a_reader_that_goes_away_ends_the_run_quietly():
    """`python -m lanelib evaluate ... | true`: the reader is gone before the table is printed;
    the run ends with 141 (128 + SIGPIPE) and no BrokenPipeError traceback."""
    p = subprocess.Popen([sys.executable, "-m", "lanelib", "evaluate", "images", "test_images"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         cwd=Path(__file__).resolve().parents[1])
    p.stdout.close()  # the reader goes away at once; the evaluation takes about a second
    err = p.stderr.read()
    assert p.wait() == 141
    assert "Traceback" not in err and "BrokenPipe" not in err


def test_parse_pattern():
    assert parse_pattern("9x6") == (9, 6)
    with pytest.raises(InputError, match="COLSxROWS"):
        parse_pattern("nine")
