"""The `video` command: outputs, per-frame log, errors, Ctrl-C, and the figures on real videos."""
from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from lanelib import io, thresholds
from lanelib.cli import main
from lanelib.config import PipelineConfig, load_config_or_preset, preset
from lanelib.errors import ConfigError, DecodeStoppedError
from lanelib.pipeline import LanePipeline
from lanelib.batch import VIDEO_LOG_COLUMNS, process_video
from lanelib.batch.video import VideoWriter

COLUMNS = ["frame", "time_s", "found", "method", "left_conf", "right_conf", "radius_m", "offset_m",
           "lane_width_m", "left_a", "left_b", "left_c", "right_a", "right_b", "right_c",
           "left_source", "right_source"]


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
    with VideoWriter(path, fps) as w:
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
    with pytest.raises(ConfigError, match="bundled presets: country, culane, hard-roads, highway, p1, tusimple"):
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

    def interrupted(self, raw, keep_images=False, index=None):
        calls.append(1)
        if len(calls) % 4 == 0:  # the 4th frame of each run
            raise KeyboardInterrupt
        return real_update(self, raw, keep_images, index)

    monkeypatch.setattr(tracking.LaneTracker, "update", interrupted)
    out, log = tmp_path / "out.mp4", tmp_path / "log.csv"
    with pytest.raises(KeyboardInterrupt):
        process_video(clip, out, log_path=log, progress=False)
    assert len(calls) == 4 and leftovers(tmp_path) == []
    assert main(["video", str(clip), "-o", str(out), "--log", str(log), "--no-progress"]) == 130
    assert len(calls) == 8
    assert leftovers(tmp_path) == []


def test_ctrl_c_on_the_command_leaves_no_file(tmp_path):
    """SIGINT to the whole process group, as a terminal's Ctrl-C does (ffmpeg gets it too).

    The command starts with SIGINT at its default, as a terminal's foreground job does: a process
    that ignores SIGINT passes that on to its children (a background job of a shell; under `make
    test` a pytest-xdist worker that has run the Dask tests), and the run would rightly go on."""
    src = drawn_clip(tmp_path / "long.mp4", n=150, fps=25)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "lanelib", "video", str(src), "-o",
                             str(out_dir / "o.mp4"), "--log", str(out_dir / "o.csv"), "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
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


def check_readme_video_row(readme_table, clip: str, rows: list[dict]) -> None:
    """Compare a video's per-frame log with its row of the 'Real video' table of docs/results.md.

    Percentages to the 0.1 point they are written with (a whole percent where written so), widths
    within 0.05 m and the largest |offset| within 0.03 m.
    """
    row = next((r for r in readme_table("Real video") if r["clip"].split()[-1] == clip), None)
    assert row is not None, f"docs/results.md: no row for {clip} in the 'Real video' table"
    found = column(rows, "found") > 0
    width = column(rows, "lane_width_m")
    offset = column(rows, "offset_m")
    assert len(rows) == int(row["frames"].replace(",", ""))

    def percent(cell: str, value: float) -> None:
        text = cell.replace("%", "").strip()
        tol = 0.05 if "." in text else 0.5
        assert 100 * value == pytest.approx(float(text), abs=tol), (clip, cell, 100 * value)

    percent(row["lane found"], found.mean())
    percent(row["width in 3.0–4.5 m"], np.mean((width >= 3.0) & (width <= 4.5)))
    lo, med, hi = (float(v) for v in row["width min / median / max (m)"].split("/"))
    w = width[found]
    assert (w.min(), np.median(w), w.max()) == pytest.approx((lo, med, hi), abs=0.05), clip
    max_offset = float(row["max \\|offset\\|"].replace("m", ""))
    assert np.nanmax(np.abs(offset[found])) == pytest.approx(max_offset, abs=0.03), clip


@pytest.mark.udacity
@pytest.mark.slow
def test_project_video_figures(project_run, readme_table):
    rows, out = project_run
    assert len(rows) == 1260 and io.VideoReader(out).info.n_frames == 1260
    check_readme_video_row(readme_table, "project_video", rows)
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
def test_p1_clips_with_the_p1_preset(udacity_p1, tmp_path, name, readme_table):
    log = tmp_path / "frames.csv"
    p = run("video", udacity_p1 / "test_videos" / f"{name}.mp4", "-o", tmp_path / "out.mp4",
            "--config", "p1", "--log", log, "--no-progress")
    assert p.returncode == 0, p.stderr
    rows = read_log(log)
    assert len(rows) == {"solidWhiteRight": 221, "solidYellowLeft": 681}[name]
    width = column(rows, "lane_width_m")
    assert np.mean((width >= 3.0) & (width <= 4.5)) >= 0.95
    check_readme_video_row(readme_table, name, rows)


