"""Tests of lanelib.autogeometry: the road geometry estimated from frames, against the true geometry of
synthetic cameras (issue 15, point 3), and its errors on frames that show no usable road.

Every camera sees the same straight road (a yellow solid line left, dashed white lines right, a
solid edge line) from six poses a few metres apart, with the car off the lane centre by up to
25 cm and turned by up to 0.004 rad. The tolerances are the issue's: the horizon row within
2 px, the lane width measured through the estimated bird's-eye view within 3 %, metres per
pixel along the road within 5 %.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from lanelib import autogeometry
from lanelib.camera import Calibration, undistort_points
from lanelib.errors import GeometryError, LaneLibError
from lanelib.autogeometry import dashes as dash_period
from lanelib.autogeometry import LOW_CONFIDENCE, RoadGeometry, RoadLineFinder, estimate_geometry, vanishing_point
from lanelib.config import PipelineConfig
from lanelib.evaluate import evaluate_video
from lanelib.io import VideoReader, read_image
from lanelib.perspective import DEFAULT_SRC_1280x720, Perspective, PerspectiveConfig
from lanelib.pipeline import LanePipeline
from lanelib.synth import (Camera, CarPose, CurvatureProfile, GroundGrid, Layout, Look, Renderer, Scene,
                           birdseye_scale, load_image_truth, load_video_truth, perspective_truth, video_sets,
                           write_video)

REPO = Path(__file__).resolve().parents[1]

BASE = dict(size_px=(1280, 720), hfov_deg=60.0, height_m=1.25, pitch_deg=-1.0)


def pinhole(**kw) -> Camera:
    return Camera.pinhole(**{**BASE, **kw})


CAMERAS = {
    "bundled": Camera(),
    "wide_960x540": pinhole(size_px=(960, 540), hfov_deg=90.0),
    "narrow_1920x1080": pinhole(size_px=(1920, 1080), hfov_deg=40.0),
    "wide_1640x590": pinhole(size_px=(1640, 590), hfov_deg=70.0, pitch_deg=0.0),
    "height_1.0": pinhole(height_m=1.0),
    "height_1.6": pinhole(height_m=1.6),
    "pitch_-4": pinhole(pitch_deg=-4.0),
    "pitch_+2": pinhole(pitch_deg=2.0),
    "yaw_+3": pinhole(yaw_deg=3.0),
    "yaw_-3": pinhole(yaw_deg=-3.0),
    "roll_+1.5": pinhole(roll_deg=1.5),
    "roll_-1.5": pinhole(roll_deg=-1.5),
    # all at once, with a mildly distorting lens that the estimate is given
    "mixed_distorted": pinhole(yaw_deg=2.5, roll_deg=-1.2, pitch_deg=-2.5, height_m=1.45,
                               dist_coeffs=(-0.12, 0.02, 0.0, 0.0, 0.0)),
}
POSES = tuple(CarPose(10.0 + 2.9 * i, 0.25 * math.sin(1.3 * i), 0.004 * math.sin(0.9 * i + 1)) for i in range(6))
STRAIGHT = Scene(CurvatureProfile(), Layout(3.7), Look(), -20.0, 260.0, seed=21)


def lens_of(camera: Camera) -> Calibration | None:
    """The calibration the estimate is given: the bundled camera's and the distorting one's."""
    if camera == Camera() or any(camera.dist_coeffs):
        return Calibration(camera.K, camera.dist, camera.size_px, 0.0)
    return None


@pytest.fixture(scope="module")
def straight_renderer() -> Renderer:
    return Renderer(STRAIGHT, GroundGrid.build())


@pytest.fixture(scope="module")
def estimates(straight_renderer) -> dict:
    """{camera name: (camera, frames, RoadGeometry)}, rendered and estimated once."""
    out = {}
    for name, camera in CAMERAS.items():
        renderer = straight_renderer.for_grid(GroundGrid.build(camera)) if name != "bundled" else straight_renderer
        frames = [renderer.render(p, noise_key=i) for i, p in enumerate(POSES)]
        out[name] = (camera, frames, estimate_geometry(frames, lens=lens_of(camera)))
    return out


def birdseye_lines(camera: Camera, geom: RoadGeometry, offset_m: float, heading_rad: float = 0.0,
                   lane_width_m: float = 3.7):
    """Return the ego lane's two lines, seen from a car ``offset_m`` right of the lane centre and
    turned by ``heading_rad``, mapped into the estimated bird's-eye view ((N, 2) each)."""
    persp = Perspective(geom.perspective_config())
    z = np.linspace(4.0, 45.0, 60)
    out = []
    for t in (-lane_width_m / 2, lane_width_m / 2):
        # the line in the car frame: lateral t - offset, rotated by the car's heading
        x0 = t - offset_m
        x = x0 * math.cos(heading_rad) - z * math.sin(heading_rad)
        zz = x0 * math.sin(heading_rad) + z * math.cos(heading_rad)
        uv = camera.project(np.column_stack([x, np.zeros_like(z), zz]), distort=False)
        out.append(persp(uv))
    return out


