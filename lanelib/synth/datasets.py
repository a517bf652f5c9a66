"""Synthetic samples in the TuSimple and CULane layouts, with exact labels (issue 17, point 5).

``write_dataset("tusimple" | "culane", out_dir, frames)`` renders ``frames`` labelled images in a
benchmark's own layout, so that ``predict``, ``evaluate`` and their tests need no third-party data:

- TuSimple: ``clips/<sequence>/<clip>/20.jpg`` (1280 x 720) and one ``label_data_<sequence>.json``
  per sequence, each image's lanes at ``benchmarks.tusimple.H_SAMPLES_PX`` (rows 160..710, -2
  where a line has no point): every painted line of the road that is in view, left to right,
  the neighbour lanes' lines included (up to 5 on the widest road);
- CULane: ``driver_9<k>_30frame/synth_<k>.MP4/<frame>.jpg`` (1640 x 590) with ``<frame>.lines.txt``
  beside each (points ``x y`` bottom up at ``benchmarks.culane.SAMPLE_ROWS_PX``) and
  ``list/test.txt``: at most 4 lines, the two nearest the car on each side, as CULane labels.

The labels are the generator's truth (``truth.lines_truth``, to ``LABEL_RANGE_M`` ahead), so they
match the rendered paint by construction: the centre of each painted line in the raw image,
through the dash gaps, hidden outside the image and under the hood.

A sample is a few sequences (folders), each one camera on one road: ``FRAMES_PER_SEQUENCE``
frames ``FRAME_SPACING_S`` apart (the car changes lanes between them), as the benchmarks' labelled
frames are seconds apart. The cameras differ from sequence to sequence (height, pitch, yaw, roll),
so the geometry must be found per sequence. Everything is drawn from ``seed``: the same bytes on
one machine (``sets`` says what may differ on another CPU).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from ..benchmarks import culane, tusimple
from ..errors import InputError
from ..io import write_image
from .camera import Camera
from .render import LOOK_AHEAD_M, LOOK_BEHIND_M, GroundGrid, Renderer
from .road import CarPose, CurvatureProfile
from .scene import Layout, Look, Scene
from .sets import IMAGE_JPEG_QUALITY, SUNNY
from .truth import NOT_VISIBLE, lines_truth

BENCHMARKS = ("tusimple", "culane")
FRAMES_PER_SEQUENCE = 10
FRAME_SPACING_S = 1.5      # between two labelled frames of a sequence
LABEL_RANGE_M = 180.0      # lines are labelled this far ahead (detailed road ends at 200 m)
CULANE_MAX_LINES = 4       # CULane labels the ego lane's lines and the neighbours' outer ones
CULANE_FPS = 30            # CULane frame names count the video's frames
MIN_POINTS = 2             # a line with fewer visible points is not labelled
START_M = 15.0             # where the car stands on a sequence's first frame


@dataclass(frozen=True)
class SequenceDesign:
    """One sequence's camera and road: mounting, lanes, look, bends and speed.

    ``lanes`` is the number of lanes (the car drives in any of them); the camera's horizontal
    field of view is ``hfov_deg`` at the benchmark's image size.
    """

    hfov_deg: float
    height_m: float
    pitch_deg: float
    yaw_deg: float
    roll_deg: float
    lanes: int
    lane_width_m: float
    look: Look
    profile: CurvatureProfile
    speed_mps: float = 27.0

    def camera(self, size_px: tuple[int, int]) -> Camera:
        """Return the sequence's pinhole camera for images of ``size_px``."""
        return Camera.pinhole(size_px, hfov_deg=self.hfov_deg, height_m=self.height_m,
                              pitch_deg=self.pitch_deg, yaw_deg=self.yaw_deg, roll_deg=self.roll_deg)

    def layout(self) -> Layout:
        """Return the road: ``lanes`` lanes, the yellow line on the left, a white edge on the right."""
        return Layout(self.lane_width_m, right_lanes=self.lanes - 1, left_shoulder_m=3.0)


