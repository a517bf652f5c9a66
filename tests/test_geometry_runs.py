"""The road geometry in runs and on the command line: `geometry`, `--auto-geometry`, the drift watch."""
from __future__ import annotations

import csv
import json
import math
import pickle
import re
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from lanelib import autogeometry, batch, io
from lanelib.batch.video import VideoWriter
from lanelib.camera import Calibration, calibrate
from lanelib.cli import main
from lanelib.config import PipelineConfig, load_config, save_config
from lanelib.errors import GeometryError
from lanelib.synth import load_video_truth

REPO = Path(__file__).resolve().parents[1]
CLIP = REPO / "videos" / "project.mp4"
OPTIONS = autogeometry.GeometryOptions(seconds=6.0, max_frames=25)


@pytest.fixture(scope="module")
def calibration_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("cal") / "calibration.json"
    calibrate(REPO / "camera_cal").save(path)
    return path


@pytest.fixture(scope="module")
def estimate(calibration_file):
    cal = Calibration.load(calibration_file)
    return cal, batch.estimate_road_geometry(CLIP, cal, OPTIONS)


def test_the_estimate_on_the_bundled_clip_finds_the_true_horizon(estimate):
    _, geo = estimate
    truth = load_video_truth(CLIP).camera
    row, _ = truth.horizon_px()
    assert geo.horizon_row_px == pytest.approx(row, abs=2.0)
    assert not geo.low_confidence
    config = batch.with_geometry(PipelineConfig(), geo)
    assert config.perspective == geo.perspective_config()
    assert config.perspective.car_x_px == pytest.approx(640.0)  # the camera's line: dst centre
    assert config.thresholds == PipelineConfig().thresholds


def test_a_seam_inside_the_lane_is_not_taken_for_a_lane_line(calibration_file):
    """Known answer: the bundled challenge clip (3.6 m lanes, the camera 1.25 m up) has a
    resurfaced strip's edge and a tar seam inside the ego lane, seen in more frames than the
    worn dashed line; the lane's width is the one its neighbours' spacing agrees with, so the
    camera's height comes out at its truth scaled by the assumed 3.7 m over the true 3.6 m
    (taking the seam for the right line reads 2.0 m, and a roll of 0.6 deg)."""
    clip = REPO / "videos" / "challenge.mp4"
    truth = load_video_truth(clip).camera
    geo = batch.estimate_road_geometry(clip, Calibration.load(calibration_file), autogeometry.GeometryOptions())
    assert geo.camera_height_m == pytest.approx(truth.height_m * 3.7 / 3.6, rel=0.03)
    assert geo.roll_deg == pytest.approx(truth.roll_deg, abs=0.2)


def test_geometry_cli_writes_a_config_that_scores_like_the_true_points(calibration_file, tmp_path, capsys):
    out = tmp_path / "geometry.json"
    figures = tmp_path / "figures.json"
    code = main(["geometry", str(CLIP), "-o", str(out), "--calibration", str(calibration_file),
                 "--geometry-seconds", "6", "--json", str(figures)])
    printed = capsys.readouterr().out
    assert code == 0
    assert "vanishing point (" in printed and "confidence" in printed and f"--config {out}" in printed
    config = load_config(out)
    assert np.allclose(json.loads(figures.read_text())["src_px"], config.perspective.src_px, atol=1e-3)
    # scored against the ground truth through the estimated view: as good as the default points
    assert main(["evaluate", "video", str(CLIP), "--config", str(out), "--max-frames", "50",
                 "--json", str(tmp_path / "eval.json")]) == 0
    scores = json.loads((tmp_path / "eval.json").read_text())
    assert scores["found_rate"] == 1.0 and scores["point_accuracy"] >= 0.99
    assert scores["offset_err_cm_median"] < 5.0
    assert config.perspective.lane_width_m == 3.7


