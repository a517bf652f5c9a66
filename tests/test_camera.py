"""Calibration, the Calibration record, and undistortion maps."""
from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from lanelib import io
from lanelib.camera import (Calibration, Undistorter, board_points, calibrate, distort_points,
                            parse_pattern, undistort_points)
from lanelib.errors import CalibrationError, InputError
from lanelib.perspective import Perspective

K = np.array([[1000.0, 0, 640.0], [0, 1000.0, 360.0], [0, 0, 1]])
DIST = np.array([-0.25, 0.05, 0.001, -0.0005, 0.0])


def render_board(rvec, tvec, pattern=(9, 6), size=(1280, 720), square=1.0):
    """Return an RGB image of a chessboard seen by the camera K, DIST at pose (rvec, tvec)."""
    cols, rows = pattern
    img = np.full((size[1], size[0]), 200, np.uint8)
    # squares from -1 to cols/rows, so the inner corners are the pattern's
    for i in range(-1, cols):
        for j in range(-1, rows):
            if (i + j) % 2:
                continue
            sq = np.array([[i, j, 0], [i + 1, j, 0], [i + 1, j + 1, 0], [i, j + 1, 0]], np.float64) * square
            # subdivide the edges so the distortion bends them
            t = np.linspace(0, 1, 6)[:-1, None]
            poly = np.vstack([sq[k] + t * (sq[(k + 1) % 4] - sq[k]) for k in range(4)])
            pts, _ = cv2.projectPoints(poly, rvec, tvec, K, DIST)
            cv2.fillPoly(img, [np.round(pts.reshape(-1, 2) * 16).astype(np.int32)], 20,
                         lineType=cv2.LINE_AA, shift=4)
    img = cv2.GaussianBlur(img, (3, 3), 0.8)
    return cv2.cvtColor(img, cv2.COLOR_GRAY2RGB)


POSES = [((0.1, 0.2, 0.0), (-4, -2.5, 14)), ((-0.3, 0.1, 0.1), (-6, -3, 13)),
         ((0.3, -0.3, -0.1), (-1, -1, 12)), ((0.0, 0.4, 0.05), (-8, -4.5, 15)),
         ((-0.2, -0.4, 0.0), (0, -3, 13)), ((0.4, 0.0, 0.2), (-5, -3, 14)),
         ((0.0, 0.0, 0.3), (-3, -3, 13))]


@pytest.fixture(scope="module")
def board_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("boards")
    for k, (r, t) in enumerate(POSES):
        io.write_image(d / f"board{k}.png", render_board(np.array(r), np.array(t, float)))
    return d


def test_calibration_recovers_known_camera(board_dir):
    cal = calibrate(board_dir)
    assert len(cal.used) == len(POSES) and cal.skipped == ()
    assert cal.rms_px < 0.5
    for (r, c) in ((0, 0), (1, 1), (0, 2), (1, 2)):
        assert cal.camera_matrix[r, c] == pytest.approx(K[r, c], rel=0.01)
    # undistorting true pixel positions lands where the true camera puts them
    pts = np.array([[200.0, 150.0], [1050, 600], [640, 360], [300, 550]])  # where boards were seen
    true_und = cv2.undistortPoints(pts.reshape(-1, 1, 2), K, DIST, P=K).reshape(-1, 2)
    assert np.abs(undistort_points(cal, pts) - true_und).max() < 1.0


def test_calibration_json_round_trip(board_dir, tmp_path):
    cal = calibrate(board_dir)
    path = cal.save(tmp_path / "cal.json")
    back = Calibration.load(path)
    np.testing.assert_allclose(back.camera_matrix, cal.camera_matrix, atol=1e-6)
    np.testing.assert_allclose(back.dist_coeffs, cal.dist_coeffs, atol=1e-8)
    assert back.image_size == cal.image_size and back.used == cal.used
    assert back.rms_px == pytest.approx(cal.rms_px, abs=1e-4)


