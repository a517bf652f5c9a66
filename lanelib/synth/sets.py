"""The bundled synthetic data: fourteen test scenes, seven video sets and the calibration boards.

The first eight scenes and three sets (``project``, ``challenge``, ``harder``) are the original
ones; the rest reproduce the failure classes of hard roads (issue 16): overpass and tree shadows
with exposure jumps, paint missing for 20-40 m, tar seams, sealant and repaved strips beside the
lines, a concrete barrier's bright edge beside the left line, low sun with glare and a wet sheen,
and a two-lane country road with hairpins, a double yellow centre line, a guard rail and grades.

Every item has a fixed seed, so ``generate_all`` writes the same bytes on every run on one machine
(JPEG through libjpeg, H.264 through x264 with one thread: frame threading would make the bytes
depend on the machine's core count). On another CPU the truth is the same and a few pixels may
differ by one grey level: numpy's SIMD kernels (exp, sin) may round a float's last bit differently.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import InputError
from ..batch.video import H264_PARAMS, VideoWriter
from ..io import write_image, write_json
from .camera import Camera
from .chessboard import (PATTERN_SIZE, board_corners_px, board_poses, camera_normals, fully_visible,
                         render_board)
from .render import LOOK_AHEAD_M, GroundGrid, Renderer
from .road import CarPose, CurvatureProfile
from .scene import Barrier, Bridge, Layout, Line, Look, Scene, Streak
from .truth import camera_truth, lane_truth, write_image_truth, write_video_truth

IMAGE_JPEG_QUALITY = 90
BOARD_JPEG_QUALITY = 92
BOARD_SEED = 7
FPS = 25.0
VIDEO_SECONDS = 10.0
MAX_VIDEO_SECONDS = 20.0   # every set's road is drawn this long, so a shorter clip is a prefix
VIDEO_THREADS = 1          # x264 threads; more make the bytes depend on the machine
EXPOSURE_TARGET = 112.0    # auto exposure: mean grey of the road area it aims at
EXPOSURE_RATE = 0.12       # share of the log-error corrected per frame
EXPOSURE_LIMITS = (0.35, 3.0)
METER_ROWS = slice(440, 680)   # at 720 rows; in proportion for other heights (meter_rows)
H264_CRF = 20      # x264 quality of the original sets (lanelib.io's default)
HARD_CRF = 23      # of the hard-road sets: keeps the bundled data under 25 MB

SUNNY = Look(tree_shadows_per_100m=0.6, patches_per_100m=1.0)
# hard light: deep, sharp shadows
HARSH = replace(SUNNY, sun=1.8, ambient=0.22, tree_shadows_per_100m=6.0)
# low sun ahead: glare, a wet sheen, washed-out paint, pale sky
LOW_SUN = Look(asphalt_grey=84.0, white_grey=178.0, yellow_rgb=(205, 180, 110), paint_wear=0.4,
               patches_per_100m=1.0, sun=1.3, ambient=0.3, sun_azimuth_deg=4.0, sun_elevation_deg=7.0,
               glare=65.0, wet=110.0, haze_m=380.0, haze_rgb=(215, 212, 205), sky_top_rgb=(150, 170, 200),
               sky_horizon_rgb=(230, 225, 215))
# the seams of the ``seams`` set: a dark seam 0.35 m inside the left line, a light one 0.3 m inside
# the right, wandering crack sealant and a light seam in the next lane
SEAMS = (Streak(-1.45, 0.06, 0.6, 0.02), Streak(1.5, 0.05, -0.55, 0.02), Streak(0.7, 0.03, 0.75, 0.22),
         Streak(2.6, 0.06, -0.4, 0.03))


def country_layout(lane_width_m: float, right_line: bool = True) -> Layout:
    """Return a two-lane country road: the ego lane right of a double yellow centre line (the inner
    stripe is its left line), the oncoming lane beyond it with a white edge line, and on the right
    a white edge line 0.35 m inside the asphalt edge (``right_line``) or only the asphalt edge."""
    line, gap = 0.12, 0.10
    far_edge = -lane_width_m / 2 - line - gap - lane_width_m
    return Layout(lane_width_m, right_lanes=0, left_shoulder_m=lane_width_m + line + gap + 0.35,
                  right_shoulder_m=0.35 if right_line else 0.0, line_width_m=line, centre_gap_m=gap,
                  right_line=right_line, extra_lines=(Line(far_edge, line, yellow=False),))


HARD_FOLDER = "hard"  # the failure classes' stills, below test_images/


@dataclass(frozen=True)
class ImageScene:
    """One bundled test image: its scene, where the car stands, and its subfolder of
    ``test_images/`` ('' for the folder itself; the failure classes of issue 16 live in
    ``hard/``, so the eight scenes every notebook and table reads stay as they were)."""

    name: str
    scene: Scene
    pose: CarPose
    folder: str = ""


def _arc(radius_m: float) -> CurvatureProfile:
    """Return a constant-curvature profile (positive radius: right; 0: straight)."""
    return CurvatureProfile(((0.0, 0.0 if radius_m == 0 else 1.0 / radius_m),))


def image_scenes() -> tuple[ImageScene, ...]:
    """Return the bundled test scenes: the eight original ones (straights, curves both ways,
    shadows, concrete, seams) and one per failure class of hard roads (issue 16)."""
    seams = (Streak(0.45, 0.05, 0.65, 0.04), Streak(-0.7, 0.015, 0.45, 0.08))
    return _original_scenes(seams) + hard_scenes()


def hard_scenes() -> tuple[ImageScene, ...]:
    """Return one still per failure class of hard roads (in ``test_images/hard/``); the car stands
    at s = 10 m on each."""
    return tuple(replace(item, folder=HARD_FOLDER) for item in (
        ImageScene("hard_overpass_shadows",      # (a) an overpass ahead, hard tree shadows, a dark exposure
                   Scene(_arc(-700), Layout(3.7),
                         replace(HARSH, tree_shadows_per_100m=10.0, bridges=(Bridge(24.0, 14.0),),
                                 exposure_steps_m=((0.0, 0.7),)), seed=111),
                   CarPose(10.0, 0.1)),
        ImageScene("hard_missing_paint",         # (e) both lines gone from 18 to 45 m ahead, worn elsewhere
                   Scene(_arc(900), Layout(3.6),
                         replace(SUNNY, paint_wear=0.45,
                                 paint_missing_m=((28.0, 55.0, -2.5, -1.2), (36.0, 62.0, 1.2, 2.5))),
                         seed=112),
                   CarPose(10.0, -0.2)),
        ImageScene("hard_seams_repaved",         # (b) seams and repaved-strip edges beside both lines
                   Scene(_arc(-1500), Layout(3.6),
                         replace(SUNNY, streaks=SEAMS, paint_wear=0.3,
                                 resurfaced=((-50.0, 400.0, -1.55, 1.4, 0.74), (-50.0, 400.0, 1.95, 5.3, 1.25))),
                         seed=113),
                   CarPose(10.0, 0.15)),
        ImageScene("hard_barrier_left",          # (f) a concrete barrier 0.6 m left of the yellow line
                   Scene(_arc(1200), Layout(3.7, left_shoulder_m=0.6),
                         replace(SUNNY, barriers=(Barrier(-2.45),)), seed=114),
                   CarPose(10.0, -0.1)),
        ImageScene("hard_low_sun_glare",         # (c) glare, a wet sheen ahead, washed-out paint
                   Scene(_arc(-900), Layout(3.7), LOW_SUN, seed=115), CarPose(10.0, 0.1)),
        ImageScene("hard_country_hairpin",       # (d) a 40 m left hairpin climbing at 8 %, asphalt edge only
                   Scene(_arc(-40), country_layout(4.6, right_line=False),
                         replace(SUNNY, tree_shadows_per_100m=8.0, paint_wear=0.25, grass_rgb=(96, 120, 60),
                                 barriers=(Barrier(2.3 + 0.6, 0.75, 0.45, 150.0, 205.0, 0.05),)),
                         seed=116, grades=((0.0, 0.0), (18.0, 0.0), (45.0, 0.07))),
                   CarPose(10.0, 0.2)),
    ))


def _original_scenes(seams: tuple[Streak, ...]) -> tuple[ImageScene, ...]:
    """Return the eight original test scenes (their bundled bytes never change)."""
    return (
        ImageScene("straight_1", Scene(_arc(0), Layout(3.7), SUNNY, seed=101), CarPose(10.0)),
        ImageScene("straight_2", Scene(_arc(0), Layout(3.6), replace(SUNNY, paint_wear=0.3, streaks=seams[:1],
                                                                    exposure=0.9), seed=102),
                  CarPose(10.0, -0.25, 0.004)),
        ImageScene("curve_left_600m", Scene(_arc(-600), Layout(3.7), SUNNY, seed=103), CarPose(10.0, 0.15)),
        ImageScene("curve_right_1000m", Scene(_arc(1000), Layout(3.8), SUNNY, seed=104), CarPose(10.0, -0.1)),
        ImageScene("curve_left_250m", Scene(_arc(-250), Layout(3.5), SUNNY, seed=105),
                   CarPose(10.0, 0.1, -0.01)),
        ImageScene("curve_right_400m_shadows",
                  Scene(_arc(400), Layout(3.7), replace(SUNNY, tree_shadows_per_100m=9.0), seed=106),
                  CarPose(10.0, 0.05)),
        ImageScene("concrete_light",
                  Scene(_arc(-2000), Layout(3.9), replace(SUNNY, concrete_m=((-50.0, 400.0),), paint_wear=0.2,
                                                          tree_shadows_per_100m=0.0), seed=107),
                  CarPose(10.0, 0.2)),
        ImageScene("seams_curve_left_1200m",
                  Scene(_arc(-1200), Layout(3.7), replace(SUNNY, streaks=seams, paint_wear=0.25,
                                                          resurfaced=((-50.0, 400.0, -2.0, 0.2, 0.82),)),
                        seed=108),
                  CarPose(10.0, -0.15, 0.003)),
    )


# --------------------------------------------------------------------------- videos

@dataclass(frozen=True)
class VideoSet:
    """A video set: the road, its look, the car's speed and its sideways drift within the lane.

    The car drives at about 25 m/s; on the ``harder`` set's mountain curves (radius down to
    45 m) at 18 m/s.

    ``drift`` is a list of (amplitude m, period s) sines added to the lateral offset; the heading
    follows from the drift (the car moves along its own heading).
    """

    name: str
    profile: CurvatureProfile
    layout: Layout
    look: Look
    speed_mps: float = 25.0
    drift: tuple[tuple[float, float], ...] = ((0.2, 7.0), (0.05, 2.3))
    seed: int = 1
    start_m: float = 15.0
    grades: tuple[tuple[float, float], ...] = ()
    crf: int = H264_CRF

    def scene(self, seed: int) -> Scene:
        """Return the scene for up to MAX_VIDEO_SECONDS of driving, drawn from ``seed``.

        Its length does not depend on the clip's, so a short clip shows the first frames of a long one.
        """
        end = self.start_m + self.speed_mps * MAX_VIDEO_SECONDS + LOOK_AHEAD_M + 20.0
        return Scene(self.profile, self.layout, self.look, -20.0, end, seed, self.grades)

    def pose(self, time_s: float) -> CarPose:
        """Return the car's pose at ``time_s``."""
        phases = [(a, 2 * math.pi / p, 2 * math.pi * time_s / p + k) for k, (a, p) in enumerate(self.drift)]
        offset = sum(a * math.sin(x) for a, _, x in phases)
        rate = sum(a * w * math.cos(x) for a, w, x in phases)
        return CarPose(self.start_m + self.speed_mps * time_s, offset, math.atan2(rate, self.speed_mps))