def test_geometry_cli_merges_into_a_tuned_config(calibration_file, tmp_path, capsys):
    tuned = tmp_path / "tuned.json"
    base = PipelineConfig()
    save_config(replace(base, search=replace(base.search, margin_px=55)), tuned)
    assert main(["geometry", str(CLIP), "-o", str(tuned), "--calibration", str(calibration_file),
                 "--geometry-seconds", "6"]) == 0
    merged = load_config(tuned)
    assert merged.search.margin_px == 55  # what the tuner saved is kept
    assert merged.perspective != base.perspective and merged.perspective.car_x_px is not None


def test_geometry_cli_checks_every_output_before_any_work(tmp_path, capsys):
    """-o, --json and --lens-out (default: OUT.lens.json) are checked before the frames are read:
    over an input, over another output, a folder or under a file, the run stops at once (exit
    2) naming the path, and writes nothing."""
    out, afile = tmp_path / "g.json", tmp_path / "afile"
    afile.write_text("")
    cases = [
        (["--lens-out", str(CLIP)], f"{CLIP}: output would overwrite an input"),
        (["--lens-out", str(out)], f"{out}: is another output of this command too"),
        (["--json", str(tmp_path / "g.lens.json")], "g.lens.json: is another output of this command too"),
        (["--lens-out", str(afile / "lens.json")], f"afile/lens.json: cannot be written ({afile} is not a folder)"),
        (["--lens-out", str(tmp_path)], f"{tmp_path}: is a folder"),
        (["--json", str(afile / "g.fig.json")], "g.fig.json: cannot be written"),
    ]
    for extra, message in cases:
        assert main(["geometry", str(CLIP), "-o", str(out)] + extra) == 2, extra
        err = capsys.readouterr().err
        assert message in err, (extra, err)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]
    assert main(["geometry", str(CLIP), "-o", str(afile / "g.json")]) == 2
    assert "g.json: cannot be written" in capsys.readouterr().err
    # a lens is estimated only without a calibration: --lens-out with one is refused, not ignored
    assert main(["geometry", str(CLIP), "-o", str(out), "--calibration", str(afile),
                 "--lens-out", str(tmp_path / "l.json")]) == 2
    assert "with --calibration the lens is the calibration's" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_video_auto_geometry_tracks_the_lane(calibration_file, tmp_path, capsys):
    out = tmp_path / "out.mp4"
    code = main(["video", str(CLIP), "-o", str(out), "--calibration", str(calibration_file),
                 "--auto-geometry", "--geometry-seconds", "6", "--end", "3", "--no-progress"])
    printed = capsys.readouterr().out
    assert code == 0
    assert "estimating the road geometry from the first 6 s" in printed and "horizon row" in printed
    assert "lane found in 75 of 75 frames" in printed


def _grey_clip(path: Path, frames: int = 20) -> Path:
    with VideoWriter(path, 25.0) as w:
        for i in range(frames):
            w.write(np.full((360, 640, 3), 90 + i % 3, np.uint8))
    return path