# --------------------------------------------------------------------------- the synthetic cameras

def test_pinhole_camera_geometry_is_the_textbook_one():
    cam = Camera.pinhole((1280, 720), focal_px=1000.0, height_m=1.4, pitch_deg=2.0, yaw_deg=-3.0, roll_deg=0.0)
    vx, vy = cam.vanishing_point_px()
    assert vy == pytest.approx(360 - 1000 * math.tan(math.radians(2.0)), abs=1e-9)
    assert vx == pytest.approx(640 + 1000 * math.tan(math.radians(3.0)) / math.cos(math.radians(2.0)), abs=1e-9)
    row, slope = cam.horizon_px()
    assert (row, slope) == (pytest.approx(vy, abs=1e-9), pytest.approx(0.0, abs=1e-12))
    # roll turns the image about the principal point: the horizon rises to the right for roll > 0
    rolled = Camera.pinhole((1280, 720), focal_px=1000.0, pitch_deg=2.0, roll_deg=1.5)
    row, slope = rolled.horizon_px()
    assert slope == pytest.approx(-math.tan(math.radians(1.5)), abs=1e-12)
    # the horizon's distance from the principal point does not change with the roll
    assert (360 - row) * math.cos(math.radians(1.5)) == pytest.approx(1000 * math.tan(math.radians(2.0)), abs=1e-6)
    # exactly one of hfov and focal length
    with pytest.raises(ValueError):
        Camera.pinhole((1280, 720))
    assert Camera.pinhole((960, 540), hfov_deg=90.0).K[0, 0] == pytest.approx(480.0)


def test_bundled_camera_is_unchanged_by_the_roll():
    cam = Camera()
    assert cam.roll_deg == 0.0
    p, y = math.radians(cam.pitch_deg), math.radians(cam.yaw_deg)
    z_axis = np.array([math.sin(y) * math.cos(p), math.sin(p), math.cos(y) * math.cos(p)])
    x_axis = np.array([math.cos(y), 0.0, -math.sin(y)])
    assert np.array_equal(cam.rotation(), np.stack([x_axis, np.cross(z_axis, x_axis), z_axis]))
    assert cam.vanishing_point_px() == pytest.approx((640.0, 419.03), abs=0.01)


def test_birdseye_scale_of_the_truth_points_is_their_own():
    for camera in (Camera(), CAMERAS["roll_+1.5"], CAMERAS["narrow_1920x1080"]):
        truth = perspective_truth(camera)
        xm, ym = birdseye_scale(camera, truth.src_px, truth.dst_px)
        assert xm == pytest.approx(truth.xm_per_px, rel=1e-3)
        assert ym == pytest.approx(truth.ym_per_px, rel=1e-3)


def test_renderer_for_another_grid_renders_what_a_new_renderer_does(straight_renderer):
    grid = GroundGrid.build(CAMERAS["wide_960x540"])
    pose = POSES[1]
    assert np.array_equal(straight_renderer.for_grid(grid).render(pose, noise_key=3),
                          Renderer(STRAIGHT, grid).render(pose, noise_key=3))