def video_sets() -> dict[str, VideoSet]:
    """Return the video sets: ``project``, ``challenge``, ``harder`` and the hard-road sets
    (``hard_video_sets``)."""
    clothoid = CurvatureProfile.from_segments
    return {**_original_sets(clothoid), **hard_video_sets()}


def hard_video_sets() -> dict[str, VideoSet]:
    """Return the hard-road sets (issue 16): ``shadows`` (a + e), ``seams`` (b + f), ``glare`` (c)
    and ``country`` (d)."""
    clothoid = CurvatureProfile.from_segments
    return {
        "shadows": VideoSet(
            "shadows",
            clothoid(0.0, ((40, 0.0), (40, 1 / 700), (80, 1 / 700), (40, 0.0), (30, 0.0), (50, -1 / 500),
                           (100, -1 / 500))),
            Layout(3.7),
            replace(HARSH, bridges=(Bridge(70.0, 14.0), Bridge(150.0, 18.0), Bridge(215.0, 10.0)),
                    tree_shadows_per_100m=7.0, sun=1.5, ambient=0.35,
                    light_m=((110.0, 135.0, 0.35),),
                    exposure_steps_m=((50.0, 1.35), (100.0, 0.75), (180.0, 1.3), (235.0, 0.8)),
                    paint_missing_m=((85.0, 120.0, -2.5, -1.2), (125.0, 150.0, 1.2, 2.5),
                                     (190.0, 225.0, -2.5, 2.5), (250.0, 275.0, 1.2, 2.5))),
            seed=11, crf=HARD_CRF),
        "seams": VideoSet(
            "seams",
            clothoid(0.0, ((30, 0.0), (60, -1 / 1200), (70, -1 / 1200), (50, 1 / 600), (120, 1 / 600))),
            Layout(3.6, left_shoulder_m=0.75),
            replace(SUNNY, streaks=SEAMS, paint_wear=0.35, patches_per_100m=2.0,
                    resurfaced=((-50.0, 130.0, -1.55, 1.4, 0.72), (130.0, 600.0, -1.55, 1.45, 1.3),
                                (60.0, 600.0, 1.95, 5.3, 1.22)),
                    barriers=(Barrier(-2.55, 0.81, s_from_m=-50.0, s_to_m=200.0),
                              Barrier(-2.5, 0.15, 0.0, 175.0, 230.0, 0.03, 200.0, 600.0))),
            drift=((0.3, 6.0), (0.06, 1.9)), seed=12, crf=HARD_CRF),
        "glare": VideoSet(
            "glare",
            clothoid(0.0, ((40, 0.0), (40, -1 / 800), (60, -1 / 800), (60, 1 / 900), (100, 1 / 900))),
            Layout(3.7), LOW_SUN, drift=((0.25, 5.0), (0.05, 2.1)), seed=13, crf=HARD_CRF),
        "country": VideoSet(
            "country",
            clothoid(0.0, ((10, 0.0), (15, 1 / 70), (20, 1 / 70), (15, -1 / 35), (45, -1 / 35), (20, 1 / 50),
                           (35, 1 / 50), (15, -1 / 80), (30, -1 / 80))),
            country_layout(3.4),
            replace(SUNNY, tree_shadows_per_100m=9.0, paint_wear=0.3, grass_rgb=(96, 120, 60),
                    patches_per_100m=2.5, sun=1.5, ambient=0.3,
                    paint_missing_m=((95.0, 130.0, 1.4, 2.2),),
                    barriers=(Barrier(2.05 + 0.5, 0.75, 0.45, 150.0, 205.0, 0.05),)),
            speed_mps=12.0, drift=((0.3, 4.0), (0.08, 1.9)), seed=14, crf=HARD_CRF,
            grades=((0.0, 0.0), (20.0, 0.0), (45.0, 0.09), (75.0, 0.09), (100.0, -0.03), (125.0, -0.03),
                    (150.0, 0.07))),
    }


