"""Tests of lanelib.synth: the camera and its mounting, calibration from the synthetic boards,
ground-truth geometry, rendering against truth, determinism against the bundled files, loaders."""
from __future__ import annotations

import json
from pathlib import Path
import math

import cv2
import numpy as np
import pytest

from lanelib import InputError
from lanelib.camera import Calibration
from lanelib.cli import main
from lanelib.io import VideoReader, encode_image, read_image
from lanelib.perspective import DEFAULT_SRC_1280x720, Perspective, PerspectiveConfig
from lanelib.synth import (Camera, CarPose, GroundGrid, Renderer, image_scenes, load_board_truth,
                           load_image_truth, load_video_truth, perspective_truth, video_sets, write_video)
from lanelib.synth.chessboard import board_poses, camera_normals, render_board
from lanelib.synth.sets import BOARD_JPEG_QUALITY, BOARD_SEED, IMAGE_JPEG_QUALITY
from lanelib.synth.truth import NOT_VISIBLE, write_image_truth, camera_truth, lane_truth

REPO = Path(__file__).resolve().parents[1]

CAL_DIR, IMAGE_DIR, VIDEO_DIR = REPO / "camera_cal", REPO / "test_images", REPO / "videos"


@pytest.fixture(scope="module")
def grid() -> GroundGrid:
    return GroundGrid.build()


@pytest.fixture(scope="module")
def scenes() -> dict:
    return {item.name: item for item in image_scenes()}


def undistorted_truth_points(truth, side: str) -> np.ndarray:
    """Return a truth line's visible points in the undistorted image, with the true camera."""
    cam = truth.camera
    k, d = np.asarray(cam.camera_matrix), np.asarray(cam.dist_coeffs)
    pts = truth.lane.points(side).reshape(-1, 1, 2)
    return cv2.undistortPoints(pts, k, d, P=k).reshape(-1, 2)


# --------------------------------------------------------------------------- camera

def test_mounting_fits_the_default_perspective_points():
    cam = Camera()
    vp = cam.project(np.array([[0.0, 0.0, 1e7]]), distort=False)[0]
    assert vp == pytest.approx((640.0, 419.03), abs=0.01)   # the default trapezoid's apex
    bottom = [cam.project(np.array([[x, 0.0, cam.ground_z_on_line(720.0, x)]]), distort=False)[0]
              for x in (-1.85, 1.85)]
    assert bottom[0] == pytest.approx((193.0, 720.0), abs=0.25)
    assert bottom[1] == pytest.approx((1087.0, 720.0), abs=0.25)
    p = perspective_truth(cam)
    assert p.visible_length_m == pytest.approx(23.501, abs=1e-3)
    assert p.ym_per_px == pytest.approx(p.visible_length_m / 720)
    assert np.abs(np.subtract(p.src_px, DEFAULT_SRC_1280x720)).max() < 0.25


def test_projection_inverts_the_ray_casting():
    cam = Camera()
    uv = np.array([[3.0, 700.0], [640.0, 600.0], [1270.0, 715.0], [900.0, 430.0]])
    ground = cam.ground_points(uv)
    back = cam.project(np.column_stack([ground[:, 0], np.zeros(4), ground[:, 1]]))
    assert np.abs(back - uv).max() < 1e-6


# --------------------------------------------------------------------------- chessboards

def test_calibration_from_the_bundled_boards_recovers_the_camera():
    truth = load_board_truth(CAL_DIR)
    obj = np.zeros((54, 3), np.float32)
    obj[:, :2] = np.mgrid[0:9, 0:6].T.reshape(-1, 2)
    found, seen = [], []
    for name in sorted(truth.corners_px):
        grey = cv2.cvtColor(read_image(CAL_DIR / name), cv2.COLOR_RGB2GRAY)
        ok, corners = cv2.findChessboardCorners(grey, (9, 6))
        if ok:
            crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
            found.append(cv2.cornerSubPix(grey, corners, (11, 11), (-1, -1), crit))
        seen.append(ok)
    assert len(truth.corners_px) == 20 and sum(seen) >= 15
    assert 2 <= sum(not v for v in truth.fully_visible.values()) <= 3
    _, k, d, _, _ = cv2.calibrateCamera([obj] * len(found), found, truth.size_px, None, None)
    for (i, j) in ((0, 0), (1, 1), (0, 2), (1, 2)):
        assert k[i, j] == pytest.approx(truth.camera_matrix[i, j], rel=0.01)
    pts = np.concatenate(list(truth.corners_px.values())).reshape(-1, 1, 2)
    inside = (pts[:, 0, 0] >= 0) & (pts[:, 0, 0] < 1280) & (pts[:, 0, 1] >= 0) & (pts[:, 0, 1] < 720)
    pts = pts[inside]
    ours = cv2.undistortPoints(pts, k, d, P=k).reshape(-1, 2)
    k_true = truth.camera_matrix
    true = cv2.undistortPoints(pts, k_true, truth.dist_coeffs, P=k_true).reshape(-1, 2)
    assert np.linalg.norm(ours - true, axis=1).max() < 0.5