def test_no_road_stops_the_run_with_the_reason(tmp_path, capsys):
    clip = _grey_clip(tmp_path / "grey.mp4")
    for argv in (["geometry", str(clip), "-o", str(tmp_path / "g.json")],
                 ["video", str(clip), "-o", str(tmp_path / "o.mp4"), "--auto-geometry"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert str(clip) in err and "no road" in err
    assert not (tmp_path / "g.json").exists() and not (tmp_path / "o.mp4").exists()


def test_a_rotated_clip_is_refused(tmp_path, capsys):
    rotated = tmp_path / "rotated.mp4"
    with io.VideoReader(CLIP, 0, 40) as r, VideoWriter(rotated, 25.0) as w:
        for frame in r:
            w.write(np.ascontiguousarray(np.rot90(frame)))
    assert main(["geometry", str(rotated), "-o", str(tmp_path / "g.json")]) == 2
    err = capsys.readouterr().err
    assert str(rotated) in err and ("rotated" in err or "confidence" in err)


def test_a_night_clip_is_refused_unless_accepted(tmp_path, capsys):
    night = tmp_path / "night.mp4"
    with io.VideoReader(CLIP, 0, 100) as r, VideoWriter(night, 25.0) as w:
        for frame in r:
            w.write((frame * 0.12).astype(np.uint8))
    code = main(["geometry", str(night), "-o", str(tmp_path / "g.json")])
    err = capsys.readouterr().err
    assert code == 2 and str(night) in err
    assert "confidence" in err or "no road" in err or "too few" in err


def test_low_confidence_is_refused_unless_accepted(calibration_file, tmp_path, capsys):
    # the bundled test images: 3 of 8 on straight road, too few for a confident estimate
    argv = ["images", str(REPO / "test_images"), "-o", str(tmp_path / "out"), "--calibration",
            str(calibration_file), "--auto-geometry"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "below 0.5" in err and "--accept-low-confidence" in err and "(--calibration)" not in err
    assert main(argv + ["--accept-low-confidence"]) == 0
    printed = capsys.readouterr().out
    assert "confidence 0.3" in printed and "of 8 images: lane found" in printed


def _shifted(frame: np.ndarray, dy: float) -> np.ndarray:
    """The frame moved down by dy px (the horizon of a camera that pitched up)."""
    m = np.float32([[1, 0, 0], [0, 1, dy]])
    return cv2.warpAffine(frame, m, (frame.shape[1], frame.shape[0]), borderMode=cv2.BORDER_REPLICATE)


def test_the_watch_estimates_again_when_the_horizon_moves(estimate):
    cal, geo = estimate
    frames = batch.sample_frames(CLIP, 6.0, 25)
    straight = [f for f in frames if autogeometry.vanishing_point(f, cal, geo.hood_row_px).ok]
    assert len(straight) >= 6
    options = autogeometry.GeometryOptions(check_every_s=0.04)  # every frame; 5 in a row (the default)
    watch = autogeometry.GeometryWatch(geo, cal, options, fps=25.0)
    for i, f in enumerate(straight[:4]):  # on the horizon: nothing happens
        assert watch.check(f, i, i / 25) is None
    assert watch.notes == []
    moved = [_shifted(f, 12.0) for f in straight]
    got = [watch.check(f, 10 + i, (10 + i) / 25) for i, f in enumerate(moved[:5])]
    assert got[:4] == [None] * 4 and got[4] is not None, watch.notes
    assert got[4].horizon_row_px == pytest.approx(geo.horizon_row_px + 12.0, abs=1.5)
    assert len(watch.notes) == 1 and "below the horizon in 5 checks in a row" in watch.notes[0]
    assert "geometry estimated again" in watch.notes[0]
    assert watch.check(moved[5], 20, 0.8) is None  # the new horizon is where the frames say



def test_the_watch_pickles_without_its_maps_and_goes_on_the_same(estimate):
    """A Dask segment ships the watch back to the driver: it pickles without its finder (the
    undistortion maps and the hood mask, megabytes), which the copy builds again on first use,
    and the copy checks the next frames as the original does, a new estimate included."""
    cal, geo = estimate
    frames = batch.sample_frames(CLIP, 6.0, 25)
    straight = [f for f in frames if autogeometry.vanishing_point(f, cal, geo.hood_row_px).ok][:6]
    watch = autogeometry.GeometryWatch(geo, cal, autogeometry.GeometryOptions(check_every_s=0.04), fps=25.0)
    assert watch.check(straight[0], 0, 0.0) is None  # the finder is built
    assert len(pickle.dumps(watch)) < 20_000 < 100 * 20_000 < len(pickle.dumps(watch.finder))
    moved = [_shifted(f, 12.0) for f in straight]
    for i, f in enumerate(moved[:2]):  # two checks off the horizon: two frames held
        assert watch.check(f, 10 + i, (10 + i) / 25) is None
    copy = pickle.loads(pickle.dumps(watch))
    assert copy._finder is None and copy.state_key() == watch.state_key()
    for i, f in enumerate(moved[2:], start=12):  # the 5th check off the horizon estimates again
        got = [w.check(f, i, i / 25) for w in (watch, copy)]
        assert [g is None for g in got] == [i != 14] * 2
        assert got[0] is None or got[0].to_dict() == got[1].to_dict()
    assert len(copy.notes) == 1 and copy.notes == watch.notes and copy.state_key() == watch.state_key()


def test_refined_geometry_moves_the_view_along_the_horizon_and_keeps_the_scale(estimate):
    _, geo = estimate
    new = autogeometry.refined_geometry(geo, 12.0, "refined by +12 px")
    r = math.radians(geo.roll_deg)
    step = np.array([math.cos(r), -math.sin(r)]) * 12.0
    assert np.allclose(np.subtract(new.vanishing_point_px, geo.vanishing_point_px), step)
    assert np.allclose(np.subtract(new.src_px, geo.src_px), step)  # the view follows the point
    assert new.horizon_row_px == geo.horizon_row_px and new.dst_px == geo.dst_px
    assert (new.xm_per_px, new.ym_per_px, new.look_ahead_m, new.hood_row_px) == \
        (geo.xm_per_px, geo.ym_per_px, geo.look_ahead_m, geo.hood_row_px)
    assert new.yaw_deg < geo.yaw_deg and new.assumptions[-1] == "refined by +12 px"
    assert geo.horizon_shift_px(new.vanishing_point_px) == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(GeometryError, match="outside the frame"):
        autogeometry.refined_geometry(geo, -geo.size_px[0] / 2, "")


class _Points:
    """A finder stand-in: the vanishing points of the checks, in order (straight road)."""

    def __init__(self, points):
        self.points = iter(points)

    def vanishing_point(self, frame):
        return autogeometry.VanishingPoint(next(self.points), 20, 20, (), True, "")


def test_the_watch_refines_the_point_once_the_evidence_says_so_and_not_back_and_forth(estimate):
    """The rule on known points: nothing before REFINE_MIN_CHECKS (or the estimate's frames
    used), a move to the median when it lies off by more than its standard error plus the
    tolerance, then twice the points for the next move; off-horizon points do not count."""
    cal, geo = estimate
    watch = autogeometry.GeometryWatch(geo, cal, autogeometry.GeometryOptions(check_every_s=0.04), fps=25.0)
    need = max(autogeometry.REFINE_MIN_CHECKS, len(geo.frames_used))
    x0, y0 = geo.vanishing_point_px
    rng = np.random.default_rng(3)
    true_x = x0 + 15.0  # the straight-ahead column, 15 px right of the estimate's
    xs = true_x + rng.normal(0.0, 5.0, 4 * need)
    watch._finder = _Points([(x, y0) for x in xs])
    frame = np.zeros((1, 1, 3), np.uint8)
    got = [watch.check(frame, i, i / 25) for i in range(4 * need)]
    moved = [i for i, g in enumerate(got) if g is not None]
    assert moved and moved[0] == need - 1, watch.notes
    assert all(b - a >= a + 1 for a, b in zip(moved, moved[1:]))  # twice the points each time
    assert watch.geometry.vanishing_point_px[0] == pytest.approx(true_x, abs=3.0)
    assert "refined: vanishing point" in watch.notes[0] and f"the {need} straight checks" in watch.notes[0]
    # a point on the horizon as estimated: no move; points off the horizon are not kept
    options = autogeometry.GeometryOptions(check_every_s=0.04, drift_checks=10**6)
    watch = autogeometry.GeometryWatch(geo, cal, options, fps=25.0)
    watch._finder = _Points([(x0 + 1.0, y0)] * need + [(x0 + 40.0, y0 + 30.0)] * need)
    assert [watch.check(frame, i, 0.0) for i in range(2 * need)] == [None] * (2 * need)
    assert len(watch.points) == need and watch.notes == []
    assert len(pickle.dumps(watch)) < 20_000


def test_a_fresh_watch_is_carried_on_by_the_evidence_of_the_one_before(estimate):
    """A Dask segment's fresh watch vs one watch through the whole clip: where the points before
    the segment change nothing in it, the previous watch carried through the segment's record
    is the one watch's state; where they would have refined the geometry in it, None (the
    segment runs again)."""
    cal, geo = estimate
    need = max(autogeometry.REFINE_MIN_CHECKS, len(geo.frames_used))
    x0, y0 = geo.vanishing_point_px
    options = autogeometry.GeometryOptions(check_every_s=0.04)
    frame = np.zeros((1, 1, 3), np.uint8)

    def run(points, indices, before=None):
        watch = autogeometry.GeometryWatch(geo, cal, options, fps=25.0) if before is None else before
        watch._finder = _Points(points)
        for i in indices:
            watch.check(frame, i, i / 25)
        return watch

    for off_px, carried in ((1.0, True), (20.0, False)):
        # the first `need - 2` points on the estimate's column, then `off_px` right of it
        points = [(x0, y0)] * (need - 2) + [(x0 + off_px, y0 + 1.0)] * need
        one = run(points, range(len(points)))
        start = need - 2
        first = run(points[:start], range(start))
        fresh = run(points[start - 3:start], range(start - 3, start))  # warmed up over 3 checks
        assert fresh.core_key() == first.core_key() and fresh.state_key() != first.state_key()
        fresh = run(points[start:], range(start, len(points)), fresh)
        got = first.carried_through(fresh, start)
        if carried:
            assert got is not None and got.state_key() == one.state_key() and one.notes == []
        else:
            assert got is None and "refined" in one.notes[0]


@pytest.mark.slow
def test_the_vanishing_point_is_refined_to_the_straight_ahead_column(bend_then_straight, refine_camera,
                                                                     refine_options, tmp_path):
    """Known answer: estimated from the first 4 s alone (the bend, the car heading right of the
    road), the vanishing point lies 12.5 px left of the camera's straight-ahead column; the
    straight checks of the next seconds move it to within 0.9 px of it at 7.7 s (frame 192), and
    the offset read from there on is off the truth by 0.040 m on average (0.081 m at most)
    instead of 0.074 m (0.137 m) (figures at writing)."""
    clip = bend_then_straight
    truth = load_video_truth(clip)
    true_x = refine_camera.vanishing_point_px()[0]
    options = refine_options
    geo = batch.estimate_road_geometry(clip, None, options)
    assert geo.vanishing_point_px[0] < true_x - 8.0  # the bias to correct
    calibration = autogeometry.geometry_calibration(None, geo)
    before = tmp_path / "before.csv"
    batch.process_video(clip, tmp_path / "before.mp4", batch.with_geometry(PipelineConfig(), geo), calibration,
                        log_path=before, progress=False)
    after = tmp_path / "after.csv"
    run = batch.process_video(clip, tmp_path / "after.mp4", PipelineConfig(), None, log_path=after,
                              progress=False, auto_geometry=options)
    refined = [re.search(r"^frame (\d+) .*-> \(([\d.]+), [\d.]+\) px", n) for n in run.notes if "refined" in n]
    assert refined and all(refined), run.notes
    first, last_x = int(refined[0][1]), float(refined[-1][2])
    assert abs(last_x - true_x) < 2.0, run.notes
    offsets = {}
    for name, path in (("before", before), ("after", after)):
        rows = list(csv.DictReader(path.open()))[first:]
        offsets[name] = np.mean([abs(float(r["offset_m"]) - truth.frames[int(r["frame"])].offset_m) for r in rows])
    assert offsets["after"] < 0.75 * offsets["before"], offsets


@pytest.mark.parametrize("name, frames", [("solidWhiteRight", 221), ("solidYellowLeft", 681)])
def test_a_p1_clip_with_auto_geometry_and_no_setup(udacity_p1, tmp_path, capsys, name, frames):
    """Real footage of another camera (960x540), no calibration, no preset: the geometry from the
    road itself gives a plausible lane in every frame."""
    clip = udacity_p1 / "test_videos" / f"{name}.mp4"
    log = tmp_path / "log.csv"
    code = main(["video", str(clip), "-o", str(tmp_path / "out.mp4"), "--auto-geometry",
                 "--log", str(log), "--no-progress"])
    printed = capsys.readouterr().out
    assert code == 0 and "dash period" in printed
    rows = list(csv.DictReader(log.open()))
    assert len(rows) == frames
    widths = [float(r["lane_width_m"]) for r in rows if r["lane_width_m"]]
    offsets = [abs(float(r["offset_m"])) for r in rows if r["offset_m"]]
    assert len(widths) == len(offsets) == frames
    assert all(3.0 <= w <= 4.5 for w in widths) and max(offsets) < 0.6
