"""Perspective warp/unwarp, metric scale, and the default points on the Udacity straight lines."""
from __future__ import annotations

import numpy as np
import pytest

from lanelib import io
from lanelib.errors import ConfigError, InputError
from lanelib.perspective import Perspective, PerspectiveConfig, scaled, trapezoid_src
from lanelib.pipeline import LanePipeline


def test_points_round_trip_within_a_pixel():
    p = Perspective()
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(200, 1080, 200), rng.uniform(470, 719, 200)])
    np.testing.assert_allclose(p.unwarp_points(p.warp_points(pts)), pts, atol=1e-6)
    # the src corners land on the dst corners
    np.testing.assert_allclose(p.warp_points(np.array(p.config.src_px)), np.array(p.config.dst_px), atol=1e-3)


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