_BENDS = CurvatureProfile.from_segments
# highways: straights (the geometry is estimated there) and gentle bends of 700 m to 2 km
_ROADS = (
    _BENDS(0.0, ((90, 0.0), (60, 1 / 1500), (150, 1 / 1500), (60, 0.0), (120, 0.0), (60, -1 / 900),
                 (120, -1 / 900), (60, 0.0), (400, 0.0))),
    _BENDS(0.0, ((140, 0.0), (80, -1 / 2000), (100, -1 / 2000), (80, 0.0), (150, 0.0), (60, 1 / 700),
                 (80, 1 / 700), (60, 0.0), (400, 0.0))),
    _BENDS(0.0, ((60, 0.0), (60, 1 / 1200), (60, 1 / 1200), (60, 0.0), (200, 0.0), (80, -1 / 1800),
                 (160, -1 / 1800), (80, 0.0), (400, 0.0))),
)
_LOOKS = (SUNNY, replace(SUNNY, paint_wear=0.3, tree_shadows_per_100m=2.0), Look(),
          replace(SUNNY, asphalt_grey=110.0, white_grey=205.0, patches_per_100m=2.5))

# TuSimple: 1280 x 720, the horizon near row 300 (the camera pitched down about 3 degrees)
TUSIMPLE_SIZE = (1280, 720)
TUSIMPLE_DESIGNS = (
    SequenceDesign(60.0, 1.60, 3.0, 0.5, 0.0, 3, 3.7, _LOOKS[0], _ROADS[0]),
    SequenceDesign(58.0, 1.50, 2.4, -1.0, 0.4, 4, 3.6, _LOOKS[1], _ROADS[1]),
    SequenceDesign(62.0, 1.70, 3.5, 1.2, 0.0, 3, 3.75, _LOOKS[2], _ROADS[2], speed_mps=24.0),
    SequenceDesign(60.0, 1.55, 2.8, 0.0, -0.5, 4, 3.7, _LOOKS[3], _ROADS[0], speed_mps=30.0),
)
# CULane: 1640 x 590, a wide lens, the horizon near row 265
CULANE_SIZE = (1640, 590)
CULANE_DESIGNS = (
    SequenceDesign(72.0, 1.45, 1.5, 0.0, 0.0, 3, 3.6, _LOOKS[0], _ROADS[1]),
    SequenceDesign(70.0, 1.55, 1.2, 1.0, 0.5, 4, 3.75, _LOOKS[1], _ROADS[2]),
    SequenceDesign(74.0, 1.40, 1.8, -0.8, 0.0, 3, 3.5, _LOOKS[2], _ROADS[0], speed_mps=22.0),
    SequenceDesign(72.0, 1.50, 1.4, 0.5, -0.4, 4, 3.7, _LOOKS[3], _ROADS[1], speed_mps=30.0),
)


@dataclass(frozen=True)
class WrittenDataset:
    """What ``write_dataset`` wrote: the images (in order), the label and list files, the sequences."""

    benchmark: str
    root: Path
    images: tuple[Path, ...]
    label_files: tuple[Path, ...]
    sequences: tuple[str, ...]
    lines: int  # labelled lines over all images


