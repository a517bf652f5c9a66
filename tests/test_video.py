"""The `video` command: outputs, per-frame log, errors, Ctrl-C, and the figures on real videos."""
from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest

from lanelib import io
from lanelib.cli import main
from lanelib.config import PipelineConfig, load_config_or_preset, preset
from lanelib.errors import ConfigError
from lanelib.pipeline import VIDEO_LOG_COLUMNS, LanePipeline, process_video

COLUMNS = ["frame", "time_s", "found", "left_conf", "right_conf", "radius_m", "offset_m",
           "lane_width_m", "left_a", "left_b", "left_c", "right_a", "right_b", "right_c"]


def run(*args, **kw):
    return subprocess.run([sys.executable, "-m", "lanelib", *map(str, args)], capture_output=True,
                          text=True, **kw)


def read_log(path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def column(rows: list[dict], name: str) -> np.ndarray:
    return np.array([float(r[name]) if r[name] != "" else np.nan for r in rows])


def drawn_clip(path, n: int = 12, fps: float = 12.5, shift_px_per_frame: float = 2.0):
    """Write a clip of a straight lane (lines at bird's-eye x = 320 and 960, drifting right)."""
    pipe = LanePipeline()
    with io.VideoWriter(path, fps) as w:
        for i in range(n):
            bird = np.full((720, 1280, 3), 70, np.uint8)
            for x in (320, 960):
                x = round(x + i * shift_px_per_frame)
                cv2.line(bird, (x, 0), (x, 719), (235, 235, 235), 24)
            w.write(pipe.perspective.unwarp(bird))
    return path


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    return drawn_clip(tmp_path_factory.mktemp("clip") / "lane.mp4")


def leftovers(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# --------------------------------------------------------------------------- outputs and log

def test_video_writes_the_annotated_clip_and_the_log(clip, tmp_path):
    out, log = tmp_path / "out.mp4", tmp_path / "frames.csv"
    p = run("video", clip, "-o", out, "--log", log)
    assert p.returncode == 0, p.stderr
    assert "12 frames" in p.stdout and "lane found in 12 of 12 frames" in p.stdout
    assert "frame/s" in p.stderr  # the tqdm bar with its rate
    reader = io.VideoReader(out)
    assert (reader.info.width, reader.info.height) == (1280, 720)
    assert reader.info.fps == pytest.approx(12.5)  # the input's rate, not ffmpeg's default
    assert sum(1 for _ in reader) == 12
    rows = read_log(log)
    assert list(rows[0]) == COLUMNS == list(VIDEO_LOG_COLUMNS)
    assert [int(r["frame"]) for r in rows] == list(range(12))
    assert column(rows, "time_s") == pytest.approx(np.arange(12) / 12.5)
    assert all(r["found"] == "1" for r in rows)
    assert column(rows, "lane_width_m") == pytest.approx(3.7, abs=0.06)
    # the lines drift right by 2 px a frame: the car moves left of centre, the fit's c follows
    xm = PipelineConfig().perspective.xm_per_px
    offsets = column(rows, "offset_m")
    assert offsets[0] == pytest.approx(0.0, abs=0.03)
    assert np.all(np.diff(offsets[6:]) < 0) and offsets[-1] < -8 * 2 * xm
    left_c = column(rows, "left_c")
    assert left_c[0] == pytest.approx(320, abs=3) and left_c[-1] > left_c[0] + 12


def test_debug_writes_the_composite(clip, tmp_path):
    out = tmp_path / "debug.mp4"
    assert main(["video", str(clip), "-o", str(out), "--debug", "--no-progress"]) == 0
    frames = list(io.VideoReader(out))
    assert len(frames) == 12 and frames[0].shape == (720, 1280, 3)
    # the binary panel (top right, bird's-eye) shows the two lines as white columns
    panel = frames[5][:360, 640:].astype(int)
    bright_cols = np.nonzero(panel[100:250].mean(axis=(0, 2)) > 150)[0]
    assert len(bright_cols) > 0
    assert {round(c / 160) for c in bright_cols} <= {1, 3}  # near x = 160 and 480 of the 640 px panel


def test_p1_preset_is_found_by_name_and_unknown_names_are_refused(tmp_path):
    cfg = preset("p1")
    assert cfg.perspective.size_px == (960, 540)
    assert load_config_or_preset("p1") == cfg
    with pytest.raises(ConfigError, match="no such config file and no bundled preset.*p1"):
        load_config_or_preset(tmp_path / "missing.json")
    with pytest.raises(ConfigError, match="bundled presets: p1"):
        preset("nope")


# --------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("content", [b"", b"this is not a video at all\n" * 50])
def test_unreadable_or_empty_video_is_one_line_and_exit_2(tmp_path, content):
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(content)
    p = run("video", bad, "-o", tmp_path / "out.mp4", "--log", tmp_path / "log.csv")
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "bad.mp4" in lines[0]
    assert leftovers(tmp_path) == ["bad.mp4"]


def test_output_over_the_input_is_refused(clip, tmp_path):
    p = run("video", clip, "-o", clip)
    assert p.returncode == 2 and "overwrite an input" in p.stderr
    assert io.VideoReader(clip).info.width == 1280  # the input is intact


# --------------------------------------------------------------------------- interruption

def test_keyboard_interrupt_mid_run_leaves_no_file(clip, tmp_path, monkeypatch):
    from lanelib import tracking

    real_update = tracking.LaneTracker.update
    calls = []

    def interrupted(self, raw, keep_images=False):
        calls.append(1)
        if len(calls) % 4 == 0:  # the 4th frame of each run
            raise KeyboardInterrupt
        return real_update(self, raw, keep_images)

    monkeypatch.setattr(tracking.LaneTracker, "update", interrupted)
    out, log = tmp_path / "out.mp4", tmp_path / "log.csv"
    with pytest.raises(KeyboardInterrupt):
        process_video(clip, out, log_path=log, progress=False)
    assert len(calls) == 4 and leftovers(tmp_path) == []
    assert main(["video", str(clip), "-o", str(out), "--log", str(log), "--no-progress"]) == 130
    assert len(calls) == 8
    assert leftovers(tmp_path) == []


def test_ctrl_c_on_the_command_leaves_no_file(tmp_path):
    """SIGINT to the whole process group, as a terminal's Ctrl-C does (ffmpeg gets it too)."""
    src = drawn_clip(tmp_path / "long.mp4", n=150, fps=25)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "lanelib", "video", str(src), "-o",
                             str(out_dir / "o.mp4"), "--log", str(out_dir / "o.csv"), "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60
    while not any(p.stat().st_size > 0 for p in out_dir.glob("*.part.mp4")):
        assert proc.poll() is None and time.monotonic() < deadline, "the run ended before Ctrl-C"
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted; no partial output was left behind" in err
    assert leftovers(out_dir) == []


# --------------------------------------------------------------------------- real videos

@pytest.fixture(scope="session")
def project_run(udacity_advanced, udacity_calibration, tmp_path_factory):
    """The whole Udacity project video through `video` once: (log rows, output path)."""
    d = tmp_path_factory.mktemp("project")
    udacity_calibration.save(d / "cal.json")
    out, log = d / "project.mp4", d / "frames.csv"
    p = run("video", udacity_advanced / "videos" / "project_video.mp4", "-o", out,
            "--calibration", d / "cal.json", "--log", log, "--no-progress")
    assert p.returncode == 0, p.stderr
    return read_log(log), out


def first_long_left_curve(curvature: np.ndarray, min_frames: int = 100) -> tuple[int, int]:
    """Return [start, end) of the first run of >= min_frames frames bending left with R < 3 km."""
    k = np.array([np.median(curvature[max(0, i - 12):i + 13]) for i in range(len(curvature))])
    left = k < -1 / 3000
    start = None
    for i, v in enumerate(np.append(left, False)):
        if v and start is None:
            start = i
        elif not v and start is not None:
            if i - start >= min_frames:
                return start, i
            start = None
    raise AssertionError("no long left curve")


@pytest.mark.udacity
@pytest.mark.slow
def test_project_video_figures(project_run):
    rows, out = project_run
    assert len(rows) == 1260 and io.VideoReader(out).info.n_frames == 1260
    found = column(rows, "found")
    width = column(rows, "lane_width_m")
    offset = column(rows, "offset_m")
    assert found.all()
    assert np.all((width >= 3.0) & (width <= 4.5))
    assert np.all(np.abs(offset) < 0.6)
    assert np.mean(np.abs(np.diff(offset)) < 0.10) >= 0.99
    # the first long curve bends left for about 12 s from the start; Udacity: radius about 1 km
    start, end = first_long_left_curve(np.sign(column(rows, "left_a") + column(rows, "right_a"))
                                       / column(rows, "radius_m"))
    assert start < 25 and 250 <= end <= 330, (start, end)
    assert 600 <= np.median(column(rows, "radius_m")[start:end]) <= 1600
    assert np.all(column(rows, "left_conf")[found > 0] > 0)


@pytest.mark.udacity
@pytest.mark.slow
@pytest.mark.parametrize("name", ["solidWhiteRight", "solidYellowLeft"])
def test_p1_clips_with_the_p1_preset(udacity_p1, tmp_path, name):
    log = tmp_path / "frames.csv"
    p = run("video", udacity_p1 / "test_videos" / f"{name}.mp4", "-o", tmp_path / "out.mp4",
            "--config", "p1", "--log", log, "--no-progress")
    assert p.returncode == 0, p.stderr
    rows = read_log(log)
    assert len(rows) == {"solidWhiteRight": 221, "solidYellowLeft": 681}[name]
    width = column(rows, "lane_width_m")
    assert np.mean((width >= 3.0) & (width <= 4.5)) >= 0.95