# --------------------------------------------------------------------------- the estimate on every camera

@pytest.mark.parametrize("name", list(CAMERAS))
def test_horizon_within_2_px(estimates, name):
    camera, _, geom = estimates[name]
    row, slope = camera.horizon_px()
    assert abs(geom.horizon_row_px - row) <= 2.0
    assert geom.horizon_slope == pytest.approx(slope, abs=0.005)
    assert len(geom.frames_used) >= 4 and geom.confidence >= LOW_CONFIDENCE


@pytest.mark.parametrize("name", list(CAMERAS))
def test_lane_width_through_the_estimated_view_within_3_percent(estimates, name):
    camera, _, geom = estimates[name]
    check_lane_width(camera, geom, 3.7)


def check_lane_width(camera: Camera, geom: RoadGeometry, lane_width_m: float) -> None:
    """Assert that the ego lane measures ``lane_width_m`` within 3 % through the estimated view."""
    for offset, heading in ((0.3, 0.0), (-0.4, 0.01)):
        left, right = birdseye_lines(camera, geom, offset, heading, lane_width_m)
        h = geom.size_px[1]
        for row in (0.05 * h, 0.5 * h, 0.95 * h):
            xl = np.interp(row, left[::-1, 1], left[::-1, 0])
            xr = np.interp(row, right[::-1, 1], right[::-1, 0])
            # across the lane, square to the lines (the car is turned by ``heading``)
            slope = np.polyfit(left[:, 1], left[:, 0], 1)[0] * geom.xm_per_px / geom.ym_per_px
            width = (xr - xl) * geom.xm_per_px * math.cos(math.atan(slope))
            assert width == pytest.approx(lane_width_m, rel=0.03), (offset, row)


def test_a_car_in_a_middle_lane_measures_its_own_lane_not_three():
    """Known answer: on a road of four 3.6 m lanes, a car in the two middle lanes (a little off
    their centres, as the TuSimple/CULane samples drive) sees the neighbour lanes' outer lines
    as a pair three lanes wide and as centred on it as its own lane's. Taking that pair (as the
    estimate once did in most frames) put the camera 0.5 m above the road with a focal length of
    3300 px; the road's other lines, one lane apart, tell the lane's true width."""
    camera = pinhole(height_m=1.55, pitch_deg=2.8, roll_deg=-0.5)
    road = Scene(CurvatureProfile(), Layout(3.6, right_lanes=3, left_shoulder_m=3.0), Look(), -20.0, 260.0,
                 seed=23)
    renderer = Renderer(road, GroundGrid.build(camera))
    offsets = (3.6 + 0.3, 7.2 - 0.25, 3.6 - 0.3, 7.2 + 0.3, 3.6 + 0.2, 7.2 - 0.3, 0.2)
    poses = [CarPose(10.0 + 2.9 * i, o, 0.004 * math.sin(0.9 * i + 1)) for i, o in enumerate(offsets)]
    geom = estimate_geometry([renderer.render(p, noise_key=i) for i, p in enumerate(poses)], lane_width_m=3.6)
    check_lane_width(camera, geom, 3.6)
    assert geom.camera_height_m == pytest.approx(1.55, rel=0.03)
    assert geom.focal_px == pytest.approx(camera.K[0, 0], rel=0.05)
    assert geom.roll_deg == pytest.approx(-0.5, abs=0.2)
    assert not geom.low_confidence


def test_an_implausible_camera_height_is_said_and_distrusted(estimates):
    """Lanes said to be 0.6 m wide put the bundled camera 0.2 m above the road: the estimate
    says so and its confidence falls below LOW_CONFIDENCE (a wrong pairing of the lines does the same)."""
    _, frames, _ = estimates["bundled"]
    geom = estimate_geometry(frames, lens=lens_of(Camera()), lane_width_m=0.6)
    assert geom.camera_height_m < autogeometry.CAMERA_HEIGHT_RANGE_M[0]
    assert any(a.startswith("implausible") for a in geom.assumptions)
    assert geom.low_confidence


