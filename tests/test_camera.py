"""Calibration, the Calibration record, and undistortion maps."""
from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from lanelib import io
from lanelib.camera import (MODEL_MARGIN, Calibration, Lens, Undistorter, board_points, calibrate,
                            distort_points, undistort_points)
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


# --------------------------------------------------------------------------- the lens as a transform

def image_grid(step: float = 20.0, size=(1280, 720)) -> np.ndarray:
    """Return (N, 2) points (x, y) every ``step`` px over a frame, its last row and column included."""
    xs, ys = np.meshgrid(np.r_[np.arange(0, size[0] - 1, step), size[0] - 1],
                         np.r_[np.arange(0, size[1] - 1, step), size[1] - 1])
    return np.column_stack([xs.ravel(), ys.ravel()]).astype(np.float64)


@pytest.mark.parametrize("dist", [DIST, np.array([-0.2467, -0.0254, -0.00067, 0.00013, 0.0107])])
def test_lens_round_trips_within_a_micropixel_over_the_image(dist):
    lens = Lens(Calibration(K, dist, (1280, 720)))
    pts = image_grid()
    np.testing.assert_allclose(lens(lens.inverse(pts)), pts, rtol=0, atol=1e-6)
    np.testing.assert_allclose(lens.inverse(lens(pts)), pts, rtol=0, atol=1e-6)
    assert lens.inverse.inverse is lens
    # the lens is distort_points, its inverse undistort_points run to convergence
    assert np.array_equal(lens(pts), distort_points(lens.calibration, pts))
    assert np.array_equal(lens.inverse(pts), undistort_points(lens.calibration, pts, exact=True))
    # OpenCV's default 5 steps are as good only near the centre (pixels off in the corners)
    centre = pts[np.hypot(pts[:, 0] - 640, pts[:, 1] - 360) < 200]
    np.testing.assert_allclose(undistort_points(lens.calibration, centre), lens.inverse(centre), atol=1e-3)


def test_lens_is_rescaled_to_the_frame_size():
    cal = Calibration(K, DIST, (1280, 720))
    half = Lens(cal, (640, 360))
    pts = image_grid(size=(640, 360))
    np.testing.assert_allclose(half(pts), Lens(cal)(2 * pts) / 2, atol=1e-9)
    assert half.size == (640, 360)
    np.testing.assert_array_equal(Undistorter(cal, (640, 360)).lens.calibration.camera_matrix,
                                  half.calibration.camera_matrix)


def test_identity_lens():
    lens = Lens(None, (1280, 720))
    pts = image_grid(97.0)
    assert lens.is_identity and not Lens(Calibration(K, DIST, (1280, 720))).is_identity
    for f in (lens, lens.inverse, lens + lens.inverse):
        out = f(pts)
        assert np.array_equal(out, pts) and out is not pts
    assert lens(np.empty((0, 2))).shape == (0, 2)
    map1, map2 = lens.undistort_maps((2, 3), cv2.CV_32FC2)
    assert map2 is None and map1.shape == (726, 1284, 2) and tuple(map1[3, 2]) == (0.0, 0.0)
    frame = np.random.default_rng(3).integers(0, 255, (720, 1280, 3), dtype=np.uint8)
    assert Undistorter(None, (1280, 720)).undistort(frame) is frame
    with pytest.raises(CalibrationError, match="frame size"):
        Lens(None)


def test_the_folded_back_rule_rejects_points_where_the_lens_model_turns_back():
    # k1 = -0.3 alone: r_d = r (1 - 0.3 r^2) grows up to r = 1.054 (x = 1694 px on the centre
    # row), then shrinks again: a point far right of the frame lands back inside it.
    lens = Lens(Calibration(K, np.array([-0.3, 0.0, 0.0, 0.0, 0.0]), (1280, 720)))
    xs = np.arange(-900.0, 2401.0, 4.0)
    row = np.column_stack([xs, np.full_like(xs, 360.0)])
    raw_x = lens(row)[:, 0]
    far = row[xs == 2300.0]
    assert 0 <= lens(far)[0, 0] < 1280                     # folded back into the frame
    ok = lens.valid(row)
    assert np.array_equal(ok, (xs >= -MODEL_MARGIN * 1280) & (xs <= (1 + MODEL_MARGIN) * 1280))
    assert not lens.valid(far)[0] and ok[xs == 1600.0][0] and ok[xs == -320.0][0]  # edges kept
    assert np.all(np.diff(raw_x[ok]) > 0)                  # monotonic where the rule keeps points
    assert not np.all(np.diff(raw_x) > 0)                  # ... and not over the whole row
    column = np.array([[640.0, -180.0], [640.0, 900.0], [640.0, -181.0], [640.0, 901.0]])
    assert lens.valid(column).tolist() == [True, True, False, False]
    # the rule does not depend on the calibration: the identity lens keeps the same region
    assert np.array_equal(Lens(None, (1280, 720)).valid(row), ok)
    # the lens's inverse checks where the raw points land; a chain checks every step's input
    und, inv_ok = lens.inverse.checked(lens(row[ok]))
    assert inv_ok.all() and np.abs(und - row[ok]).max() < 1e-3  # slow convergence near the fold
    persp = Perspective()
    bird = np.array([[640.0, 700.0], [-3000.0, 700.0], [640.0, 0.0], [4000.0, 700.0]])
    to_raw = persp.inverse + lens
    assert np.array_equal(to_raw.valid(bird), lens.valid(persp.inverse(bird)))
    assert to_raw.valid(bird).tolist() == [True, False, True, False]


def old_maps_through(cal, size, Minv, out_size):
    """The composed remap maps as ``Undistorter.maps_through`` made them before the transforms."""
    w, h = out_size
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    grid = np.stack([xs.ravel(), ys.ravel()], axis=1).reshape(-1, 1, 2)
    und = cv2.perspectiveTransform(grid, Minv).reshape(-1, 2)
    src = distort_points(cal, und) if cal is not None else und
    fw, fh = size
    outside = ((und[:, 0] < -0.25 * fw) | (und[:, 0] > 1.25 * fw)
               | (und[:, 1] < -0.25 * fh) | (und[:, 1] > 1.25 * fh))
    src[outside] = -1.0
    return cv2.convertMaps(src[:, 0].reshape(h, w).astype(np.float32),
                           src[:, 1].reshape(h, w).astype(np.float32), cv2.CV_16SC2)


@pytest.mark.parametrize("cal", [Calibration(K, DIST, (1280, 720)), None])
def test_remap_maps_of_the_chain_are_the_old_composed_maps(cal):
    persp = Perspective()
    und = Undistorter(cal, (1280, 720))
    old = old_maps_through(und.calibration, und.size, persp.Minv, (1280, 720))
    chain = und.lens.inverse + persp
    for maps in (chain.remap_maps((1280, 720)), und.maps_through(persp.Minv, (1280, 720))):
        assert np.array_equal(maps[0], old[0]) and np.array_equal(maps[1], old[1])
    # the lens's own grids are the Undistorter's
    if cal is not None:
        m = und.lens.undistort_maps()
        ref = cv2.initUndistortRectifyMap(K, DIST, None, K, (1280, 720), cv2.CV_16SC2)
        assert np.array_equal(m[0], ref[0]) and np.array_equal(m[1], ref[1])


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
