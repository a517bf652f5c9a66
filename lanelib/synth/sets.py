"""The bundled synthetic data: eight test scenes, three video sets and the calibration boards.

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
from ..io import VideoWriter, write_image, write_json
from .camera import Camera
from .chessboard import (PATTERN_SIZE, board_corners_px, board_poses, camera_normals, fully_visible,
                         render_board)
from .render import LOOK_AHEAD_M, GroundGrid, Renderer
from .road import CarPose, CurvatureProfile
from .scene import Bridge, Layout, Look, Scene, Streak
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

SUNNY = Look(tree_shadows_per_100m=0.6, patches_per_100m=1.0)


@dataclass(frozen=True)
class ImageScene:
    """One bundled test image: its scene and where the car stands."""

    name: str
    scene: Scene
    pose: CarPose


def _arc(radius_m: float) -> CurvatureProfile:
    """Return a constant-curvature profile (positive radius: right; 0: straight)."""
    return CurvatureProfile(((0.0, 0.0 if radius_m == 0 else 1.0 / radius_m),))


def image_scenes() -> tuple[ImageScene, ...]:
    """Return the eight bundled test scenes: straights, curves both ways, shadows, concrete, seams."""
    seams = (Streak(0.45, 0.05, 0.65, 0.04), Streak(-0.7, 0.015, 0.45, 0.08))
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

    def scene(self, seed: int) -> Scene:
        """Return the scene for up to MAX_VIDEO_SECONDS of driving, drawn from ``seed``.

        Its length does not depend on the clip's, so a short clip shows the first frames of a long one.
        """
        end = self.start_m + self.speed_mps * MAX_VIDEO_SECONDS + LOOK_AHEAD_M + 20.0
        return Scene(self.profile, self.layout, self.look, -20.0, end, seed)

    def pose(self, time_s: float) -> CarPose:
        """Return the car's pose at ``time_s``."""
        phases = [(a, 2 * math.pi / p, 2 * math.pi * time_s / p + k) for k, (a, p) in enumerate(self.drift)]
        offset = sum(a * math.sin(x) for a, _, x in phases)
        rate = sum(a * w * math.cos(x) for a, w, x in phases)
        return CarPose(self.start_m + self.speed_mps * time_s, offset, math.atan2(rate, self.speed_mps))


def video_sets() -> dict[str, VideoSet]:
    """Return the three video sets: ``project``, ``challenge`` and ``harder``."""
    clothoid = CurvatureProfile.from_segments
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
    with VideoWriter(path, FPS, threads=VIDEO_THREADS) as out:
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

def write_test_images(out_dir: str | os.PathLike, grid: GroundGrid | None = None) -> list[Path]:
    """Write the eight test images (JPEG) with their JSON truth into ``out_dir``; return the image paths."""
    grid = grid or GroundGrid.build()
    cam = camera_truth(grid.camera)
    paths = []
    for item in image_scenes():
        renderer = Renderer(item.scene, grid)
        path = write_image(Path(out_dir) / f"{item.name}.jpg", renderer.render(item.pose), IMAGE_JPEG_QUALITY)
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
    say("test_images: 8 scenes")
    files += write_test_images(root / "test_images", grid)
    for name, video_set in video_sets().items():
        say(f"videos/{name}.mp4: {VIDEO_SECONDS:.0f} s")
        files.append(write_video(root / "videos" / f"{name}.mp4", video_set, grid=grid))
    return files