@pytest.mark.parametrize("name", list(CAMERAS))
def test_metres_per_pixel_along_the_road_within_5_percent(estimates, name):
    camera, _, geom = estimates[name]
    assert geom.scale_source.startswith("dash period")
    # the scale the estimated points truly carry ...
    _, ym_true = birdseye_scale(camera, geom.src_px, geom.dst_px)
    assert geom.ym_per_px == pytest.approx(ym_true, rel=0.05)
    # ... and lengths along the road measured in the view, near and far
    persp = Perspective(geom.perspective_config())
    z = np.array([6.0, 10.0, 16.0, 22.0])
    y = persp(camera.project(np.column_stack([np.zeros(4), np.zeros(4), z]), distort=False))[:, 1]
    for i, j in ((0, 1), (0, 3), (2, 3)):
        assert abs(y[i] - y[j]) * geom.ym_per_px == pytest.approx(z[j] - z[i], rel=0.05)


@pytest.mark.parametrize("name", [n for n in CAMERAS if n != "bundled"] + ["bundled"])
def test_roll_pitch_yaw_and_focal_length(estimates, name):
    camera, _, geom = estimates[name]
    assert geom.roll_deg == pytest.approx(camera.roll_deg, abs=0.2)
    if camera.roll_deg:
        assert geom.roll_source.startswith("lane spacing")
    assert geom.focal_px == pytest.approx(camera.K[0, 0], rel=0.05)
    assert geom.pitch_deg == pytest.approx(camera.pitch_deg, abs=0.3)
    assert geom.yaw_deg == pytest.approx(camera.yaw_deg, abs=0.3)
    assert geom.camera_height_m == pytest.approx(camera.height_m, rel=0.03)


def test_bundled_camera_estimate_is_close_to_the_default_points(estimates):
    _, _, geom = estimates["bundled"]
    assert geom.vanishing_point_px == pytest.approx((640.0, 419.0), abs=1.5)
    # the sides of the estimated trapezoid run through the default corners' rows within 3 px
    (tlx, tly), (blx, bly), (brx, bry), (trx, try_) = geom.src_px
    for row, (dl, dr) in ((470.0, (DEFAULT_SRC_1280x720[0][0], DEFAULT_SRC_1280x720[3][0])),
                          (720.0, (DEFAULT_SRC_1280x720[1][0], DEFAULT_SRC_1280x720[2][0]))):
        left = blx + (row - bly) * (tlx - blx) / (tly - bly)
        right = brx + (row - bry) * (trx - brx) / (try_ - bry)
        assert (left, right) == (pytest.approx(dl, abs=3.0), pytest.approx(dr, abs=3.0))
    # the hood of the synthetic car: 26 px high in the middle (row 694), in the undistorted frame
    hood = undistort_points(lens_of(Camera()), np.array([[640.0, 694.0]]), exact=True)[0, 1]
    assert geom.hood_row_px == pytest.approx(hood, abs=2.0)
    assert geom.look_ahead_m == 25.0 and geom.near_m == pytest.approx(5.0, abs=1.0)


def test_a_known_focal_length_gives_the_scale_without_dashes(estimates):
    camera, frames, _ = estimates["pitch_+2"]
    # dashes far longer than the road shows: none is seen as a dash of that pattern
    geom = estimate_geometry(frames, focal_px=camera.K[0, 0], dash_m=30.0, gap_m=90.0)
    assert geom.scale_source == "focal length and lane width"
    _, ym_true = birdseye_scale(camera, geom.src_px, geom.dst_px)
    assert geom.ym_per_px == pytest.approx(ym_true, rel=0.05)
    assert geom.pitch_deg == pytest.approx(2.0, abs=0.3)
    # no focal length and no dashes: an assumed focal length, said so, with a low confidence
    guess = estimate_geometry(frames, dash_m=30.0, gap_m=90.0)
    assert guess.scale_source.startswith("assumed focal length") and guess.pitch_deg is None
    assert guess.low_confidence and any("assumed" in a for a in guess.assumptions)


