"""Speed of the video path on every clip at hand: per-stage ms, detect_to_remap, video_to_codec.

Runs ``lanelib.bench.run`` (the figures of ``python -m lanelib bench``) on each 1280x720 or
960x540 clip that exists: the Udacity project video (with its calibration), the bundled
synthetic project video (with its true camera) and the Udacity P1 clip (with the ``p1`` preset),
and prints one report per clip, then a summary table. Nothing is asserted: speed is read, not
tested.

    .venv/bin/python bench/bench_video.py [--frames 250] [--json out.json]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lanelib import bench, data, io
from lanelib.config import PipelineConfig, preset
from lanelib.errors import LaneLibError
from lanelib.evaluate import calibration_from_truth

def sources() -> list[tuple[str, Path, object, PipelineConfig]]:
    """Return (name, clip, calibration, config) of each clip that exists."""
    out = []
    udacity = data.udacity("videos/project_video.mp4")
    if udacity is not None:
        out.append(("udacity project", udacity, data.udacity_calibration(), PipelineConfig()))
    synth = data.bundled("videos") / "project.mp4"
    if synth.is_file():
        out.append(("synthetic project", synth, calibration_from_truth(synth), PipelineConfig()))
    p1 = data.udacity("test_videos/solidYellowLeft.mp4", data.UDACITY_P1)
    if p1 is not None:
        out.append(("p1 solidYellowLeft", p1, None, preset("p1")))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=250, help="clip frames for video_fps and codec_fps")
    ap.add_argument("--json", type=Path, help="also write every clip's figures to this JSON file")
    args = ap.parse_args()
    results = {}
    try:
        for name, clip, cal, cfg in sources():
            print(f"=== {name}", flush=True)
            figures = bench.run(clip, cal, cfg, clip_frames=args.frames)
            print(bench.format_report(figures) + "\n", flush=True)
            results[name] = figures
    except LaneLibError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if not results:
        print("no clip found: set LANELIB_DATA or run `python -m lanelib synth --all`", file=sys.stderr)
        return 2
    print(f"{'clip':22s} {'size':>9s} {'detect ms':>9s} {'remap ms':>8s} {'d/r':>5s} "
          f"{'video fps':>9s} {'codec fps':>9s} {'v/c':>5s} {'cpu c/v':>7s}")
    for name, f in results.items():
        print(f"{name:22s} {f['size'][0]:>4d}x{f['size'][1]:<4d} {f['detect_ms']:9.2f} "
              f"{f['remap_ms']:8.2f} {f['detect_to_remap']:5.2f} {f['video_fps']:9.1f} "
              f"{f['codec_fps']:9.1f} {f['video_to_codec']:5.2f} {f['cpu_codec_to_video']:7.2f}")
    if args.json:
        io.write_json(args.json, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
