"""Frames per second of the synthetic road renderer at 1280x720, per video set.

Each set's scene is built once (maps, tables), then ``--frames`` frames along its drive are
rendered; the wall-clock figure is what a clip costs, the CPU figure (all of OpenCV's threads)
is fairer on a busy machine. ``--with-truth`` adds the ground truth of every frame. The issue's
budget is 10 frames/s, so that a 10 s clip renders in under a minute.

    .venv/bin/python bench/bench_synth.py [--frames 100] [--with-truth]
"""
from __future__ import annotations

import argparse
import time

from lanelib.synth import GroundGrid, Renderer, lane_truth, video_sets
from lanelib.synth.sets import FPS


def main() -> None:
    """Print render frames/s (wall and CPU) for every video set."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100, help="frames per set (default: 100)")
    ap.add_argument("--with-truth", action="store_true", help="also compute every frame's truth")
    args = ap.parse_args()
    t0 = time.perf_counter()
    grid = GroundGrid.build()
    print(f"camera grid built in {time.perf_counter() - t0:.2f} s")
    for name, video_set in video_sets().items():
        t0 = time.perf_counter()
        renderer = Renderer(video_set.scene(video_set.seed), grid)
        setup = time.perf_counter() - t0
        renderer.render(video_set.pose(0.0))  # warm up
        wall, cpu = time.perf_counter(), time.process_time()
        for i in range(args.frames):
            pose = video_set.pose(i / FPS)
            renderer.render(pose, noise_key=i)
            if args.with_truth:
                lane_truth(renderer, pose)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        print(f"{name:10s} scene set-up {setup:5.2f} s   {args.frames / wall:5.1f} frames/s wall   "
              f"{1e3 * cpu / args.frames:5.1f} ms CPU per frame")


if __name__ == "__main__":
    main()