def test_ignoring_the_roll_states_its_cost(estimates):
    camera, frames, _ = estimates["roll_+1.5"]
    geom = estimate_geometry(frames, estimate_roll=False)
    assert geom.roll_deg == 0.0 and geom.roll_source == "assumed 0"
    assert any(a.startswith("roll assumed 0") for a in geom.assumptions)
    # the horizon at the centre still within 2 px: the vanishing point is near the centre column
    assert abs(geom.horizon_row_px - camera.horizon_px()[0]) <= 2.0


def test_the_result_is_deterministic_and_json(estimates):
    camera, frames, geom = estimates["yaw_-3"]
    again = estimate_geometry(frames)
    assert again.to_dict() == geom.to_dict()
    d = json.loads(json.dumps(geom.to_dict()))
    assert d["size_px"] == [1280, 720] and len(d["src_px"]) == 4
    cfg = geom.perspective_config()
    assert isinstance(cfg, PerspectiveConfig)
    assert cfg.xm_per_px == pytest.approx(geom.xm_per_px) and cfg.ym_per_px == pytest.approx(geom.ym_per_px)
    assert "vanishing point" in geom.summary()


def test_one_bundled_image_is_enough_for_the_horizon():
    path = REPO / "test_images" / "straight_1.jpg"
    truth = load_image_truth(path)
    geom = estimate_geometry([read_image(path)], lens=truth.camera.calibration())
    assert abs(geom.horizon_row_px - truth.camera.horizon_px()[0]) <= 2.0
    assert geom.hood_source.startswith("not detected")
    assert any("hood not detected" in a for a in geom.assumptions)


# --------------------------------------------------------------------------- one frame

def test_vanishing_point_of_one_frame(estimates):
    camera, frames, _ = estimates["yaw_+3"]
    finder = RoadLineFinder(camera.size_px)
    vp = finder.vanishing_point(frames[0])
    assert vp.ok and vp.inlier_segments >= 10 and len(vp.lines) >= 2
    assert vp.point_px[1] == pytest.approx(camera.vanishing_point_px()[1], abs=1.5)
    # the car is turned by POSES[0].heading_rad: the road vanishes that much to the left
    expected_x = camera.vanishing_point_px()[0] - camera.K[0, 0] * math.tan(POSES[0].heading_rad)
    assert vp.point_px[0] == pytest.approx(expected_x, abs=3.0)
    assert vanishing_point(frames[0]).point_px == pytest.approx(vp.point_px)
    # on the estimated horizon: no drift; a frame of the same camera pitched 1 deg down: drift
    _, _, geom = estimates["yaw_+3"]
    assert abs(geom.horizon_shift_px(vp.point_px)) < 1.0
    tilted = Camera.pinhole(**{**BASE, "yaw_deg": 3.0, "pitch_deg": 0.0})
    frame = Renderer(STRAIGHT, GroundGrid.build(tilted)).render(POSES[0])
    shift = geom.horizon_shift_px(RoadLineFinder(tilted.size_px).vanishing_point(frame).point_px)
    expected = tilted.vanishing_point_px()[1] - camera.vanishing_point_px()[1]    # 19 px higher
    assert shift == pytest.approx(expected, abs=1.5) and -shift > autogeometry.DRIFT_PX


# --------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("kind", ["grey", "noise"])
def test_frames_with_no_road_raise_naming_the_reason(kind):
    rng = np.random.default_rng(5)
    if kind == "grey":
        frames = [np.full((720, 1280, 3), 118, np.uint8)] * 3
    else:
        frames = [rng.integers(0, 256, (720, 1280, 3), dtype=np.uint8) for _ in range(3)]
    with pytest.raises(GeometryError) as e:
        estimate_geometry(frames)
    msg = str(e.value)
    assert "no consistent vanishing point in 3 frames" in msg
    assert any(r in msg for r in ("no road", "too few line segments", "inconsistent", "too few lines"))
    assert "give frames" in msg
    vp = vanishing_point(frames[0])
    assert vp.point_px is None and not vp.ok and vp.reason
    if kind == "grey":
        assert vp.reason.startswith("no road")