# --------------------------------------------------------------------------- the band hot path

def textured_frame(seed: int) -> np.ndarray:
    """Return a 1280x720 frame of noisy road with bright and yellow strokes (many mask hits)."""
    rng = np.random.default_rng(seed)
    img = np.clip(rng.normal(95, 30, (720, 1280, 3)), 0, 255).astype(np.uint8)
    img = cv2.GaussianBlur(img, (5, 5), 0)
    for _ in range(40):
        x, y = int(rng.integers(0, 1280)), int(rng.integers(0, 720))
        color = [(240, 240, 240), (230, 190, 40), (200, 150, 60)][int(rng.integers(0, 3))]
        cv2.line(img, (x, y), (x + int(rng.integers(-40, 40)), y + int(rng.integers(20, 200))),
                 color, int(rng.integers(3, 30)))
    return img


BAND_CONFIGS = {
    "default": {},
    "open and close": {"thresholds": {"open_px": 3, "close_px": 5}},
    "wide kernels": {"thresholds": {"rule": "sobel_dir & (sobel_mag | sobel_y) | line_tophat & ~white",
                                    "sobel_dir": {"enabled": True, "kernel_px": 7},
                                    "sobel_mag": {"enabled": True, "kernel_px": 5},
                                    "sobel_y": {"enabled": True, "kernel_px": 1},
                                    "line_tophat": {"width_px": 40}}},
    "per-mask openings": {"thresholds": {"rule": "yellow | (white & line_tophat) | s_channel",
                                         "yellow": {"open_px": 5}, "white": {"open_px": 3},
                                         "s_channel": {"open_px": 4}}},
}
# configs whose masks depend on the whole view (CLAHE's tiles): the band path thresholds the
# whole view and cuts the bands from it, so it is exact, but a crop grown by context_px is not
BAND_WHOLE_VIEW_CONFIGS = {
    "clahe": {"thresholds": {"clahe": True, "clahe_clip_limit": 3.0}},
    "clahe and openings": {"thresholds": {"clahe": True, "yellow": {"open_px": 3}, "open_px": 3}},
}
PRIORS = {  # (left, right) bird's-eye fits: ordinary, curved, at the image's edges, one line only
    "ordinary": ((0.0, 0.0, 320.0), (0.0, 0.0, 960.0)),
    "curved": ((4e-4, -0.5, 420.0), (4e-4, -0.5, 1060.0)),
    "edges": ((0.0, 0.02, 10.0), (0.0, -0.02, 1275.0)),
    "close together": ((0.0, 0.0, 560.0), (0.0, 0.0, 700.0)),
    "right only": (None, (1e-4, 0.1, 900.0)),
}


@pytest.mark.parametrize("config_name", [*BAND_CONFIGS, *BAND_WHOLE_VIEW_CONFIGS])
def test_band_detection_sees_the_same_pixels_as_the_full_view(config_name):
    from lanelib.config import from_dict
    from lanelib.records import LineFit

    cfg = from_dict(PipelineConfig, {**BAND_CONFIGS, **BAND_WHOLE_VIEW_CONFIGS}[config_name])
    pipe = LanePipeline(cfg)
    raw = textured_frame(len(config_name))
    for name, (left, right) in PRIORS.items():
        prior = (LineFit(left, 500, 700.0), LineFit(right, 500, 700.0))
        band = pipe.detect(raw, prior=prior)                      # bands only
        full = pipe.detect(raw, prior=prior, keep_images=True)    # whole view
        for side in ("left", "right"):
            for a, b in zip(getattr(band.search, f"{side}_pixels"), getattr(full.search, f"{side}_pixels")):
                assert np.array_equal(a, b), (config_name, name, side)
            assert getattr(band, side).coeffs_px == getattr(full, side).coeffs_px
        mask = pipe.band_binary(raw, prior)
        assert np.all(full.images["binary"][mask > 0] == 255)  # nothing outside the full mask