def _original_sets(clothoid) -> dict[str, "VideoSet"]:
    """Return the three original video sets (their bundled bytes never change)."""
    return {
        "project": VideoSet(
            "project",
            clothoid(0.0, ((50, 0.0), (60, -1 / 900), (130, -1 / 900), (60, 0.0), (40, 0.0), (60, 1 / 1400))),
            Layout(3.7),
            replace(SUNNY, concrete_m=((150.0, 185.0),), tree_shadows_per_100m=1.2),
            seed=1),
        "challenge": VideoSet(
            "challenge",
            clothoid(0.0, ((80, 0.0), (80, -1 / 2500), (120, -1 / 2500), (80, 1 / 3000))),
            Layout(3.6),
            Look(asphalt_grey=118.0, asphalt_blotches=0.05, white_grey=200.0, yellow_rgb=(200, 178, 96),
                 paint_wear=0.45, patches_per_100m=3.0,
                 streaks=(Streak(0.6, 0.06, 0.7, 0.05), Streak(-0.35, 0.02, 0.5, 0.1),
                          Streak(2.1, 0.05, 0.6, 0.04)),
                 resurfaced=((-50.0, 600.0, -2.2, 0.45, 0.72),),
                 bridges=(Bridge(130.0, 16.0),), haze_m=450.0, sun=0.9, ambient=0.45,
                 sky_top_rgb=(120, 150, 190), sky_horizon_rgb=(190, 200, 210)),
            drift=((0.25, 6.0), (0.06, 1.7)), seed=2),
        "harder": VideoSet(
            "harder",
            clothoid(0.0, ((15, 0.0), (20, 1 / 60), (35, 1 / 60), (25, -1 / 80), (30, -1 / 80), (20, 1 / 45),
                           (25, 1 / 45), (25, -1 / 140), (40, -1 / 140), (20, 1 / 100))),
            Layout(3.5, right_lanes=1),
            Look(asphalt_grey=85.0, paint_wear=0.3, tree_shadows_per_100m=7.0, sun=1.5, ambient=0.3,
                 light_m=((30.0, 55.0, 0.25), (95.0, 120.0, 0.3), (160.0, 175.0, 0.2)),
                 grass_rgb=(96, 120, 60), patches_per_100m=2.0),
            speed_mps=18.0, drift=((0.75, 4.0), (0.12, 1.9)), seed=3),
    }


