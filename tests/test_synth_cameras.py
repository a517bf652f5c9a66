"""Tests of lanelib.synth with other cameras than the bundled one (issue 15, point 3): sizes,
focal lengths, mountings and roll; the renderer and the ground truth agree on each."""
from __future__ import annotations

import math

import numpy as np
import pytest

from lanelib import autogeometry, batch, io
from lanelib.camera import Calibration, undistort_points
from lanelib.cli import main
from lanelib.autogeometry import RoadLineFinder, detect_hood, estimate_geometry, estimate_lens
from lanelib.perspective import Perspective
from lanelib.synth import (Camera, CarPose, CurvatureProfile, GroundGrid, Layout, Look, Renderer, Scene,
                           camera_truth, lane_truth, load_video_truth, video_sets, write_video)
from lanelib.synth.sets import METER_ROWS, meter_rows
from lanelib.synth.truth import NOT_VISIBLE, H_SAMPLES_PX, camera_from_json, camera_json, h_samples_px

ROLLED = Camera.pinhole((960, 540), hfov_deg=80.0, height_m=1.4, pitch_deg=1.0, yaw_deg=-2.0, roll_deg=1.5)


@pytest.fixture(scope="module")
def rolled_grid() -> GroundGrid:
    return GroundGrid.build(ROLLED)


def test_truth_rows_and_meter_rows_follow_the_image_height():
    assert h_samples_px((1280, 720)) == H_SAMPLES_PX
    assert h_samples_px((960, 540)) == tuple(range(320, 540, 10))
    assert h_samples_px((1920, 1080)) == tuple(range(630, 1080, 10))
    assert meter_rows(720) == METER_ROWS
    assert meter_rows(1080) == slice(660, 1020)


def test_the_hood_is_as_high_in_proportion(rolled_grid):
    bundled = GroundGrid.build(Camera())
    assert bundled.hood_top.min() == pytest.approx(694.0)
    assert rolled_grid.hood_top.min() == pytest.approx(540 - 26 * 540 / 720, abs=1e-3)


def test_camera_truth_round_trips_the_roll():
    truth = camera_truth(ROLLED)
    obj = camera_json(truth)
    assert obj["roll_deg"] == 1.5
    back = camera_from_json(obj, None)
    assert back.roll_deg == 1.5 and back.camera() == ROLLED
    assert back.horizon_px() == pytest.approx(ROLLED.horizon_px())
    # the bundled camera's truth does not hold the key: its files stay as they were
    assert "roll_deg" not in camera_json(camera_truth(Camera()))


def test_rendered_lines_lie_on_their_truth_through_a_rolled_camera(rolled_grid):
    scene = Scene(CurvatureProfile(((0.0, -1 / 400),)), Layout(3.6), Look(), -20.0, 260.0, seed=31)
    renderer = Renderer(scene, rolled_grid)
    pose = CarPose(12.0, 0.2, 0.01)
    image = renderer.render(pose).astype(np.float64)
    lane = lane_truth(renderer, pose)
    assert lane.h_samples_px == h_samples_px((960, 540))
    yellow = image[..., 0] + image[..., 1] - 2 * image[..., 2]
    errors = []
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or row < 340:
            continue
        lo = int(round(x)) - 10
        if lo < 40 or lo + 61 > 960:
            continue
        profile = np.clip(yellow[row, lo:lo + 21] - np.median(yellow[row, lo - 40:lo + 61]), 0, None)
        errors.append((profile * np.arange(lo, lo + 21)).sum() / profile.sum() - x)
    assert len(errors) >= 10 and np.abs(errors).max() < 1.0


def test_a_video_through_another_camera_carries_its_truth(rolled_grid, tmp_path):
    path = write_video(tmp_path / "clip.mp4", video_sets()["project"], seconds=0.2, grid=rolled_grid)
    truth = load_video_truth(path)
    assert len(truth.frames) == 5 and truth.camera.size_px == (960, 540)
    assert truth.camera.roll_deg == 1.5 and truth.camera.camera() == ROLLED
    assert truth.frames[0].h_samples_px == h_samples_px((960, 540))
    left = truth.frames[0].points("left")
    assert len(left) >= 5 and np.all((left[:, 0] >= 0) & (left[:, 0] < 960))
    # the truth's perspective points are a lane centred on the car, 28.25 m ahead at the top
    p = truth.camera.perspective
    assert p.size_px == (960, 540) and p.dst_px[2] == (720.0, 540.0)
    assert p.visible_length_m == pytest.approx(28.25 - ROLLED.ground_z_on_line(540.0, 0.0), abs=0.2)
    assert math.isfinite(p.xm_per_px) and p.xm_per_px > 0


# --------------------------------------------------------------------------- a barrel lens not given (issue 15)