@pytest.mark.parametrize("config_name", BAND_CONFIGS)
def test_a_crop_grown_by_context_px_thresholds_exactly(config_name):
    from lanelib import thresholds
    from lanelib.config import from_dict

    tconf = from_dict(PipelineConfig, BAND_CONFIGS[config_name]).thresholds
    cx, cy = thresholds.context_px(tconf)
    img = textured_frame(7)
    full = thresholds.combine(img, tconf)
    for x0, y0, x1, y1 in [(300, 200, 420, 380), (0, 0, 150, 90), (1100, 600, 1280, 720)]:
        a0, b0, a1, b1 = max(0, x0 - cx), max(0, y0 - cy), min(1280, x1 + cx), min(720, y1 + cy)
        crop = thresholds.combine(img[b0:b1, a0:a1], tconf)
        assert np.array_equal(crop[y0 - b0:y1 - b0, x0 - a0:x1 - a0], full[y0:y1, x0:x1])
    if config_name == "default":  # the top-hat's border is tight: one pixel short is not enough
        spec = tconf.line_tophat
        r = 2 * (spec.width_px // 2)  # the top-hat's own part of mask_context_px
        assert thresholds.mask_context_px(spec)[0] == r + spec.min_width_px - 1
        kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (spec.width_px, 1))
        light = thresholds.channel(img, spec.space, spec.channel)
        tophat = lambda a: cv2.morphologyEx(a, cv2.MORPH_TOPHAT, kernel)  # noqa: E731
        whole = tophat(light)[:, 300:420]
        assert np.array_equal(tophat(light[:, 300 - r:420 + r])[:, r:-r], whole)
        assert not np.array_equal(tophat(light[:, 301 - r:419 + r])[:, r - 1:-(r - 1)], whole)


@pytest.mark.udacity
def test_band_detection_on_real_frames(udacity_advanced, udacity_calibration):
    pipe = LanePipeline(PipelineConfig(), udacity_calibration)
    prior = None
    checked = 0
    with io.VideoReader(udacity_advanced / "videos" / "project_video.mp4") as reader:
        for i, raw in enumerate(reader):
            if i >= 120:
                break
            if i % 8:
                continue
            if prior is not None:
                band, full = pipe.detect(raw, prior=prior), pipe.detect(raw, prior=prior, keep_images=True)
                assert band.left.coeffs_px == full.left.coeffs_px
                assert band.right.coeffs_px == full.right.coeffs_px
                checked += 1
            r = pipe.detect(raw)
            prior = (r.left, r.right)
    assert checked == 14


@pytest.mark.parametrize("degree", [1, 2])
def test_the_moment_fit_is_numpys_least_squares_fit(degree):
    from lanelib.fit import least_squares_poly

    rng = np.random.default_rng(degree)
    for n, lo, hi in [(20000, 0, 720), (300, 500, 720), (5, 10, 600)]:
        ys = rng.integers(lo, hi, n).astype(np.int32)
        xs = (2e-4 * ys ** 2 - 0.3 * ys + 500 + rng.normal(0, 8, n)).astype(np.int32)
        ours = np.array(least_squares_poly(ys, xs, degree, 720.0))[2 - degree:]
        numpy = np.polyfit(ys.astype(float), xs.astype(float), degree)
        assert ours == pytest.approx(numpy, rel=1e-8, abs=1e-12)


def test_the_overlay_blended_in_its_box_equals_the_whole_frame_blend():
    from lanelib import draw
    from lanelib.perspective import Perspective

    image = textured_frame(11)
    persp = Perspective()
    minv = persp.Minv
    cfg = draw.DrawConfig()
    for left, right in [((0, 0, 320), (0, 0, 960)), ((4e-4, -0.5, 420), (4e-4, -0.5, 1060)),
                        ((0, 0, -3000), (0, 0, 5000)), ((1e-3, 0, 100), (1e-3, 0, 1200))]:
        fill = image.copy()
        pts = [cv2.perspectiveTransform(draw.line_points(c, 720, cfg.samples).reshape(-1, 1, 2), minv)
               .reshape(-1, 2) for c in (left, right)]
        cv2.fillPoly(fill, [draw.pixel_points(np.vstack([pts[0], pts[1][::-1]]))], cfg.lane_color,
                     lineType=cv2.LINE_AA)
        expected = cv2.addWeighted(fill, cfg.lane_alpha, image, 1 - cfg.lane_alpha, 0)
        for p, color in zip(pts, (cfg.left_color, cfg.right_color)):
            cv2.polylines(expected, [draw.pixel_points(p)], False, color, cfg.line_thickness_px, cv2.LINE_AA)
        assert np.array_equal(draw.lane_overlay(image, left, right, persp.inverse, cfg), expected)


