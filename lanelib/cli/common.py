"""What the subcommands share: the exit codes of their ``--help``, the pipeline, geometry, clip
range and Dask options, reading a config and a calibration, and the lines printed about a run."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .. import autogeometry
from ..autogeometry import GeometryOptions
from ..camera import Calibration
from ..config import PipelineConfig, load_config_or_preset, override


EXIT_OK = "exit codes: 0 every input ran;"
EXIT_REST = ("2 nothing was run: a usage error, a missing or empty input, an unreadable video, a bad "
             "config or calibration, an output over an input (one line on stderr, nothing written); "
             "130 interrupted by Ctrl-C (no half-written output is left).")


def exit_codes(*code_1: str) -> str:
    """Return the ``--help`` epilog that lists a subcommand's exit codes (code 1 as given)."""
    return " ".join((EXIT_OK, *code_1, EXIT_REST))


def common_pipeline_args(p: argparse.ArgumentParser, default: str = "built-in") -> None:
    """Add --calibration, --config (``default``: what the help says is used without it) and --set."""
    p.add_argument("--calibration", type=Path, metavar="FILE",
                   help="camera calibration JSON from `calibrate` (default: none, frames are "
                        "taken as undistorted)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON (e.g. saved by a notebook tuner) or the name of a "
                        "bundled preset (p1: the 960x540 Udacity P1 camera; highway: the default "
                        "checks; country: lanes 2.5-5.0 m wide on bends to 30 m; tusimple, culane: "
                        f"the benchmark's camera); default: {default}")
    set_arg(p)


REFUSED_STOPS = "an estimate that fails or is not confident stops the run (exit 2)"
REFUSED_FALLS_BACK = ("once per sequence folder; a sequence whose estimate fails or is not confident keeps "
                       "the config's points, and one line says which and why (the run goes on)")


def geometry_args(p: argparse.ArgumentParser, auto: bool, video: bool = False,
                   refused: str = REFUSED_STOPS) -> None:
    """Add the options of the road geometry estimate (``auto``: behind ``--auto-geometry``;
    ``video``: its help says how a video's geometry is checked and refined; ``refused``: what
    its help says a refused estimate does)."""
    if auto:
        through = ("; estimated from the first --geometry-seconds, then checked every 0.5 s: the vanishing point "
                   "is refined along the horizon as straight road accumulates, and the geometry "
                   "estimated again when the horizon moves (a hill); the run's notes say when"
                   if video else "")
        p.add_argument("--auto-geometry", action="store_true",
                       help="estimate the bird's-eye points and scale from the frames themselves "
                            f"(see `geometry --help`) instead of the config's perspective{through}; "
                            f"{refused}")
    g = p.add_argument_group("road geometry" + (" (with --auto-geometry)" if auto else ""))
    g.add_argument("--lane-width", type=float, default=GeometryOptions.lane_width_m, metavar="M",
                   help="the ego lane's width, which sets the scale across the road (default 3.7)")
    g.add_argument("--look-ahead-m", type=float, default=GeometryOptions.look_ahead_m, metavar="M",
                   help="how far ahead of the camera the bird's-eye view reaches (default 25)")
    g.add_argument("--dash-m", type=float, default=GeometryOptions.dash_m, metavar="M",
                   help="length of a dash of the dashed lines, for the scale along the road (default 3)")
    g.add_argument("--gap-m", type=float, default=GeometryOptions.gap_m, metavar="M",
                   help="gap between dashes (default 9; US freeways: --dash-m 3.05 --gap-m 9.14)")
    g.add_argument("--focal-px", type=float, metavar="PX",
                   help="the camera's focal length in px when no calibration gives it")
    g.add_argument("--geometry-seconds", type=float, default=GeometryOptions.seconds, metavar="S",
                   help="of a video read for the estimate, from its start (default 20)")
    g.add_argument("--accept-low-confidence", action="store_true",
                   help=f"use an estimate whose confidence is below {autogeometry.LOW_CONFIDENCE} "
                        "(refused otherwise)")


def geometry_options(args) -> "GeometryOptions":
    return GeometryOptions(lane_width_m=args.lane_width, look_ahead_m=args.look_ahead_m,
                                dash_m=args.dash_m, gap_m=args.gap_m, focal_px=args.focal_px,
                                seconds=args.geometry_seconds,
                                accept_low_confidence=args.accept_low_confidence)