def meter_rows(height_px: int) -> slice:
    """Return the rows the auto exposure meters: METER_ROWS at 720 rows, the same share of others."""
    if height_px == 720:
        return METER_ROWS
    return slice(int(METER_ROWS.start * height_px / 720), int(METER_ROWS.stop * height_px / 720))


def _next_exposure(frame: np.ndarray, gain: float) -> float:
    """Return the auto-exposure gain for the next frame after ``frame`` was taken at ``gain``."""
    mean = float(frame[meter_rows(frame.shape[0])].mean()) + 1.0
    new = gain * (EXPOSURE_TARGET / mean) ** EXPOSURE_RATE
    return float(np.clip(new, *EXPOSURE_LIMITS))


class _ClipWriter(VideoWriter):
    """``batch.video.VideoWriter`` at another x264 quality (``crf``); at H264_CRF it is the same."""

    def __init__(self, path: str | os.PathLike, fps: float, threads: int | None, crf: int):
        super().__init__(path, fps, threads=threads)
        self._crf = crf

    def _start(self, size: tuple[int, int]) -> None:
        if self._crf == H264_CRF:
            super()._start(size)
            return
        saved = H264_PARAMS["output_params"]
        out = list(saved)
        out[out.index("-crf") + 1] = str(self._crf)
        try:  # VideoWriter._start reads batch.video.H264_PARAMS when the first frame comes
            H264_PARAMS["output_params"] = out
            super()._start(size)
        finally:
            H264_PARAMS["output_params"] = saved