def test_distort_points_is_opencvs_projection():
    from lanelib.camera import Calibration, distort_points

    K = np.array([[1150.0, 0, 660.0], [0, 1148.0, 380.0], [0, 0, 1]])
    rng = np.random.default_rng(5)
    pts = np.column_stack([rng.uniform(-300, 1600, 5000), rng.uniform(-200, 900, 5000)])
    norm = np.column_stack([(pts[:, 0] - 660.0) / 1150.0, (pts[:, 1] - 380.0) / 1148.0, np.ones(5000)])
    for dist in ([-0.24, -0.05, -0.001, 0.0002, 0.02], [0.1, -0.3, 0.002, -0.001], [-0.2, 0.1, 0, 0, 0.05, 0.01, 0, 0]):
        cal = Calibration(K, np.array(dist), (1280, 720))
        expected, _ = cv2.projectPoints(norm, np.zeros(3), np.zeros(3), K, np.array(dist))
        assert np.abs(distort_points(cal, pts) - expected.reshape(-1, 2)).max() < 1e-6


# --------------------------------------------------------------------------- synthetic ground truth

SYNTH = Path(__file__).resolve().parents[1] / "videos"


def synthetic_report(name: str, use_tracker: bool = True):
    from lanelib import evaluate

    path = SYNTH / f"{name}.mp4"  # bundled with the repo: missing is a failure, not a skip
    cal = evaluate.calibration_from_truth(path)
    return evaluate.evaluate_video(path, LanePipeline(PipelineConfig(), cal, size=cal.image_size),
                                   use_tracker=use_tracker)


def test_synthetic_project_tracked_against_truth():
    report = synthetic_report("project")
    err = report.offset_err_cm
    assert report.found.all()
    assert np.median(err) <= 5.0 and err.max() <= 30.0
    assert report.summary()["point_accuracy"] >= 0.95


def test_synthetic_challenge_tracked_against_truth():
    report = synthetic_report("challenge")
    assert report.found.mean() >= 0.95
    assert np.nanmedian(report.offset_err_cm) <= 5.0


# --------------------------------------------------------------------------- bench

def test_bench_reports_every_figure_consistently(capsys):
    from lanelib import bench
    from lanelib.evaluate import calibration_from_truth

    clip = SYNTH / "project.mp4"  # bundled with the repo
    f = bench.run(clip, calibration_from_truth(clip), clip_frames=12, stage_frames=4, repeats=1,
                  video_rounds=1, fallback_clips=("project", "harder"), fallback_frames=30)
    assert {"detect_ms", "remap_ms", "detect_to_remap", "video_fps", "codec_fps",
            "video_to_codec"} <= set(f)
    assert f["detect_to_remap"] == pytest.approx(f["detect_ms"] / f["remap_ms"], rel=0.01)
    assert f["video_to_codec"] == pytest.approx(f["video_fps"] / f["codec_fps"], rel=0.01)
    assert f["robust_ms"] > 0 and Path(f["robust_source"]).name in ("challenge_video.mp4", "challenge.mp4")
    assert f["robust_to_remap"] == pytest.approx(f["robust_ms"] / f["robust_remap_ms"], rel=0.01)
    assert 0 < f["default_ms"] and f["default_to_remap"] > 0
    assert f["size"] == [1280, 720] and f["calibrated"]
    stages = f["stages_ms"]
    assert {"remap", "detect", "band_binary (prior bands)", "undistort (images, --debug)",
            "annotate raw (video path)", "tracker update"} <= set(stages)
    rule = thresholds.rule_masks(PipelineConfig().thresholds)
    assert len(rule) >= 2 and {f"  mask {n}" for n in rule} <= set(stages)
    assert "vanishing point (geometry)" in stages
    geo = f["geometry_s"]
    assert geo["frames"] == 50 and geo["cpu_s"] > 0 and geo["result"].startswith("confidence")
    report = bench.format_report(f)
    assert "detect_to_remap" in report and "video_to_codec" in report and f"mask {rule[0]}" in report
    assert "robust_to_remap" in report and "every fallback runs" in report
    assert "--auto-geometry's estimate from 50 frames" in report
    # the clean clip never needs a fallback; harder's first second (tree shade hides the dashes)
    # does, and each fallback frame counts at least one run
    fb = f["fallbacks"]
    assert set(fb) == {"project.mp4", "harder.mp4"}  # the benchmarked clip is not measured twice
    assert fb["project.mp4"]["frames"] == 30 and fb["project.mp4"]["fallback_pct"] == 0.0
    assert fb["project.mp4"]["runs"] == {} and fb["project.mp4"]["cpu_ms_fallback"] is None
    hard = fb["harder.mp4"]
    assert hard["fallback_pct"] > 0 and hard["cpu_ms_fallback"] > 0
    assert sum(hard["runs"].values()) >= round(hard["fallback_pct"] * 30 / 100)
    assert "fallback searches of the tracker" in report and "harder.mp4" in report