# A wide dashcam with strong barrel distortion, estimated WITHOUT its calibration. Near the bottom
# corners the lens pulls the road in by 10-15 %; the lane lines bow by under a pixel (they run
# near the centre, where a lens bends a line little), enough for the estimate to measure the
# lens from them (``estimate_lens``) and undistort the frames with it. The truth here is the raw
# image's: the horizon's row at the centre column and road points projected through the lens,
# then undistorted with the lens the estimate measured (as a pipeline running with it does).
BARREL = Camera.pinhole((960, 540), hfov_deg=90.0, height_m=1.25, pitch_deg=-1.0,
                        dist_coeffs=(-0.25, 0.0, 0.0, 0.0, 0.0))
BARREL_POSES = tuple(CarPose(10.0 + 2.9 * i, 0.25 * math.sin(1.3 * i), 0.004 * math.sin(0.9 * i + 1))
                     for i in range(6))


PINHOLE_90 = Camera.pinhole((960, 540), hfov_deg=90.0, height_m=1.25, pitch_deg=-1.0)


@pytest.fixture(scope="module")
def barrel_frames():
    scene = Scene(CurvatureProfile(), Layout(3.7), Look(), -20.0, 260.0, seed=21)
    renderer = Renderer(scene, GroundGrid.build(BARREL))
    return [renderer.render(p, noise_key=i) for i, p in enumerate(BARREL_POSES)]


@pytest.fixture(scope="module")
def barrel_estimate(barrel_frames):
    return estimate_geometry(barrel_frames)


def _raw_horizon_row(camera: Camera) -> float:
    """Return the row where the horizon crosses the centre column of the RAW (distorted) image."""
    az = np.radians(np.linspace(-40.0, 40.0, 4001))
    far = np.column_stack([1e6 * np.sin(az), np.full_like(az, -camera.height_m), 1e6 * np.cos(az)])
    uv = camera.project(far, distort=True)
    ok = np.isfinite(uv[:, 0])
    return float(np.interp(camera.size_px[0] / 2, uv[ok, 0], uv[ok, 1]))


def _raw_errors(camera: Camera, geom) -> tuple[float, list[float], list[float]]:
    """Return (horizon row error px, lane width errors, lengths-along errors) of an estimate made
    from the raw frames, against the truth projected through the lens (and, when the estimate
    measured a lens, undistorted with the lens it measured, as the pipeline then does)."""
    persp = Perspective(geom.perspective_config())
    if geom.lens is not None:
        raw = persp
        persp = lambda uv: raw(undistort_points(geom.lens, uv, exact=True))  # noqa: E731
    h = geom.size_px[1]
    widths = []
    for offset in (0.3, -0.4):
        z = np.linspace(3.0, 60.0, 400)
        lines = []
        for t in (-1.85, 1.85):
            uv = camera.project(np.column_stack([np.full_like(z, t - offset), np.zeros_like(z), z]))
            lines.append(persp(uv[np.isfinite(uv).all(1)]))
        for row in (0.05 * h, 0.5 * h, 0.95 * h):
            xl = np.interp(row, lines[0][::-1, 1], lines[0][::-1, 0])
            xr = np.interp(row, lines[1][::-1, 1], lines[1][::-1, 0])
            widths.append((xr - xl) * geom.xm_per_px / 3.7 - 1)
    z = np.array([6.0, 10.0, 16.0, 22.0])
    y = persp(camera.project(np.column_stack([np.zeros(4), np.zeros(4), z])))[:, 1]
    along = [abs(y[i] - y[j]) * geom.ym_per_px / (z[j] - z[i]) - 1 for i, j in ((0, 1), (0, 3), (2, 3))]
    horizon = np.array([[camera.size_px[0] / 2, _raw_horizon_row(camera)]])
    if geom.lens is not None:
        horizon = undistort_points(geom.lens, horizon, exact=True)
    return geom.horizon_row_px - float(horizon[0, 1]), widths, along


def test_a_barrel_lens_not_given_is_never_a_confident_wrong_scale(barrel_estimate):
    """Issue 15 point 6: without its calibration, a strongly distorting lens gives either a low
    confidence (refused unless told) or a geometry within the issue's tolerances."""
    horizon, widths, along = _raw_errors(BARREL, barrel_estimate)
    good = abs(horizon) <= 2.0 and max(map(abs, widths)) <= 0.03 and max(map(abs, along)) <= 0.05
    assert barrel_estimate.low_confidence or good, (barrel_estimate.confidence, horizon, widths, along)


def test_a_barrel_lens_not_given_is_estimated_from_its_bent_lines(barrel_estimate):
    """Issue 15 point 1: the lane lines' bend gives the lens (k1 within 8 %, at the true focal
    length), the frames are undistorted with it and the horizon and the lane width are then
    within the issue's tolerances. Undistortion pushes the near dashes out of the frame, so the
    dash period is measured on the undistorted frames on a larger canvas; both are said."""
    lens = barrel_estimate.lens
    assert lens is not None and lens.estimated
    k1_at_true_focal = lens.dist_coeffs[0] / lens.camera_matrix[0, 0] ** 2 * 480.0 ** 2
    assert k1_at_true_focal == pytest.approx(-0.25, rel=0.08)
    assert barrel_estimate.assumptions[0].startswith("lens not given: its radial distortion was estimated")
    assert barrel_estimate.scale_source.startswith("dash period of the undistorted frames on a canvas")
    assert any("pushes the near dashes out of the frame" in a for a in barrel_estimate.assumptions)
    # the focal length the dashes give, within 5 % of the camera's
    assert barrel_estimate.focal_px == pytest.approx(480.0, rel=0.05)


