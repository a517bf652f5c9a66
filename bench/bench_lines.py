"""Milliseconds per 1280x720 frame of ``LanePipeline.detect`` (the ego pair) and ``detect_lines``
(every line in view: the ego pair, then the lines view), on one OpenCV thread.

The frames are a synthetic TuSimple-layout sample rendered first (``synth.datasets``, seed 0,
``--frames`` images of its first sequences), each with the true bird's-eye geometry of its camera
(``synth.truth.perspective_truth``), so no third-party data and no geometry estimate is needed;
the lines view's maps are made before timing (once per camera, as ``predict`` does). Printed per
path: the median and 90th percentile of the wall time and the median CPU time of the process
(a fairer figure on a busy machine), and the lines found per frame. TuSimple scores a frame whose
prediction took over 200 ms as missed.

    .venv/bin/python bench/bench_lines.py [--frames 20]
"""
from __future__ import annotations

import argparse
import re
import statistics
import tempfile
import time
from dataclasses import replace

import cv2

from lanelib import io
from lanelib.config import PipelineConfig
from lanelib.pipeline import LanePipeline
from lanelib.synth import datasets
from lanelib.synth.truth import perspective_truth


def load_frames(n: int) -> list[tuple[LanePipeline, object]]:
    """Return (pipeline of its camera, frame) for ``n`` rendered TuSimple-layout frames."""
    out, pipes = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        written = datasets.write_dataset("tusimple", tmp, n, seed=0)
        for path in written.images:
            k = int(re.search(r"synth(\d+)", str(path)).group(1)) - 1
            if k not in pipes:
                d = datasets.TUSIMPLE_DESIGNS[k % len(datasets.TUSIMPLE_DESIGNS)]
                truth = perspective_truth(d.camera(datasets.TUSIMPLE_SIZE), d.lane_width_m)
                pipes[k] = LanePipeline(replace(PipelineConfig(), perspective=truth.config()))
                pipes[k].lines_view()
            out.append((pipes[k], io.read_image(path)))
    return out


def time_per_frame(fn, frames) -> tuple[list[float], list[float], list]:
    """Return the wall and CPU milliseconds of ``fn(pipeline, frame)`` per frame, and its results."""
    for pipe, frame in frames[:3]:
        fn(pipe, frame)  # warm-up: caches, allocations
    wall, cpu, results = [], [], []
    for pipe, frame in frames:
        w0, c0 = time.perf_counter(), time.process_time()
        results.append(fn(pipe, frame))
        wall.append((time.perf_counter() - w0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    return wall, cpu, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20, help="frames to render and time (default: 20)")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    frames = load_frames(args.frames)
    print(f"{len(frames)} synthetic TuSimple-layout frames 1280x720 (seed 0); OpenCV {cv2.__version__}, 1 thread")
    paths = {"detect (ego pair)": lambda p, f: p.detect(f),
             "detect_lines (every line)": lambda p, f: p.detect_lines(f),
             "detect_lines, no ego (predict)": lambda p, f: p.detect_lines(f, ego=False)}
    for name, fn in paths.items():
        wall, cpu, results = time_per_frame(fn, frames)
        p90 = statistics.quantiles(wall, n=10)[-1]
        found = [len(r.lines) if hasattr(r, "lines") else int(r.left.found) + int(r.right.found) for r in results]
        print(f"  {name:31s} median {statistics.median(wall):6.1f} ms  p90 {p90:6.1f} ms  "
              f"cpu median {statistics.median(cpu):6.1f} ms  lines/frame {statistics.mean(found):.1f}")


if __name__ == "__main__":
    main()