def test_first_board_renders_to_the_bundled_bytes():
    cam = Camera()
    rng = np.random.default_rng(BOARD_SEED)
    board = board_poses(cam, rng)[0]
    image = render_board(cam, camera_normals(cam), board, rng)
    assert encode_image(image, ".jpg", BOARD_JPEG_QUALITY) == (CAL_DIR / "calibration01.jpg").read_bytes()


# --------------------------------------------------------------------------- ground truth

@pytest.mark.parametrize("name", ["straight_1", "straight_2"])
def test_straight_truth_lines_are_straight_in_the_bird_eye_view(name):
    truth = load_image_truth(IMAGE_DIR / f"{name}.jpg")
    lane, persp = truth.lane, truth.camera.perspective
    xm, ym = persp.xm_per_px, persp.ym_per_px
    z_bottom = Camera().ground_z_on_line(720.0, 0.0)      # metres from the car to the bottom row
    fits = {}
    for config in (persp.config(), PerspectiveConfig()):
        for side in ("left", "right"):
            bird = Perspective(config).warp_points(undistorted_truth_points(truth, side))
            assert len(bird) >= 20
            fit = np.polyfit(bird[:, 1], bird[:, 0], 1)           # x = a y + b
            assert np.abs(np.polyval(fit, bird[:, 1]) - bird[:, 0]).max() < 1.0
            fits[side] = fit
        # slope: the car's heading (positive right: the road runs to the left ahead)
        assert math.atan(fits["left"][0] * xm / ym) == pytest.approx(lane.heading_rad, abs=5e-4)
    # at the car (z = 0, below the bottom row) the lines lie a lane width apart, around the offset
    y_car = 720.0 + z_bottom / ym
    left, right = (np.polyval(fits[s], y_car) for s in ("left", "right"))
    assert (right - left) * xm * math.cos(lane.heading_rad) == pytest.approx(lane.lane_width_m, abs=0.01)
    assert (640.0 - (left + right) / 2) * xm == pytest.approx(lane.offset_m, abs=0.01)


def test_centred_straight_lane_maps_to_the_dst_columns():
    truth = load_image_truth(IMAGE_DIR / "straight_1.jpg")
    assert truth.lane.offset_m == 0 and truth.lane.lane_width_m == 3.7
    persp = Perspective(truth.camera.perspective.config())
    for side, x_dst in (("left", 320.0), ("right", 960.0)):
        x = persp.warp_points(undistorted_truth_points(truth, side))[:, 0]
        assert np.abs(x - x_dst).max() < 2.0


def test_truth_matches_the_scene_parameters(scenes):
    for name, item in scenes.items():
        lane = load_image_truth(IMAGE_DIR / item.folder / f"{name}.jpg").lane
        k = item.scene.profile.knots[0][1]
        assert lane.lane_width_m == item.scene.layout.lane_width_m
        assert lane.offset_m == pytest.approx(item.pose.offset_m)
        assert lane.curvature_per_m == pytest.approx(k, abs=1e-9)
        assert lane.radius_m == (math.inf if k == 0 else pytest.approx(1 / abs(k), rel=1e-6))
    curve = load_image_truth(IMAGE_DIR / "curve_right_1000m.jpg").lane
    assert curve.curvature_per_m > 0   # bends to the right: positive


def test_rendered_yellow_line_lies_on_its_truth(grid, scenes):
    item = scenes["curve_left_250m"]
    renderer = Renderer(item.scene, grid)
    image = renderer.render(item.pose).astype(np.float64)
    lane = lane_truth(renderer, item.pose)
    yellow = image[..., 0] + image[..., 1] - 2 * image[..., 2]
    errors = []
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or not 480 <= row <= 690:
            continue
        lo = int(round(x)) - 12
        profile = np.clip(yellow[row, lo:lo + 25] - np.median(yellow[row, lo - 40:lo + 65]), 0, None)
        errors.append((profile * np.arange(lo, lo + 25)).sum() / profile.sum() - x)
    assert len(errors) >= 15 and np.abs(errors).max() < 1.0


# --------------------------------------------------------------------------- determinism

