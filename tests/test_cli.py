"""The command line: help, exit codes, outputs of calibrate and images."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from lanelib import io
from lanelib.cli import build_parser, main


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
    assert "calibration1.jpg" in p.stderr  # the skipped boards are named in a warning
    out = tmp_path / "out"
    p = run("images", udacity_advanced / "test_images", "-o", out, "--calibration", cal, "--debug")
    assert p.returncode == 0, p.stderr
    rows = json.loads((out / "results.json").read_text())
    assert len(rows) == 8 and all(r["found"] for r in rows)
    assert all(set(r) >= {"file", "found", "left_found", "right_found", "radius_m", "offset_m",
                          "lane_width_m"} for r in rows)
    assert len(list(out.glob("*.jpg"))) == 8