def test_a_rotated_video_is_refused_or_distrusted(estimates):
    _, frames, _ = estimates["bundled"]
    rotated = [np.ascontiguousarray(np.rot90(f)) for f in frames]
    try:
        geom = estimate_geometry(rotated)
    except GeometryError as e:
        assert "rotated" in str(e) or "vanishing point" in str(e)
    else:
        assert geom.low_confidence


def test_a_bending_road_is_not_straight(straight_renderer):
    bend = Scene(CurvatureProfile(((0.0, 1 / 500),)), Layout(3.7), Look(), -20.0, 260.0, seed=22)
    renderer = Renderer(bend, straight_renderer.grid)
    frames = [renderer.render(CarPose(10.0 + 3 * i), noise_key=i) for i in range(3)]
    with pytest.raises(GeometryError, match="road not straight"):
        estimate_geometry(frames, lens=lens_of(Camera()))


def test_bad_arguments_are_input_errors(estimates):
    _, frames, _ = estimates["bundled"]
    with pytest.raises(LaneLibError, match="no frames"):
        estimate_geometry([])
    with pytest.raises(LaneLibError, match="frame 1"):
        estimate_geometry([frames[0], frames[0][:100]])
    with pytest.raises(LaneLibError, match="must be positive"):
        estimate_geometry(frames, lane_width_m=0.0)
    with pytest.raises(GeometryError, match="look-ahead"):
        estimate_geometry(frames, lens=lens_of(Camera()), look_ahead_m=3.0)


# --------------------------------------------------------------------------- the evaluation

def test_auto_geometry_scores_like_the_true_one(tmp_path):
    """Issue 15's goal on a 3 s clip of the project road through the wide 960x540 camera: with the
    estimated points the pipeline's median curvature error is within 1.5x, and its point
    accuracy within 2 points, of what the true points give."""
    camera = CAMERAS["wide_960x540"]
    path = write_video(tmp_path / "wide.mp4", video_sets()["project"], seconds=3.0, grid=GroundGrid.build(camera))
    with VideoReader(path) as reader:
        frames = [f for i, f in enumerate(reader) if i % 3 == 0]
    geom = estimate_geometry(frames)
    truth = load_video_truth(path)
    scores = {}
    for name, config in (("true", truth.camera.perspective.config()), ("auto", geom.perspective_config())):
        pipeline = LanePipeline(PipelineConfig(perspective=config), truth.camera.calibration())
        scores[name] = evaluate_video(path, pipeline).summary()
    assert scores["auto"]["found_rate"] == 1.0
    assert scores["auto"]["curvature_err_median"] <= 1.5 * scores["true"]["curvature_err_median"]
    assert scores["auto"]["point_accuracy"] >= scores["true"]["point_accuracy"] - 0.02


def test_the_dash_length_model_allows_for_blur_and_ignores_markers_and_merged_runs():
    """Runs of dashes a + b q^2 long in q (b px of blur), raised markers (3 px) and two dashes
    merged into one run: the model is the dashes' (Theil-Sen over the single long runs), and a
    marker less the blur is far shorter than a dash, so the period finder drops it."""
    a, b = 3.0 / 1100, 3.0
    q = np.linspace(0.008, 0.026, 12)
    dashes = a + b * q ** 2
    markers_q = np.array([0.013, 0.018, 0.023])
    markers = 3.0 * markers_q ** 2
    merged_q, merged = np.array([0.02]), np.array([3 * a + b * 0.02 ** 2])
    centre = np.concatenate([q, markers_q, merged_q])
    length = np.concatenate([dashes, markers, merged])
    got_a, got_b = dash_period.dash_length_model(centre, length)
    assert got_a == pytest.approx(a, rel=0.02) and got_b == pytest.approx(b, rel=0.05)
    own = markers - got_b * markers_q ** 2
    assert np.all(own < dash_period.DASH_LENGTH_WINDOW[0] * got_a)