def test_straight_1_renders_to_the_bundled_bytes(grid, scenes, tmp_path):
    item = scenes["straight_1"]
    first = Renderer(item.scene, grid).render(item.pose)
    second = Renderer(item.scene, grid).render(item.pose)
    assert np.array_equal(first, second)
    assert encode_image(first, ".jpg", IMAGE_JPEG_QUALITY) == (IMAGE_DIR / "straight_1.jpg").read_bytes()
    renderer = Renderer(item.scene, grid)
    path = write_image_truth(tmp_path / "straight_1.jpg", item.scene.seed, lane_truth(renderer, item.pose),
                             camera_truth(grid.camera))
    assert path.read_bytes() == (IMAGE_DIR / "straight_1.json").read_bytes()


def test_video_frames_and_truth_match_the_bundled_clip(grid, tmp_path):
    clips = [write_video(tmp_path / f"p{k}.mp4", video_sets()["project"], seconds=0.2, grid=grid)
             for k in range(2)]
    assert clips[0].read_bytes() == clips[1].read_bytes()
    fresh = load_video_truth(clips[0]).frames
    bundled = load_video_truth(VIDEO_DIR / "project.mp4").frames
    assert fresh == bundled[:len(fresh)]
    with VideoReader(clips[0]) as a, VideoReader(VIDEO_DIR / "project.mp4") as b:
        for fa, fb, _ in zip(a, b, range(5)):
            assert np.abs(fa.astype(int) - fb.astype(int)).mean() < 2.0


def test_bundled_videos_have_truth_for_every_frame():
    for name in ("project", "challenge", "harder"):
        truth = load_video_truth(VIDEO_DIR / f"{name}.mp4")
        assert truth.fps == 25 and 200 <= len(truth.frames) <= 250
        with VideoReader(VIDEO_DIR / f"{name}.mp4") as r:
            assert r.info.n_frames == len(truth.frames)
    harder = load_video_truth(VIDEO_DIR / "harder.mp4").frames
    assert min(f.radius_m for f in harder) < 150
    rows = np.asarray(harder[0].h_samples_px)
    mid = (rows >= 440) & (rows <= 680)    # lines leaving the view, not hidden by the hood
    assert any(NOT_VISIBLE in np.asarray(f.left_x_px + f.right_x_px)[np.tile(mid, 2)] for f in harder)


def test_camera_truth_gives_its_calibration():
    from_camera = camera_truth(Camera())
    from_file = load_image_truth(IMAGE_DIR / "straight_1.jpg").camera
    for cam in (from_camera, from_file):
        cal = cam.calibration()
        # what evaluate.truth_calibration computed before the method existed
        K = np.asarray(cam.camera_matrix, np.float64)
        d = np.asarray(cam.dist_coeffs, np.float64)
        size = tuple(int(v) for v in cam.size_px)
        assert np.array_equal(cal.camera_matrix, K) and cal.camera_matrix.dtype == np.float64
        assert np.array_equal(cal.dist_coeffs, d) and cal.dist_coeffs.dtype == np.float64
        assert cal.image_size == size == (1280, 720) and cal.rms_px == 0.0
        assert cal.to_dict() == Calibration(K, d, size, 0.0).to_dict()
    np.testing.assert_allclose(from_file.calibration().camera_matrix, Camera().camera_matrix, atol=1e-6)


# --------------------------------------------------------------------------- loaders and CLI

def test_missing_truth_names_the_file(tmp_path):
    image = tmp_path / "road.jpg"
    image.write_bytes((IMAGE_DIR / "straight_1.jpg").read_bytes())
    with pytest.raises(InputError, match="road.json"):
        load_image_truth(image)
    with pytest.raises(InputError, match="clip.csv"):
        load_video_truth(tmp_path / "clip.mp4")
    with pytest.raises(InputError, match="camera_truth.json"):
        load_board_truth(tmp_path)


def test_malformed_truth_is_an_input_error(tmp_path):
    (tmp_path / "road.json").write_text("{not json")
    with pytest.raises(InputError, match="road.json"):
        load_image_truth(tmp_path / "road.jpg")
    (tmp_path / "road.json").write_text(json.dumps({"seed": 1}))
    with pytest.raises(InputError, match="not an image ground-truth file"):
        load_image_truth(tmp_path / "road.jpg")


def test_synth_cli_needs_all_or_a_kind(capsys):
    with pytest.raises(SystemExit) as e:
        main(["synth"])
    assert e.value.code == 2
    assert main(["synth", "video", "-o", "x.mp4", "--seconds", "0"]) == 2
    assert "--seconds" in capsys.readouterr().err


def test_pose_outside_the_scene_is_refused(grid, scenes):
    renderer = Renderer(scenes["straight_1"].scene, grid)
    with pytest.raises(ValueError, match="needs road"):
        renderer.render(CarPose(1e4))