def write_video(path: str | os.PathLike, video_set: VideoSet, seconds: float = VIDEO_SECONDS,
                seed: int | None = None, grid: GroundGrid | None = None,
                progress: Callable[[int, int], None] | None = None) -> Path:
    """Render ``seconds`` of ``video_set`` to an mp4 at ``path`` with its CSV/JSON truth; return the path.

    ``progress(done, total)`` is called after every frame.
    """
    if not 0 < seconds <= MAX_VIDEO_SECONDS:
        raise InputError(f"--seconds {seconds:g}: choose a length above 0 and up to {MAX_VIDEO_SECONDS:g} s")
    seed = video_set.seed if seed is None else seed
    grid = grid or GroundGrid.build()
    renderer = Renderer(video_set.scene(seed), grid)
    n = int(round(seconds * FPS))
    gain, lanes = video_set.look.exposure, []
    with _ClipWriter(path, FPS, threads=VIDEO_THREADS, crf=video_set.crf) as out:
        for i in range(n):
            pose = video_set.pose(i / FPS)
            frame = renderer.render(pose, gain, noise_key=i)
            out.write(frame)
            lanes.append(lane_truth(renderer, pose))
            gain = _next_exposure(frame, gain)
            if progress:
                progress(i + 1, n)
    extra = {"set": video_set.name, "speed_mps": video_set.speed_mps}
    write_video_truth(path, seed, FPS, lanes, camera_truth(grid.camera), extra)
    return Path(path)


