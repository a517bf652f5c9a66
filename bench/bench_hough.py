"""Milliseconds per 960x540 frame of the basic Hough lane-line path, on one OpenCV thread.

Two figures: ``HoughLaneFinder.process`` (colour selection, blur, Canny, region of interest,
Hough, the two fits) and the video path without decoding or encoding (``HoughTracker.process``
and ``annotate``). The frames are the first ``--frames`` of the Udacity P1 clip
solidWhiteRight.mp4 when the data is present (LANELIB_DATA, default ../shared/data), else one
synthetic frame with two painted lines; they are decoded before timing. Printed per path: the
median and 90th percentile of the wall time and the median CPU time of the process (a fairer
figure on a busy machine).

    .venv/bin/python bench/bench_hough.py [--frames 200] [--video PATH]
"""
from __future__ import annotations

import argparse
import itertools
import statistics
import time
from pathlib import Path

import cv2
import numpy as np

from lanelib import data, hough, io

def default_video() -> Path:
    """Return where solidWhiteRight.mp4 is expected (``lanelib.data``: LANELIB_DATA or ../shared/data)."""
    return data.data_root() / data.UDACITY_P1 / "test_videos" / "solidWhiteRight.mp4"


def synthetic_frame() -> np.ndarray:
    """Return a 960x540 dark road with a yellow left and a white right line."""
    rgb = np.full((540, 960, 3), 70, np.uint8)
    cv2.line(rgb, (180, 539), (450, 330), (240, 200, 20), 12, cv2.LINE_AA)
    cv2.line(rgb, (860, 539), (520, 330), (255, 255, 255), 12, cv2.LINE_AA)
    return rgb


def load_frames(video: Path, n: int) -> tuple[list[np.ndarray], str]:
    """Return up to ``n`` decoded frames of ``video`` (or ``n`` synthetic ones) and their source."""
    if video.is_file():
        with io.VideoReader(video) as reader:
            return [f.copy() for f in itertools.islice(reader, n)], video.name
    return [synthetic_frame()] * n, "synthetic frame (no video found at " + str(video) + ")"


def time_per_frame(fn, frames: list[np.ndarray]) -> tuple[list[float], list[float]]:
    """Return the wall and CPU milliseconds of ``fn(frame)`` for each frame."""
    for frame in frames[:10]:
        fn(frame)  # warm-up: caches, allocations
    wall, cpu = [], []
    for frame in frames:
        w0, c0 = time.perf_counter(), time.process_time()
        fn(frame)
        wall.append((time.perf_counter() - w0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200, help="frames to time (default: 200)")
    parser.add_argument("--video", type=Path, default=None,
                        help="960x540 clip (default: solidWhiteRight.mp4 of the P1 data)")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    frames, source = load_frames(args.video or default_video(), args.frames)
    h, w = frames[0].shape[:2]
    finder, tracker = hough.HoughLaneFinder(), hough.HoughTracker()
    paths = {"HoughLaneFinder.process": finder.process,
             "HoughTracker.process + annotate": lambda f: hough.annotate(f, tracker.process(f))}
    print(f"{len(frames)} frames {w}x{h} from {source}; OpenCV {cv2.__version__}, 1 thread")
    for name, fn in paths.items():
        wall, cpu = time_per_frame(fn, frames)
        p90 = statistics.quantiles(wall, n=10)[-1]
        print(f"  {name:32s} median {statistics.median(wall):6.2f} ms  p90 {p90:6.2f} ms  "
              f"cpu median {statistics.median(cpu):6.2f} ms  ({1e3 / statistics.median(wall):.0f} fps)")


if __name__ == "__main__":
    main()
