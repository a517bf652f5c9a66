"""Perspective warp/unwarp, metric scale, the default points on the Udacity straight lines, and
the straight-line check."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from lanelib import io
from lanelib.camera import Calibration, Lens, distort_points, undistort_points
from lanelib.errors import ConfigError, InputError
from lanelib.params import SearchConfig
from lanelib.perspective import (Chain, Homography, Perspective, PerspectiveConfig, StraightLineCheck,
                                 scaled, straight_line_check, trapezoid_src)
from lanelib.pipeline import LanePipeline


def test_points_round_trip_within_a_pixel():
    p = Perspective()
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(200, 1080, 200), rng.uniform(470, 719, 200)])
    np.testing.assert_allclose(p.unwarp_points(p.warp_points(pts)), pts, atol=1e-6)
    # the src corners land on the dst corners
    np.testing.assert_allclose(p.warp_points(np.array(p.config.src_px)), np.array(p.config.dst_px), atol=1e-3)


def test_perspective_is_a_homography_with_an_inverse():
    p = Perspective()
    rng = np.random.default_rng(2)
    pts = np.column_stack([rng.uniform(0, 1279, 500), rng.uniform(300, 719, 500)])
    np.testing.assert_allclose(p.inverse(p(pts)), pts, rtol=1e-9, atol=0)
    bird = np.column_stack([rng.uniform(-500, 1800, 500), rng.uniform(-200, 900, 500)])
    np.testing.assert_allclose(p(p.inverse(bird)), bird, rtol=1e-9, atol=0)
    assert np.array_equal(p(pts), p.warp_points(pts))
    assert np.array_equal(p.inverse(bird), p.unwarp_points(bird))
    # scikit-image's names: params is the matrix; the inverse holds Minv, and its inverse M again
    assert p.params is p.M and p.inverse.params is p.Minv and p.inverse.inverse.params is p.M
    # the same numbers as OpenCV's point transform with the two matrices
    assert np.array_equal(p(pts), cv2.perspectiveTransform(pts.reshape(-1, 1, 2), p.M).reshape(-1, 2))
    h = Homography(p.M)  # no matrix back given: the matrix inverse (the same map up to scale)
    np.testing.assert_allclose(h.inverse.params / h.inverse.params[2, 2], p.Minv, rtol=1e-9, atol=1e-12)
    assert p(np.empty((0, 2))).shape == (0, 2)
    assert p.valid([(1.0, np.nan), (3.0, 4.0)]).tolist() == [False, True]
    with pytest.raises(ConfigError, match="3x3"):
        Homography(np.eye(2))


K = np.array([[1156.0, 0, 671.0], [0, 1151.0, 389.0], [0, 0, 1]])
DIST = np.array([-0.2467, -0.0254, -0.00067, 0.00013, 0.0107])


def test_composition_applies_in_order_and_inverts_in_reverse():
    lens, p = Lens(Calibration(K, DIST, (1280, 720))), Perspective()
    rng = np.random.default_rng(3)
    raw = np.column_stack([rng.uniform(0, 1279, 300), rng.uniform(430, 719, 300)])
    to_bird = lens.inverse + p
    assert isinstance(to_bird, Chain) and to_bird.transforms == (to_bird.transforms[0], p)
    assert np.array_equal(to_bird(raw), p(undistort_points(lens.calibration, raw, exact=True)))
    bird = to_bird(raw)
    to_raw = to_bird.inverse
    assert np.array_equal(to_raw(bird), distort_points(lens.calibration, p.inverse(bird)))
    np.testing.assert_allclose(to_raw(bird), raw, rtol=0, atol=1e-6)
    # chains flatten, and a chain of homographies is the product of their matrices
    shift = Homography(np.array([[1.0, 0, 5], [0, 1, -7], [0, 0, 1]]))
    three = p + shift + p.inverse
    assert len(three.transforms) == 3 and len((three + three).transforms) == 6
    product = Homography(p.Minv @ shift.params @ p.M)
    np.testing.assert_allclose(three(raw), product(raw), rtol=1e-9)
    np.testing.assert_allclose(three.inverse(three(raw)), raw, rtol=1e-9)


def test_image_round_trip_keeps_a_marked_point_within_a_pixel():
    p = Perspective()
    img = np.zeros((720, 1280), np.uint8)
    img[600:603, 700:703] = 255  # a 3x3 dot at (701, 601) in the undistorted view
    back = p.unwarp(p.warp(img))
    ys, xs = np.nonzero(back > 60)
    assert abs(xs.mean() - 701) < 1 and abs(ys.mean() - 601) < 1


def test_metres_per_pixel_come_with_the_points():
    cfg = PerspectiveConfig(lane_width_m=3.7, visible_length_m=30.0)
    assert cfg.xm_per_px == pytest.approx(3.7 / 640)
    assert cfg.ym_per_px == pytest.approx(30.0 / 720)
    half = scaled(cfg, (640, 360))
    assert half.xm_per_px == pytest.approx(2 * cfg.xm_per_px)
    assert half.src_px[1] == pytest.approx((cfg.src_px[1][0] / 2, 360.0))


def test_trapezoid_is_symmetric():
    tl, bl, br, tr = trapezoid_src(470, 720, 150, 900, 640)
    assert tl == (565, 470) and br == (1090, 720) and (tl[0] + tr[0]) / 2 == 640


def test_bad_points_and_wrong_size():
    with pytest.raises(ConfigError, match="src_px"):
        PerspectiveConfig(src_px=((0, 0), (1, 1), (2, 2)))
    with pytest.raises(ConfigError, match="collinear"):
        Perspective(PerspectiveConfig(src_px=((0, 0), (1, 1), (2, 2), (3, 3))))
    with pytest.raises(InputError, match="640x360.*1280x720"):
        Perspective().warp(np.zeros((360, 640, 3), np.uint8))


@pytest.mark.parametrize("name", ["straight_lines1", "straight_lines2"])
def test_default_points_make_udacity_straight_lines_vertical(name, udacity_advanced, udacity_calibration):
    pipe = LanePipeline(calibration=udacity_calibration)
    result = pipe.detect(io.read_image(udacity_advanced / "test_images" / f"{name}.jpg"))
    for fit in (result.left, result.right):
        slant = abs(fit.x_at(0) - fit.x_at(719)) / 720 * 100
        assert slant < 2.0, f"{name}: line slants {slant:.2f} px per 100 px"
    assert result.lane_width_m == pytest.approx(3.7, abs=0.2)


# --------------------------------------------------------------------------- straight-line check

def test_straight_line_check_on_drawn_lines():
    binary = np.zeros((720, 1280), np.uint8)
    cv2.line(binary, (300, 0), (330, 719), 255, 12)   # 30 px over 719 px: 4.17 px per 100 px
    cv2.line(binary, (960, 0), (960, 719), 255, 12)
    c = straight_line_check(binary, 3.7 / 640)
    assert c.left_slope == pytest.approx(100 * 30 / 719, abs=0.1)
    assert c.right_slope == pytest.approx(0.0, abs=0.05)
    assert c.lane_width_m == pytest.approx((960 - 330) * 3.7 / 640, abs=0.02)
    empty = straight_line_check(np.zeros((720, 1280), np.uint8), 0.005)
    assert np.isnan(empty.left_slope) and np.isnan(empty.lane_width_m) and empty.left_fit is None


def test_straight_line_check_needs_enough_of_a_line():
    binary = np.zeros((720, 1280), np.uint8)
    cv2.line(binary, (320, 0), (320, 719), 255, 12)
    cv2.line(binary, (960, 690), (960, 719), 255, 12)  # 5 % of the height: too short to fit
    c = straight_line_check(binary, 3.7 / 640, SearchConfig(), car_x=640.0)
    assert c.left_fit is not None and c.right_fit is None
    assert math.isnan(c.right_slope) and math.isnan(c.lane_width_m)


def test_straight_line_check_prints_rounded_figures():
    c = StraightLineCheck(-0.0001, 4.166, 3.7049, (0.0, 320.0), (0.04, 930.0))
    assert str(c) == "left +0.00 px/100 px, right +4.17 px/100 px, lane width 3.70 m"
    nan = float("nan")
    assert str(StraightLineCheck(nan, nan, nan, None, None)) == (
        "left not found, right not found, lane width not found")