def sequence_sizes(frames: int, per_sequence: int = FRAMES_PER_SEQUENCE) -> list[int]:
    """Return how many frames each sequence gets: ``frames`` split as evenly as possible into
    ceil(frames / per_sequence) sequences."""
    n = math.ceil(frames / per_sequence)
    return [frames // n + (1 if k < frames % n else 0) for k in range(n)]


def _poses(design: SequenceDesign, count: int, rng: np.random.Generator) -> list[CarPose]:
    """Return the car's poses: ``FRAME_SPACING_S`` apart, in a random lane, a little off its centre."""
    poses = []
    for i in range(count):
        lane = int(rng.integers(design.lanes))
        offset = lane * design.lane_width_m + float(rng.uniform(-0.35, 0.35))
        heading = float(rng.uniform(-0.012, 0.012))
        poses.append(CarPose(START_M + i * FRAME_SPACING_S * design.speed_mps, offset, heading))
    return poses


def _visible(xs: tuple[float, ...]) -> int:
    return sum(x != NOT_VISIBLE for x in xs)


def culane_lines(lines: tuple[tuple[float, tuple[float, ...]], ...], car_t_m: float,
                 rows_px: tuple[int, ...]) -> list[np.ndarray]:
    """Return the CULane labels of one image from ``truth.lines_truth``: the (up to) two lines
    nearest the car on each side that show at least ``MIN_POINTS`` points, left to right, each
    an (n, 2) array of x, y (px) bottom up."""
    left = [xs for t, xs in lines if t < car_t_m][-CULANE_MAX_LINES // 2:]
    right = [xs for t, xs in lines if t >= car_t_m][:CULANE_MAX_LINES // 2]
    out = []
    for xs in left + right:
        pts = [(x, y) for x, y in zip(xs, rows_px) if x != NOT_VISIBLE]
        if len(pts) >= MIN_POINTS:
            out.append(np.asarray(pts, np.float64))
    return out


def write_dataset(benchmark: str, out_dir: str | os.PathLike, frames: int, seed: int = 0,
                  per_sequence: int = FRAMES_PER_SEQUENCE,
                  progress: Callable[[int, int], None] | None = None) -> WrittenDataset:
    """Render ``frames`` labelled images in the layout of ``benchmark`` under ``out_dir``.

    Parameters
    ----------
    benchmark : "tusimple" or "culane" (see the module docstring for the layouts).
    out_dir : the dataset root to write (files of the same names are replaced).
    frames : how many labelled images, 1 or more.
    seed : draws the sequences' scenes and the car's lanes and poses (0: the default sample).
    per_sequence : frames per sequence at most; ceil(frames / per_sequence) sequences share
        them evenly, sequence k on ``*_DESIGNS[k % 4]``.
    progress : called as ``progress(done, total)`` after every image.
    """
    if benchmark not in BENCHMARKS:
        raise InputError(f"{benchmark!r}: not a benchmark layout; choose one of {', '.join(BENCHMARKS)}")
    if frames < 1:
        raise InputError(f"--frames {frames}: give 1 frame or more")
    if per_sequence < 1:
        raise InputError(f"per_sequence {per_sequence}: give 1 frame or more per sequence")
    tusimple_layout = benchmark == "tusimple"
    designs, size = (TUSIMPLE_DESIGNS, TUSIMPLE_SIZE) if tusimple_layout else (CULANE_DESIGNS, CULANE_SIZE)
    rows = tusimple.H_SAMPLES_PX if tusimple_layout else culane.SAMPLE_ROWS_PX
    root = Path(out_dir)
    images, label_files, sequences, entries = [], [], [], []
    total_lines = 0
    for k, count in enumerate(sequence_sizes(frames, per_sequence)):
        design = designs[k % len(designs)]
        rng = np.random.default_rng([seed, k])
        end_m = START_M + (count - 1) * FRAME_SPACING_S * design.speed_mps + LOOK_AHEAD_M + 20.0
        scene = Scene(design.profile, design.layout(), design.look, -LOOK_BEHIND_M - 10.0, end_m,
                      seed=int(rng.integers(2 ** 31)))
        renderer = Renderer(scene, GroundGrid.build(design.camera(size)))
        records, labels = [], {}
        for i, pose in enumerate(_poses(design, count, rng)):
            image = renderer.render(pose, noise_key=i)
            lines = lines_truth(renderer, pose, rows, LABEL_RANGE_M)
            if tusimple_layout:
                sequence = f"synth{k + 1:02d}"
                raw_file = f"clips/{sequence}/{i + 1:04d}/20.jpg"
                lanes = tuple(xs for _, xs in lines if _visible(xs) >= MIN_POINTS)
                records.append(tusimple.TuSimpleRecord(raw_file, lanes, tuple(float(r) for r in rows)))
                path = root / raw_file
                total_lines += len(lanes)
            else:
                sequence = f"driver_9{k}_30frame/synth_{k + 1:04d}.MP4"
                entry = f"/{sequence}/{round(i * FRAME_SPACING_S * CULANE_FPS):05d}.jpg"
                labels[entry] = culane_lines(lines, pose.offset_m, rows)
                entries.append(entry)
                path = root / entry.lstrip("/")
                total_lines += len(labels[entry])
            images.append(write_image(path, image, IMAGE_JPEG_QUALITY))
            if progress:
                progress(len(images), frames)
        sequences.append(sequence)
        if tusimple_layout:
            label_files.append(tusimple.write_labels(root / f"label_data_{sequence}.json", records))
        else:
            label_files += culane.write_labels(root, labels)
    if not tusimple_layout:
        label_files.append(culane.write_list(root / "list" / "test.txt", entries))
    return WrittenDataset(benchmark, root, tuple(images), tuple(label_files), tuple(sequences), total_lines)
