"""Known-answer tests of the hard-road failure classes of lanelib.synth (issue 16): the double
yellow centre line, the asphalt edge, missing paint, barriers, glare and sheen, exposure jumps,
and the truth of a road with a vertical profile (grades)."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from lanelib.synth import CarPose, GroundGrid, Renderer, Scene, image_scenes, load_image_truth, load_video_truth
from lanelib.synth.road import CurvatureProfile, heights
from lanelib.synth.scene import Barrier, Layout, Look
from lanelib.synth.sets import country_layout, hard_scenes, hard_video_sets
from lanelib.synth.truth import NOT_VISIBLE, lane_truth

REPO = Path(__file__).resolve().parents[1]
PLAIN = Look(patches_per_100m=0.0, asphalt_blotches=0.0, grain=0.0, paint_wear=0.0, sensor_noise=0.0)


@pytest.fixture(scope="module")
def grid() -> GroundGrid:
    return GroundGrid.build()


def yellowness(image: np.ndarray) -> np.ndarray:
    f = image.astype(np.float64)
    return f[..., 0] + f[..., 1] - 2 * f[..., 2]


def test_double_yellow_renders_two_stripes_at_their_offsets(grid):
    layout = Layout(3.6, right_lanes=0, left_shoulder_m=4.0, line_width_m=0.12, centre_gap_m=0.1)
    lines = layout.lines()
    assert [ln.t_m for ln in lines if ln.yellow] == pytest.approx([-1.8 - 0.22, -1.8])
    scene = Scene(CurvatureProfile(), layout, PLAIN, seed=5)
    r = Renderer(scene, grid)
    pose = CarPose(10.0)
    image = r.render(pose)
    inner = lane_truth(r, pose)
    outer = lane_truth(Renderer(replace(scene, layout=Layout(2 * 2.02, right_lanes=0)), grid), pose)
    row = 600
    i = inner.h_samples_px.index(row)
    x_in, x_out = inner.left_x_px[i], outer.left_x_px[i]
    assert x_out < x_in - 8           # two stripes, the truth on the inner one
    y = yellowness(image)[row]
    lo = int(x_out) - 15
    profile = y[lo:int(x_in) + 16]
    above = profile > 0.5 * profile.max()
    starts = np.flatnonzero(above[1:] & ~above[:-1]) + 1
    ends = np.flatnonzero(~above[1:] & above[:-1]) + 1
    peaks = [lo + float((profile[a:b] * np.arange(a, b)).sum() / profile[a:b].sum()) for a, b in zip(starts, ends)]
    assert len(peaks) == 2
    assert peaks[0] == pytest.approx(x_out, abs=1.5) and peaks[1] == pytest.approx(x_in, abs=1.5)
    assert y[int(round((x_in + x_out) / 2))] < 0.5 * profile.max()   # the gap between them is asphalt


def test_asphalt_edge_is_the_right_truth_line(grid):
    layout = country_layout(4.6, right_line=False)
    assert not any(ln.t_m > 0 for ln in layout.lines())     # nothing painted on the right
    assert layout.paved_m[1] == pytest.approx(2.3)
    scene = Scene(CurvatureProfile(), layout, PLAIN, seed=6)
    r = Renderer(scene, grid)
    pose = CarPose(10.0)
    grey = r.render(pose).astype(np.float64).mean(axis=2)
    lane = lane_truth(r, pose)
    assert lane.lane_width_m == 4.6
    for row, x in zip(lane.h_samples_px, lane.right_x_px):
        if x == NOT_VISIBLE or not 500 <= row <= 680:
            continue
        xi = int(round(x))
        step = np.abs(np.diff(grey[row, xi - 6:xi + 7]))
        assert abs(int(np.argmax(step)) + xi - 6 + 0.5 - x) <= 1.5   # the asphalt/grass edge


def test_missing_paint_leaves_no_paint_in_the_truth_band(grid):
    look = replace(PLAIN, paint_missing_m=((25.0, 60.0, -2.5, -1.2),))
    scene = Scene(CurvatureProfile(), Layout(3.7), look, seed=7)
    r = Renderer(scene, grid)
    pose = CarPose(10.0)
    y = yellowness(r.render(pose))
    lane = lane_truth(r, pose)
    cam = grid.camera
    gone, kept = [], []
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or row > 690:
            continue
        z = cam.ground_points(np.array([[x, row]]))[0, 1]        # distance ahead of this row
        band = y[row, int(x) - 4:int(x) + 5].max()
        if 15.0 + 3.0 < z < 40.0:
            gone.append(band)
        elif z < 15.0 - 3.0:
            kept.append(band)
    assert len(gone) >= 3 and len(kept) >= 3
    assert max(gone) < 25 and min(kept) > 100


def test_barrier_face_lies_beyond_the_left_line_and_its_top_is_bright(grid):
    look = replace(PLAIN, barriers=(Barrier(-2.45),))
    scene = Scene(CurvatureProfile(), Layout(3.7, left_shoulder_m=0.6), look, seed=8)
    plain = Renderer(replace(scene, look=PLAIN), grid)
    r = Renderer(scene, grid)
    pose = CarPose(10.0)
    a, b = r.render(pose).astype(np.float64), plain.render(pose).astype(np.float64)
    changed = np.abs(a - b).max(axis=2) > 10
    lane = lane_truth(r, pose)
    cam = grid.camera
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or not 480 <= row <= 680:
            continue
        assert not changed[row, int(x) + 3:].any()          # the lane and its line untouched
        # the face's foot: where the road at t = -2.45 is seen in this row
        z = cam.ground_points(np.array([[x, row]]))[0, 1]
        foot = cam.project(np.array([[-2.45, 0.0, z]]))[0, 0]
        if foot > 40 and row <= 620:   # the face, left of its foot, in the image
            assert changed[row, int(foot) - 30:int(foot) - 8].all()
    # the top edge is the brightest part of the face (bright edge beside the line)
    row = 560
    cols = np.flatnonzero(changed[row])
    grey = a[:, cols[-1] - 10].mean(axis=1)
    face_rows = np.flatnonzero(changed[:, cols[-1] - 10])
    assert grey[face_rows].argmax() + face_rows[0] < face_rows.mean()


def test_glare_raises_the_floor_and_sheen_brightens_the_road_ahead(grid):
    scene = Scene(CurvatureProfile(), Layout(3.7), PLAIN, seed=9)
    pose = CarPose(10.0)
    base = Renderer(scene, grid).render(pose).astype(np.float64)
    glare = Renderer(replace(scene, look=replace(PLAIN, glare=60.0)), grid).render(pose).astype(np.float64)
    wet = Renderer(replace(scene, look=replace(PLAIN, wet=100.0)), grid).render(pose).astype(np.float64)
    diff = (glare - base).mean(axis=2)
    assert np.median(diff[600:680]) > 4.0              # the veil everywhere (a tenth of it, times the vignette)
    assert diff[:400].max() > diff[600:680].mean() + 30   # and much more round the sun
    sheen = (wet - base).mean(axis=2)[:690]
    # brightest where the sun's mirror image lies: the road point seen 8 deg below the horizon
    cam = grid.camera
    z = cam.height_m / np.tan(np.radians(8.0))
    row = cam.project(np.array([[0.0, 0.0, z]]))[0, 1]
    assert int(np.argmax(sheen[:, 600:680].mean(axis=1))) == pytest.approx(row, abs=25)
    assert sheen[:, 600:680].mean(axis=1).max() > 60


def test_exposure_step_scales_the_frame(grid):
    scene = Scene(CurvatureProfile(), Layout(3.7), PLAIN, seed=10)
    pose = CarPose(10.0)
    base = Renderer(scene, grid).render(pose).astype(np.float64)
    step = Renderer(replace(scene, look=replace(PLAIN, exposure_steps_m=((5.0, 0.5), (50.0, 2.0)))),
                    grid).render(pose).astype(np.float64)
    assert step[500:680].mean() == pytest.approx(0.5 * base[500:680].mean(), rel=0.03)


def test_heights_integrate_the_grade():
    s = np.arange(-10.0, 100.0, 0.05)
    h = heights(((0.0, 0.0), (20.0, 0.0), (40.0, 0.1)), s)
    assert h[np.searchsorted(s, 0.0)] == pytest.approx(0.0, abs=1e-9)
    assert np.interp(40.0, s, h) == pytest.approx(1.0, abs=1e-6)        # ramp: 20 m at 5 % mean
    assert np.interp(90.0, s, h) == pytest.approx(6.0, abs=1e-6)        # then 10 %


def test_pitched_truth_is_the_projection_of_the_line_on_the_drawn_surface(grid):
    grades = ((0.0, 0.0), (20.0, 0.0), (45.0, 0.08))
    scene = Scene(CurvatureProfile(), Layout(3.7), PLAIN, seed=11, grades=grades)
    r = Renderer(scene, grid)
    pose = CarPose(10.0, 0.1)
    lane = lane_truth(r, pose)
    flat = lane_truth(Renderer(replace(scene, grades=()), grid), pose)
    cam = grid.camera
    z_grid, above = r.heights_ahead(pose)
    # the known answer: a straight road, so the line is x = -1.85 - 0.1 at height H(z) (the road's
    # height integrated from the grades, seen from the pitched car); project it densely
    s = np.arange(-20.0, 300.0, 0.05)
    h = heights(grades, s)
    assert np.interp(50.0, z_grid, above) == pytest.approx(
        np.interp(60.0, s, h) - np.interp(10.0, s, h), abs=1e-3)     # the car stands on the flat part
    z = np.arange(3.0, 100.0, 0.01)
    uv = cam.project(np.column_stack([np.full_like(z, -1.95), -np.interp(z, z_grid, above), z]))
    checked = 0
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE:
            continue
        assert uv[-1, 1] < row < uv[0, 1]                      # rows fall monotonically here
        assert x == pytest.approx(np.interp(row, uv[::-1, 1], uv[::-1, 0]), abs=0.05)
        checked += 1
    assert checked >= 20
    # the climbing road is seen higher: the truth lines reach rows above the flat road's
    rows = np.asarray(lane.h_samples_px)
    seen = rows[np.asarray(lane.left_x_px) != NOT_VISIBLE]
    seen_flat = rows[np.asarray(flat.left_x_px) != NOT_VISIBLE]
    assert seen.min() <= seen_flat.min()
    # and the rendered yellow line lies on the truth
    y = yellowness(r.render(pose))
    errors = []
    for row, x in zip(lane.h_samples_px, lane.left_x_px):
        if x == NOT_VISIBLE or row > 690:
            continue
        lo = int(round(x)) - 8
        profile = np.clip(y[row, lo:lo + 17] - 30, 0, None)
        if profile.sum() > 0:
            errors.append((profile * np.arange(lo, lo + 17)).sum() / profile.sum() - x)
    assert len(errors) >= 15 and np.abs(errors).max() < 1.0


def test_new_scenes_and_sets_are_registered_with_fixed_seeds():
    names = [item.name for item in image_scenes()]
    assert names[:8] == ["straight_1", "straight_2", "curve_left_600m", "curve_right_1000m", "curve_left_250m",
                         "curve_right_400m_shadows", "concrete_light", "seams_curve_left_1200m"]
    assert len(hard_scenes()) == 6 and len(set(names)) == len(names)
    sets = hard_video_sets()
    assert set(sets) == {"shadows", "seams", "glare", "country"}
    assert len({s.seed for s in sets.values()}) == 4


@pytest.mark.parametrize("name", ["shadows", "seams", "glare", "country"])
def test_bundled_hard_clips_have_truth_for_every_frame(name):
    truth = load_video_truth(REPO / "videos" / f"{name}.mp4")
    assert truth.fps == 25 and len(truth.frames) == 250
    if name == "country":
        radii = [f.radius_m for f in truth.frames]
        assert 30 <= min(radii) <= 40 and all(f.lane_width_m == 3.4 for f in truth.frames)


def test_bundled_hard_stills_carry_their_truth():
    for item in hard_scenes():
        assert item.folder == "hard"
        lane = load_image_truth(REPO / "test_images" / "hard" / f"{item.name}.jpg").lane
        assert lane.lane_width_m == item.scene.layout.lane_width_m
        assert sum(x != NOT_VISIBLE for x in lane.left_x_px) >= 8