def test_bench_refuses_a_tiny_clip():
    p = run("bench", "--frames", "5")
    assert p.returncode == 2 and "--frames 5: give 10 frames or more" in p.stderr


# --------------------------------------------------------------------------- broken videos

PROJECT = SYNTH / "project.mp4"


def broken_video(kind: str, folder: Path, faststart: Path) -> Path:
    """Write a video that cannot be read at all into ``folder``, with the project's truth beside it."""
    path = folder / f"{kind}.mp4"
    data = PROJECT.read_bytes()
    if kind == "truncated":  # the first 30 % of the bytes: the index (written last) is gone
        path.write_bytes(data[:int(0.3 * len(data))])
    elif kind == "codec":  # a codec tag no decoder knows
        i = data.index(b"avc1", data.index(b"stsd"))
        path.write_bytes(data[:i] + b"zzzz" + data[i + 4:])
    elif kind == "no_frames":
        subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(PROJECT), "-c",
                        "copy", "-frames:v", "0", str(path)], check=True)
    elif kind == "first_frame_cut":  # the index, and half of the first frame
        head = faststart.read_bytes()
        path.write_bytes(head[:head.index(b"mdat") + 5000])
    else:
        path.write_bytes(b"GIF89a" + bytes(range(256)) * 8)
    for suffix in (".csv", ".json"):
        shutil.copy(PROJECT.with_suffix(suffix), path.with_suffix(suffix))
    return path


@pytest.mark.parametrize("kind,cause", [
    ("truncated", "moov atom not found: the mp4 has no index"),
    ("codec", "unknown codec"),
    ("no_frames", "the file holds no video stream"),
    ("first_frame_cut", "not a readable video"),
    ("not_a_video", "no video stream found"),
])
def test_an_unreadable_video_is_one_line_exit_2_and_nothing_written(tmp_path, faststart, capsys, kind, cause):
    src = broken_video(kind, tmp_path, faststart)
    before = leftovers(tmp_path)
    out = tmp_path / "out"
    for args in (["video", src, "-o", out / "v.mp4", "--log", out / "v.csv", "--no-progress"],
                 ["hough", src, "-o", out / "h.mp4", "--log", out / "h.csv", "--no-progress"],
                 ["evaluate", "video", src, "--json", out / "e.json"]):
        assert main([str(a) for a in args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"error: {src}: ") and cause in err[0], err
    assert leftovers(tmp_path) == before  # no output, not even the output folder's files
    assert not out.exists() or leftovers(out) == []


def test_a_video_broken_half_way_keeps_the_frames_before_the_break(tmp_path, faststart, capsys):
    data = faststart.read_bytes()
    src = tmp_path / "cut.mp4"
    src.write_bytes(data[:len(data) // 12])
    with pytest.raises(DecodeStoppedError) as e:  # how many frames the cut file holds
        for _ in io.VideoReader(src):
            pass
    n = e.value.frames
    assert 8 <= n <= 40
    for command in ("video", "hough"):
        out, log = tmp_path / f"{command}.mp4", tmp_path / f"{command}.csv"
        assert main([command, str(src), "-o", str(out), "--log", str(log), "--no-progress"]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"error: {src}: decoding stopped at frame {n}: the file ends after {n} of the 250 "
                       f"frames its container announces (truncated?); wrote {n} frames to {out} and "
                       f"{n} rows to {log}"]
        assert sum(1 for _ in io.VideoReader(out)) == n
        assert [int(r["frame"]) for r in read_log(log)] == list(range(n))
    assert not list(tmp_path.glob(".*part*"))
    # evaluate cannot score frames that are not there: exit 2, unless it needs only those
    for use in ([], ["--max-frames", str(n + 1)]):
        for suffix in (".csv", ".json"):
            shutil.copy(PROJECT.with_suffix(suffix), src.with_suffix(suffix))
        assert main(["evaluate", "video", str(src), *use]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"only {n} of the {n + 1 if use else 250} frames to score" in err[0]
    assert main(["evaluate", "video", str(src), "--max-frames", str(n)]) == 0
    assert capsys.readouterr().err == ""