# --------------------------------------------------------------------------- images and boards

def write_test_images(out_dir: str | os.PathLike, grid: GroundGrid | None = None,
                      names: tuple[str, ...] | None = None) -> list[Path]:
    """Write the test images (JPEG) with their JSON truth into ``out_dir``; return the image paths.

    ``names`` limits it to those scenes (default: all of ``image_scenes``).
    """
    grid = grid or GroundGrid.build()
    cam = camera_truth(grid.camera)
    paths = []
    for item in image_scenes():
        if names is not None and item.name not in names:
            continue
        renderer = Renderer(item.scene, grid)
        path = write_image(Path(out_dir) / item.folder / f"{item.name}.jpg", renderer.render(item.pose),
                           IMAGE_JPEG_QUALITY)
        write_image_truth(path, item.scene.seed, lane_truth(renderer, item.pose), cam)
        paths.append(path)
    return paths


def write_boards(out_dir: str | os.PathLike, seed: int = BOARD_SEED, camera: Camera = Camera()) -> list[Path]:
    """Write the 20 chessboard images and ``camera_truth.json`` into ``out_dir``; return the image paths."""
    rng = np.random.default_rng(seed)
    normals = camera_normals(camera)
    out, images = Path(out_dir), {}
    paths = []
    for k, board in enumerate(board_poses(camera, rng), start=1):
        path = write_image(out / f"calibration{k:02d}.jpg", render_board(camera, normals, board, rng),
                           BOARD_JPEG_QUALITY)
        corners = board_corners_px(camera, board)
        images[path.name] = {"fully_visible": fully_visible(camera, corners),
                             "corners_px": [[round(float(x), 4), round(float(y), 4)] for x, y in corners]}
        paths.append(path)
    write_json(out / "camera_truth.json", {
        "format": "lanelib-synth-camera-truth/1", "seed": seed,
        "camera_matrix": [list(r) for r in camera.camera_matrix], "dist_coeffs": list(camera.dist_coeffs),
        "image_size": list(camera.size_px), "pattern_size": list(PATTERN_SIZE),
        "corner_order": "row by row, x fastest: inner corner (i, j) at index j * 9 + i",
        "images": images})
    return paths


def generate_all(out_root: str | os.PathLike, progress: Callable[[str], None] | None = None) -> list[Path]:
    """Write ``camera_cal/``, ``test_images/`` and ``videos/`` under ``out_root``; return the data files."""
    root = Path(out_root)
    say = progress or (lambda _msg: None)
    grid = GroundGrid.build()
    say("camera_cal: 20 chessboards")
    files = write_boards(root / "camera_cal", camera=grid.camera)
    say(f"test_images: {len(image_scenes())} scenes")
    files += write_test_images(root / "test_images", grid)
    for name, video_set in video_sets().items():
        say(f"videos/{name}.mp4: {VIDEO_SECONDS:.0f} s")
        files.append(write_video(root / "videos" / f"{name}.mp4", video_set, grid=grid))
    return files