def test_board_not_found_and_corrupt_file_are_skipped_with_names(board_dir, tmp_path):
    d = tmp_path / "mixed"
    d.mkdir()
    for f in sorted(board_dir.iterdir())[:3]:
        (d / f.name).write_bytes(f.read_bytes())
    io.write_image(d / "road.png", np.full((720, 1280, 3), 90, np.uint8))
    (d / "broken.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the record says what was skipped; nothing is warned
        cal = calibrate(d)
    assert set(cal.skipped) == {"road.png", "broken.jpg"} and len(cal.used) == 3
    assert cal.skip_reasons == {"broken.jpg": "unreadable image", "road.png": "no 9x6 board found"}


def test_too_few_boards_names_the_folder(tmp_path):
    io.write_image(tmp_path / "road.png", np.full((720, 1280, 3), 90, np.uint8))
    with pytest.raises(CalibrationError, match=f"{tmp_path}.*only 0 image"):
        calibrate(tmp_path)


def test_missing_folder(tmp_path):
    with pytest.raises(InputError, match="no such folder"):
        calibrate(tmp_path / "nope")


def test_rescaled_calibration_and_aspect_mismatch():
    cal = Calibration(K.copy(), DIST.copy(), (1280, 720))
    half = cal.for_size((640, 360))
    np.testing.assert_allclose(half.camera_matrix[:2], K[:2] / 2)
    np.testing.assert_allclose(half.dist_coeffs, DIST)
    with pytest.raises(CalibrationError, match="960x720.*1280x720.*aspect"):
        cal.for_size((960, 720))


def test_undistorter_rejects_wrong_size():
    und = Undistorter(Calibration(K, DIST, (1280, 720)), (1280, 720))
    with pytest.raises(InputError, match="640x480.*1280x720"):
        und.undistort(np.zeros((480, 640, 3), np.uint8))


def test_distort_undistort_points_round_trip():
    cal = Calibration(K, DIST, (1280, 720))
    pts = np.array([[50.0, 40.0], [640, 360], [1200, 700], [900, 200]])
    np.testing.assert_allclose(distort_points(cal, undistort_points(cal, pts)), pts, atol=0.1)


def test_composed_remap_equals_undistort_then_warp():
    cal = Calibration(K, DIST, (1280, 720))
    rng = np.random.default_rng(0)
    raw = cv2.resize(rng.integers(0, 255, (90, 160, 3), dtype=np.uint8), (1280, 720),
                     interpolation=cv2.INTER_CUBIC)
    und = Undistorter(cal, (1280, 720))
    persp = Perspective()
    two_step = persp.warp(und.undistort(raw))
    maps = und.maps_through(persp.Minv, (1280, 720))
    one_step = cv2.remap(raw, maps[0], maps[1], cv2.INTER_LINEAR)
    # compare away from the borders: mean abs difference is a few grey levels at most
    diff = np.abs(two_step[100:-100, 300:-300].astype(int) - one_step[100:-100, 300:-300])
    assert diff.mean() < 4


def test_parse_pattern():
    assert parse_pattern("9x6") == (9, 6)
    with pytest.raises(InputError, match="COLSxROWS"):
        parse_pattern("nine")


def test_board_points_layout():
    pts = board_points((9, 6))
    assert pts.shape == (54, 3) and tuple(pts[1]) == (1, 0, 0) and tuple(pts[9]) == (0, 1, 0)


# ---------------------------------------------------------------- Udacity camera (real data)

def test_udacity_calibration(udacity_calibration):
    cal = udacity_calibration
    assert len(cal.used) == 17 and len(cal.skipped) == 3
    assert cal.rms_px < 1.5
    # the two 1281x721 photos are used on purpose (same sensor, one extra row and column)
    assert {"calibration7.jpg", "calibration15.jpg"} <= set(cal.used)
    assert cal.image_size == (1280, 720)