def print_geometry(geo) -> None:
    print(geo.summary())
    for a in geo.assumptions:
        print(f"  assumed: {a}")


def set_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="KEY=VALUE",
                   help="set one config value over --config (or its default), dotted as in the JSON "
                        "file, e.g. --set search.trim_outliers_pct=95 --set thresholds.clahe=true "
                        "(repeatable)")


def load_config(args, default: PipelineConfig = PipelineConfig()) -> PipelineConfig:
    """Return the config of --config (file or preset; else ``default``) with each --set applied."""
    config = load_config_or_preset(args.config) if args.config else default
    return override(config, args.settings)


def load_pipeline_inputs(args, default: PipelineConfig = PipelineConfig()):
    config = load_config(args, default)
    calibration = Calibration.load(args.calibration) if args.calibration else None
    return config, calibration


def print_failed(rows: list[dict]) -> int:
    """Print one ``error:`` line on stderr per row that failed; return how many did."""
    failed = [r for r in rows if "error" in r]
    for r in failed:
        print(f"error: {r['error']}", file=sys.stderr)
    return len(failed)


def range_args(p: argparse.ArgumentParser, videos_only: str = "") -> None:
    p.add_argument("--start", type=float, metavar="S",
                   help=f"{videos_only}run on part of the clip from S seconds: from the first frame "
                        "at or after S (frame i shows from i / fps s); default: the clip's start. "
                        "ffmpeg seeks there, the frames before are not decoded, and the tracking "
                        "starts afresh on that frame. The output video "
                        "holds only the part; the --log rows keep the source clip's frame index "
                        "and time_s, so frame 50 of a 25 fps clip is logged as frame 50, 2.0 s")
    p.add_argument("--end", type=float, metavar="E",
                   help=f"{videos_only}run up to the last frame before E seconds (--start 2 --end 3 "
                        "at 25 fps: frames 50..74, 25 frames); default: the clip's end. A "
                        "negative time, a start not before the end or a start beyond the clip's "
                        "last frame is an error (exit code 2)")


def clip_part(args, run) -> str:
    """Return the summary's note of the clip's part a --start/--end run covered ('' for all of it)."""
    if args.start is None and args.end is None:
        return ""
    last = run.first_frame + run.frames - 1
    return f" (frames {run.first_frame}..{last} of {args.input})"


def print_joints(joints) -> None:
    """Print how a Dask run's segments were joined (``cluster.Joints``; nothing in one process)."""
    if joints is not None and joints.joints:
        print(f"dask: {joints}")


# what --workers splits, and where the workers read and write (the shared filesystem --scheduler needs)
DASK_WORK = {
    "predict": ("in chunks of frames", "read the images and write the predictions themselves, so "
                "DATASET_ROOT and PRED_DIR"),
    "images": ("in chunks of images", "read the images and write the annotated ones themselves, so "
               "IN_DIR and OUT_DIR"),
    "video": ("in segments of the clip, each started 50 frames early to warm the tracker up (the "
              "output and log are those of one process), joined without re-encoding",
              "read the video and write the segments beside OUT themselves, so IN and OUT's folder"),
    "evaluate": ("in chunks of images, or segments of the video (with the tracker each started 50 "
                 "frames early to warm it up); tusimple|culane: the images' scores in chunks (the "
                 "labels and predictions are read here and sent); the figures are those of one process",
                 "read the images or the video and its truth themselves, so PATH (images|video)"),
    "hough": ("in chunks of images, or segments of a video (as `video`)",
              "read the input and write the outputs themselves, so IN and OUT"),
}


def dask_args(p, command: str) -> None:
    split, shared = DASK_WORK[command]
    g = p.add_argument_group("dataset scale (Dask)")
    g.add_argument("--workers", type=int, default=1, metavar="N",
                   help=f"run on N worker processes of a Dask LocalCluster on this machine, {split} "
                        "(default 1: in this process, without Dask)")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on the workers of a running Dask cluster (tcp://HOST:PORT of `dask "
                        f"scheduler`; start workers with `dask worker ADDRESS`); the workers {shared} "
                        "must be on a filesystem they share, at the same path; --workers is ignored. "
                        "Start the workers with DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON__"
                        "MALLOC_TRIM_THRESHOLD_=None in their environment (Dask's default trimming "
                        "doubles a frame's time)")