def _true_lines(camera: Camera, offsets=(0.25, -0.2, 0.0)) -> list[list[np.ndarray]]:
    """Return per car offset (a frame) the raw-image rows' centres of four road lines."""
    out = []
    for off in offsets:
        frame = []
        for t in (-1.85, 1.85, -5.55, 5.55):
            z = np.linspace(2.5, 40.0, 300)
            uv = camera.project(np.column_stack([np.full_like(z, t - off), np.zeros_like(z), z]))
            uv = uv[np.isfinite(uv).all(1) & (uv[:, 1] < 0.96 * camera.size_px[1])
                    & (uv[:, 0] > 0) & (uv[:, 0] < camera.size_px[0])]
            rows = np.arange(np.ceil(uv[:, 1].min()), uv[:, 1].max())
            frame.append(np.column_stack([np.interp(rows, uv[::-1, 1], uv[::-1, 0]), rows]))
        out.append(frame)
    return out


def test_the_lens_estimate_recovers_k1_from_exact_lines():
    """Known answer: lines projected through the barrel lens (k1 = -0.25 at f = 480 px) give
    lam = k1 / f^2 within 2 %; through a pinhole, lam 0 (not applied)."""
    found = estimate_lens(_true_lines(BARREL), BARREL.size_px)
    assert found.applied
    assert found.lam * 480.0 ** 2 == pytest.approx(-0.25, rel=0.02)
    assert found.residual_bend_px < 0.2 * found.bend_px
    flat = estimate_lens(_true_lines(PINHOLE_90), PINHOLE_90.size_px)
    assert not flat.applied and abs(flat.kappa) < 0.01


def test_the_lens_estimate_from_the_barrel_frames(barrel_frames):
    """Known answer on the rendered frames' lane-line paint: lam within 6 % of the lens's."""
    finder = RoadLineFinder(BARREL.size_px, None, detect_hood(barrel_frames))
    lines = [list(a.line_points) for a in map(finder.analyse, barrel_frames) if a.vp.ok]
    found = estimate_lens(lines, BARREL.size_px)
    assert found.applied, found.reason
    assert found.lam * 480.0 ** 2 == pytest.approx(-0.25, rel=0.06)


def test_no_lens_is_estimated_on_a_distortion_free_camera():
    """The same wide camera without distortion: the lines are straight, no lens is applied, the
    estimate is as before and says the lens was taken as distortion-free."""
    scene = Scene(CurvatureProfile(), Layout(3.7), Look(), -20.0, 260.0, seed=21)
    renderer = Renderer(scene, GroundGrid.build(PINHOLE_90))
    geo = estimate_geometry([renderer.render(p, noise_key=i) for i, p in enumerate(BARREL_POSES)])
    assert geo.lens is None
    assert any(a.startswith("lens not given and taken as distortion-free") for a in geo.assumptions)
    assert "lens" not in geo.to_dict()


def test_a_barrel_lens_not_given_is_measured_from_the_road(barrel_estimate):
    """Issue 15 point 1 (the shared project video without --calibration is this class): the
    geometry of a barrel-distorted camera, no calibration given, is measured (not assumed) within
    the issue's tolerances: horizon 2 px, lane width 3 %, metres per pixel along the road 5 %."""
    horizon, widths, along = _raw_errors(BARREL, barrel_estimate)
    assert barrel_estimate.scale_source.startswith("dash period")
    assert barrel_estimate.lens is not None
    assert not barrel_estimate.low_confidence
    assert abs(horizon) <= 2.0
    assert max(map(abs, widths)) <= 0.03
    assert max(map(abs, along)) <= 0.05


def test_the_geometry_command_writes_the_estimated_lens_for_reuse(barrel_frames, tmp_path, capsys):
    """`geometry FOLDER -o g.json` of the barrel camera writes the lens it measured beside the
    perspective (g.lens.json, readable by --calibration), and a run with --auto-geometry
    undistorts with it (``autogeometry.geometry_calibration``)."""
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, frame in enumerate(barrel_frames):
        io.write_image(folder / f"{i:02d}.png", frame)
    out = tmp_path / "g.json"
    assert main(["geometry", str(folder), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "lens not given: its radial distortion was estimated" in printed
    lens = Calibration.load(tmp_path / "g.lens.json")
    assert lens.estimated and lens.dist_coeffs[0] < 0
    geo = batch.estimate_road_geometry(folder, None, autogeometry.GeometryOptions())
    assert autogeometry.geometry_calibration(None, geo) is geo.lens
    given = Calibration(BARREL.K, np.asarray(BARREL.dist, float), BARREL.size_px)
    assert autogeometry.geometry_calibration(given, geo) is given
