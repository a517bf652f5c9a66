"""Milliseconds of Python time per slider change of each tuner on a 1280x720 source.

A slider change is what happens in the kernel when the browser sends a new value: setting the
control's ``.value`` runs the ``observe`` callback, which rebuilds the config, recomputes what the
control affects and replaces the preview's JPEG bytes. Each control is moved back and forth
``--changes`` times; the median and the 90th percentile of the wall time, and the median CPU
time of the process (all of OpenCV's threads; a fairer figure on a busy machine), are printed
per control and per tuner. The issue's budget is 50 ms per change.

    .venv/bin/python bench/bench_widgets.py [--changes 50] [--image test_images/xxx.jpg]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from lanelib import data, io, widgets
from lanelib.errors import LaneLibError

# (tuner, control key, two values to alternate between)
MOVES = {
    widgets.ThresholdTuner: [("white.range1", (190, 255), (210, 255)),
                             ("lab_b.range", (150, 255), (160, 255)),
                             ("line_tophat.range", (30, 255), (40, 255)),
                             ("line_tophat.width_px", 61, 41),
                             ("sobel_x.range", (20.0, 255.0), (30.0, 255.0)),
                             ("yellow.enabled", False, True)],
    widgets.PerspectiveTuner: [("top_y", 470.0, 476.0),
                               ("top_width", 151.4, 140.0),
                               ("bottom_width", 894.0, 860.0),
                               ("centre_x", 640.0, 650.0),
                               ("dst_margin", 320.0, 300.0)],
    widgets.FitTuner: [("n_windows", 9, 12),
                       ("margin_px", 80, 100),
                       ("minpix", 50, 1000),
                       ("prior_margin_px", 60, 80)],
    widgets.HoughTuner: [("canny", (50, 150), (60, 170)),
                         ("threshold_votes", 25, 40),
                         ("min_line_length_px", 20, 60),
                         ("roi.top_y", 0.60, 0.64)],
}
# controls whose change may leave the preview's pixels as they were
MAY_NOT_CHANGE = {"yellow.enabled", "threshold_votes", "min_line_length_px"}


def pick_image(arg: str | None) -> dict[str, Path]:
    """Return {label: path} of one 1280x720 road image (the given one, else the first found)."""
    if arg:
        return {Path(arg).name: Path(arg)}
    try:
        choices = widgets.image_choices()
    except LaneLibError:
        choices = {}
        folder = data.udacity("test_images")
        if folder is not None:
            choices = {p.name: p for p in io.list_images(folder)}
    for label, path in choices.items():
        if io.read_image(path).shape[:2] == (720, 1280):
            return {label: path}
    sys.exit("no 1280x720 road image found: pass --image")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--changes", type=int, default=50, help="changes per control (default 50)")
    ap.add_argument("--image", help="a 1280x720 road image (default: the first bundled one)")
    args = ap.parse_args()
    images = pick_image(args.image)
    print(f"source: {next(iter(images.values()))} (1280x720), {args.changes} changes per control")
    print(f"{'tuner':<18}{'control':<24}{'median ms':>10}{'p90 ms':>9}{'CPU ms':>9}")
    for cls, moves in MOVES.items():
        tuner = cls(images)
        everything, all_cpu = [], []
        for key, a, b in moves:
            control = tuner.controls[key]
            times, cpu = [], []
            for i in range(args.changes):
                before = tuner.preview.value
                t0, c0 = time.perf_counter(), time.process_time()
                control.value = a if i % 2 else b
                times.append((time.perf_counter() - t0) * 1000)
                cpu.append((time.process_time() - c0) * 1000)
                if tuner.preview.value == before and key not in MAY_NOT_CHANGE:
                    sys.exit(f"{cls.__name__}.{key}: the preview did not change")
            everything += times
            all_cpu += cpu
            print(f"{cls.__name__:<18}{key:<24}{statistics.median(times):>10.1f}"
                  f"{np.percentile(times, 90):>9.1f}{statistics.median(cpu):>9.1f}")
        print(f"{cls.__name__:<18}{'(all controls)':<24}{statistics.median(everything):>10.1f}"
              f"{np.percentile(everything, 90):>9.1f}{statistics.median(all_cpu):>9.1f}")


if __name__ == "__main__":
    main()
