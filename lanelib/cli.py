"""Command-line interface: ``python -m lanelib SUBCOMMAND ...``.

Each subcommand has one ``_add_<name>`` function below that registers its parser and a thin
``_run_<name>`` that calls into the module owning the work. The exit codes (``main``): 0 when
every input ran; 1 when the run finished but some inputs failed (a bad file in a folder: its own
row and one ``error:`` line each; a video that broke off half-way: the outputs keep the frames
before the break); 2 when nothing was run (usage error, missing or empty input, unreadable video,
bad config or calibration: one line on stderr, nothing written); 130 on Ctrl-C, which leaves no
half-written output.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from . import ablation, autogeometry, bench, data, evaluate, hough, runs, scoreboard, synth
from .benchmarks import culane, metrics, tusimple, why, why_images
from .camera import Calibration, calibrate, parse_pattern
from .config import (PipelineConfig, benchmark_config, load_config_or_preset, override, preset_names,
                     save_parts)
from .draw import STRAIGHT_M
from .errors import InputError, LaneLibError, PartialOutputError
from .io import VIDEO_SUFFIXES, check_not_input, check_output, list_images, write_json, write_text
from .pipeline import LanePipeline
from .synth import datasets as synth_datasets

_EXIT_OK = "exit codes: 0 every input ran;"
_EXIT_REST = ("2 nothing was run: a usage error, a missing or empty input, an unreadable video, a bad "
              "config or calibration, an output over an input (one line on stderr, nothing written); "
              "130 interrupted by Ctrl-C (no half-written output is left).")
_EXIT_IMAGES = ("1 the run finished but some files failed (unreadable, not an image, too small, a "
                "size the calibration does not fit): one `error:` line each on stderr, a row with "
                "its \"error\" in results.json, no output image;")
_EXIT_HOUGH = ("1 images: the run finished but some files failed (unreadable, not an image): one "
               "`error:` line each on stderr, a row with its \"error\" in results.json, no output "
               "image; video: the video broke off half-way (decoding stopped): the output video and "
               "log keep the frames before the break, and one `error:` line says where and why;")
_EXIT_VIDEO = ("1 the video broke off half-way (decoding stopped): the output video and log keep the "
               "frames before the break, and one `error:` line says where and why;")


def _exit_codes(*code_1: str) -> str:
    """Return the ``--help`` epilog that lists a subcommand's exit codes (code 1 as given)."""
    return " ".join((_EXIT_OK, *code_1, _EXIT_REST))


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="python -m lanelib",
        description="lanelib: camera calibration, lane finding on images and videos, synthetic "
                    "data with ground truth, evaluation and benchmarks.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    # one line per subcommand, in the order of the pipeline
    _add_calibrate(sub)
    _add_images(sub)
    _add_video(sub)
    _add_geometry(sub)
    _add_bench(sub)
    _add_hough(sub)
    _add_evaluate(sub)
    _add_predict(sub)
    _add_synth(sub)
    _add_scoreboard(sub)
    _add_ablation(sub)
    _add_why(sub)
    return parser


def _common_pipeline_args(p: argparse.ArgumentParser, default: str = "built-in") -> None:
    """Add --calibration, --config (``default``: what the help says is used without it) and --set."""
    p.add_argument("--calibration", type=Path, metavar="FILE",
                   help="camera calibration JSON from `calibrate` (default: none, frames are "
                        "taken as undistorted)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON (e.g. saved by a notebook tuner) or the name of a "
                        "bundled preset (p1: the 960x540 Udacity P1 camera; highway: the default "
                        "checks; country: lanes 2.5-5.0 m wide on bends to 30 m; tusimple, culane: "
                        f"the benchmark's camera); default: {default}")
    _set_arg(p)


_REFUSED_STOPS = "an estimate that fails or is not confident stops the run (exit 2)"
_REFUSED_FALLS_BACK = ("once per sequence folder; a sequence whose estimate fails or is not confident keeps "
                       "the config's points, and one line says which and why (the run goes on)")


def _geometry_args(p: argparse.ArgumentParser, auto: bool, video: bool = False,
                   refused: str = _REFUSED_STOPS) -> None:
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
    g.add_argument("--lane-width", type=float, default=runs.GeometryOptions.lane_width_m, metavar="M",
                   help="the ego lane's width, which sets the scale across the road (default 3.7)")
    g.add_argument("--look-ahead-m", type=float, default=runs.GeometryOptions.look_ahead_m, metavar="M",
                   help="how far ahead of the camera the bird's-eye view reaches (default 25)")
    g.add_argument("--dash-m", type=float, default=runs.GeometryOptions.dash_m, metavar="M",
                   help="length of a dash of the dashed lines, for the scale along the road (default 3)")
    g.add_argument("--gap-m", type=float, default=runs.GeometryOptions.gap_m, metavar="M",
                   help="gap between dashes (default 9; US freeways: --dash-m 3.05 --gap-m 9.14)")
    g.add_argument("--focal-px", type=float, metavar="PX",
                   help="the camera's focal length in px when no calibration gives it")
    g.add_argument("--geometry-seconds", type=float, default=runs.GeometryOptions.seconds, metavar="S",
                   help="of a video read for the estimate, from its start (default 20)")
    g.add_argument("--accept-low-confidence", action="store_true",
                   help=f"use an estimate whose confidence is below {autogeometry.LOW_CONFIDENCE} "
                        "(refused otherwise)")


def _geometry_options(args) -> "runs.GeometryOptions":
    return runs.GeometryOptions(lane_width_m=args.lane_width, look_ahead_m=args.look_ahead_m,
                                dash_m=args.dash_m, gap_m=args.gap_m, focal_px=args.focal_px,
                                seconds=args.geometry_seconds,
                                accept_low_confidence=args.accept_low_confidence)


def _print_geometry(geo) -> None:
    print(geo.summary())
    for a in geo.assumptions:
        print(f"  assumed: {a}")


def _set_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="KEY=VALUE",
                   help="set one config value over --config (or its default), dotted as in the JSON "
                        "file, e.g. --set search.trim_outliers_pct=95 --set thresholds.clahe=true "
                        "(repeatable)")


def _load_config(args, default: PipelineConfig = PipelineConfig()) -> PipelineConfig:
    """Return the config of --config (file or preset; else ``default``) with each --set applied."""
    config = load_config_or_preset(args.config) if args.config else default
    return override(config, args.settings)


def _load_pipeline_inputs(args, default: PipelineConfig = PipelineConfig()):
    config = _load_config(args, default)
    calibration = Calibration.load(args.calibration) if args.calibration else None
    return config, calibration


def _add_calibrate(sub) -> None:
    p = sub.add_parser("calibrate", help="calibrate a camera from chessboard photos",
                       description="Find the chessboard in every image of CAL_DIR, calibrate the "
                                   "camera and write the calibration as JSON (camera_matrix, "
                                   "dist_coeffs, image_size [w, h], rms_px, used, skipped).",
                       epilog=_exit_codes())
    p.add_argument("cal_dir", type=Path, metavar="CAL_DIR", help="folder of chessboard photos")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="calibration JSON to write")
    p.add_argument("--pattern", default="9x6",
                   help="inner corners per row x per column (default: 9x6)")
    p.set_defaults(func=_run_calibrate)


def _run_calibrate(args) -> int:
    cal = calibrate(args.cal_dir, parse_pattern(args.pattern))
    for name, why in sorted(cal.skip_reasons.items()):
        print(f"skipped {args.cal_dir / name}: {why}", file=sys.stderr)
    cal.save(args.output)
    print(f"{args.output}: {len(cal.used)} boards used, {len(cal.skipped)} skipped, "
          f"RMS reprojection error {cal.rms_px:.3f} px, image size "
          f"{cal.image_size[0]}x{cal.image_size[1]}")
    return 0


def _add_images(sub) -> None:
    p = sub.add_parser("images", help="find the lane in a folder of images",
                       description="Run the lane pipeline on every image of IN_DIR; write one "
                                   "annotated image per input and OUT_DIR/results.json (file, found, "
                                   "left_found, right_found, radius_m, offset_m, lane_width_m, "
                                   "and note when the image was grey, 16-bit or slightly corrupt). "
                                   "Grey, RGBA and 16-bit images are read as RGB (16-bit: value "
                                   ">> 8); a file that fails gets a row {file, error} and the run "
                                   "goes on.",
                       epilog=_exit_codes(_EXIT_IMAGES))
    p.add_argument("in_dir", type=Path, metavar="IN_DIR", help="folder of road images")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT_DIR",
                   help="folder for the annotated images and results.json")
    _common_pipeline_args(p)
    p.add_argument("--debug", action="store_true",
                   help="write the 2x2 debug composite instead of the annotated frame")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar (Dask runs)")
    _dask_args(p, "images")
    _geometry_args(p, auto=True)
    p.set_defaults(func=_run_images)


def _run_images(args) -> int:
    files = list_images(args.in_dir)
    config, calibration = _load_pipeline_inputs(args)
    if args.auto_geometry:
        geo = runs.estimate_road_geometry(args.in_dir, calibration, _geometry_options(args))
        _print_geometry(geo)
        config = runs.with_geometry(config, geo)
        calibration = runs.geometry_calibration(calibration, geo)
    rows = runs.process_images(files, args.output, config, calibration, debug=args.debug,
                               workers=args.workers, scheduler=args.scheduler,
                               progress=not args.no_progress)
    for r in rows:
        if "error" in r:
            continue
        radius = "straight" if r["found"] and r["radius_m"] >= STRAIGHT_M else f"{r['radius_m']} m"
        status = (f"radius {radius}, offset {r['offset_m']} m, width {r['lane_width_m']} m"
                  if r["found"] else f"no lane found: {r['reason']}")
        print(f"{r['file']}: {status}" + (f" (note: {r['note']})" if r.get("note") else ""))
    failed = _print_failed(rows)
    print(f"{sum(bool(r.get('found')) for r in rows)} of {len(rows)} images: lane found"
          + (f"; {failed} failed" if failed else "") + f"; results in {args.output / 'results.json'}")
    return 1 if failed else 0


def _print_failed(rows: list[dict]) -> int:
    """Print one ``error:`` line on stderr per row that failed; return how many did."""
    failed = [r for r in rows if "error" in r]
    for r in failed:
        print(f"error: {r['error']}", file=sys.stderr)
    return len(failed)


def _add_video(sub) -> None:
    p = sub.add_parser("video", help="track the lane through a video",
                       description="Track the lane through IN (frame by frame, with sanity checks, "
                                   "smoothing and fall back) and write the annotated video OUT "
                                   "(H.264, same size and frame rate). A progress bar shows fps "
                                   "and ETA; Ctrl-C leaves no half-written file.",
                       epilog=_exit_codes(_EXIT_VIDEO))
    p.add_argument("input", type=Path, metavar="IN", help="input video (mp4)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output video (mp4) to write")
    _common_pipeline_args(p)
    p.add_argument("--debug", action="store_true",
                   help="write the 2x2 debug composite (undistorted, binary, search, result)")
    p.add_argument("--log", type=Path, metavar="CSV",
                   help="per-frame CSV: frame, time_s, found, method (windows, prior, or hold: "
                        "held from earlier frames, drawn in amber), left_conf, right_conf, radius_m, "
                        "offset_m, lane_width_m, left_a..c, right_a..c (bird's-eye pixel fits)")
    _range_args(p)
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    _dask_args(p, "video")
    _geometry_args(p, auto=True, video=True)
    p.set_defaults(func=_run_video)


def _range_args(p: argparse.ArgumentParser, videos_only: str = "") -> None:
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


def _part(args, run) -> str:
    """Return the summary's note of the clip's part a --start/--end run covered ('' for all of it)."""
    if args.start is None and args.end is None:
        return ""
    last = run.first_frame + run.frames - 1
    return f" (frames {run.first_frame}..{last} of {args.input})"


def _print_joints(joints) -> None:
    """Print how a Dask run's segments were joined (``cluster.Joints``; nothing in one process)."""
    if joints is not None and joints.joints:
        print(f"dask: {joints}")


def _run_video(args) -> int:
    config, calibration = _load_pipeline_inputs(args)
    options = _geometry_options(args) if args.auto_geometry else None
    if options is not None:
        print(f"estimating the road geometry from the first {options.seconds:g} s of {args.input}")
    run = runs.process_video(args.input, args.output, config, calibration, debug=args.debug,
                             log_path=args.log, progress=not args.no_progress,
                             start_s=args.start, end_s=args.end, auto_geometry=options,
                             on_geometry=_print_geometry, workers=args.workers, scheduler=args.scheduler)
    for note in run.notes:
        print(f"geometry: {note}")
    print(f"{args.output}: {run.frames} frames{_part(args, run)} in {run.seconds:.1f} s "
          f"({run.fps:.1f} fps); lane found in {run.found_frames} of {run.frames} frames"
          + (f"; per-frame log in {args.log}" if args.log else ""))
    _print_joints(run.joints)
    return 0


def _add_geometry(sub) -> None:
    p = sub.add_parser(
        "geometry", help="estimate the bird's-eye view from the road itself",
        description="Estimate the road geometry of a camera from a video's first seconds or a folder "
                    "of its images: the vanishing point of the road and the horizon (with the roll, "
                    "from three or more lane lines), the hood, the bird's-eye points for a look-ahead, "
                    "the scale across (lane width) and along the road (the dash period, else the "
                    "focal length of --calibration or --focal-px, else an assumed 60 deg field of "
                    "view, which is said), and pitch and yaw when a focal length is known. Writes "
                    "the perspective part of a PipelineConfig to OUT (merged into OUT when it is "
                    "already a config, e.g. one a tuner saved; else the whole config of --config or "
                    "the defaults) and prints the figures, the confidence and every assumption. "
                    "Frames with no consistent vanishing point, or an estimate below the confidence "
                    "limit, stop with the reason (exit 2). See lanelib/autogeometry/ for the method.",
        epilog=_exit_codes())
    p.add_argument("input", type=Path, metavar="VIDEO_OR_FOLDER",
                   help="a video of the camera (a straight stretch helps) or a folder of its images")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="config JSON to write (readable by --config)")
    p.add_argument("--calibration", type=Path, metavar="FILE",
                   help="the camera's calibration JSON (undistorts the frames; its focal length "
                        "gives pitch, yaw and a check of the scale)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="for a new OUT: the config whose other parts it holds (default: built-in)")
    p.add_argument("--json", type=Path, metavar="FILE", help="also write every figure as JSON")
    p.add_argument("--lens-out", type=Path, metavar="FILE",
                   help="where to write the lens estimated from the road's lines when no --calibration "
                        "is given and the lines measure one (a calibration JSON for --calibration; "
                        "default: OUT with the suffix .lens.json); the perspective of OUT is then for "
                        "frames undistorted with it")
    _geometry_args(p, auto=False)
    p.set_defaults(func=_run_geometry)


def _run_geometry(args) -> int:
    if args.lens_out is not None and args.calibration is not None:
        raise InputError(f"--lens-out {args.lens_out}: with --calibration the lens is the calibration's "
                         "and none is estimated from the road; drop --lens-out (or --calibration)")
    calibration = Calibration.load(args.calibration) if args.calibration else None
    inputs = [args.input] + ([args.calibration] if args.calibration else [])
    # every output, before any work: writable, over no input and over no other output
    lens_out = None if calibration is not None else args.lens_out or args.output.with_suffix(".lens.json")
    outputs = [f for f in (args.output, args.json, lens_out) if f is not None]
    for i, f in enumerate(outputs):
        check_output(f, inputs, outputs[:i])
    base = load_config_or_preset(args.config) if args.config else PipelineConfig()
    geo = runs.estimate_road_geometry(args.input, calibration, _geometry_options(args))
    _print_geometry(geo)
    save_parts(runs.with_geometry(base, geo), args.output, ("perspective",))
    if geo.lens is not None:
        geo.lens.save(lens_out)
        print(f"perspective written to {args.output}, the estimated lens to {lens_out} (use them together: "
              f"--config {args.output} --calibration {lens_out})")
    else:
        print(f"perspective written to {args.output} (use it with --config {args.output})")
    if args.json:
        write_json(args.json, geo.to_dict(), inputs=inputs)
        print(f"figures written to {args.json}")
    return 0


def _add_hough(sub) -> None:
    p = sub.add_parser("hough", help="basic straight lane lines (Canny + Hough) on images or a video",
                       description="Find the left and right lane lines as straight lines (white and "
                                   "yellow selection, Canny, region of interest, Hough) in IN, a "
                                   "folder of images or a video. For images, write one annotated "
                                   "image per input and OUT/results.json (file, left_found, "
                                   "right_found, left_x_bottom, left_x_top, right_x_bottom, "
                                   "right_x_top in px, reason); for a video, write the annotated "
                                   "video OUT (lines smoothed across frames, a lost line held for "
                                   "a few frames). A file that fails gets a row {file, error} "
                                   "and the run goes on.",
                       epilog=_exit_codes(_EXIT_HOUGH))
    p.add_argument("input", type=Path, metavar="IN", help="folder of road images, or a video (mp4)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output folder (images) or output video (mp4)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON (its `hough` part is used) or the name of a bundled "
                        "preset; default: built-in")
    _set_arg(p)
    p.add_argument("--log", type=Path, metavar="CSV",
                   help="videos only: per-frame CSV: frame, time_s, left_found, right_found, "
                        "left_x_bottom, left_x_top, right_x_bottom, right_x_top, left_held, "
                        "right_held, reason")
    _range_args(p, "videos only: ")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    _dask_args(p, "hough")
    p.set_defaults(func=_run_hough)


def _run_hough(args) -> int:
    config = _load_config(args).hough
    if args.input.is_dir():
        if args.log:
            raise InputError("--log is for videos; for images the rows are in OUT/results.json")
        if args.start is not None or args.end is not None:
            raise InputError(f"{args.input}: --start and --end are for videos; drop them for a "
                             "folder of images")
        rows = runs.hough_images(list_images(args.input), args.output, config, workers=args.workers,
                                 scheduler=args.scheduler, progress=not args.no_progress)
        for r in rows:
            if "error" in r:
                continue
            print(f"{r['file']}: left x {r['left_x_bottom']} px, right x {r['right_x_bottom']} px "
                  f"at the bottom row" + (f"; {r['reason']}" if r["reason"] else "")
                  + (f" (note: {r['note']})" if r.get("note") else ""))
        failed = _print_failed(rows)
        both = sum(bool(r.get("left_found") and r.get("right_found")) for r in rows)
        print(f"{both} of {len(rows)} images: both lines found" + (f"; {failed} failed" if failed else "")
              + f"; results in {args.output / 'results.json'}")
        return 1 if failed else 0
    if not args.input.exists():
        raise InputError(f"{args.input}: no such file or folder; check the path")
    if args.input.suffix.lower() not in VIDEO_SUFFIXES:
        raise InputError(f"{args.input}: neither a folder of images nor a video "
                         f"({', '.join(VIDEO_SUFFIXES)}); pass one of those")
    run = runs.hough_video(args.input, args.output, config, log_path=args.log,
                           progress=not args.no_progress, start_s=args.start, end_s=args.end,
                           workers=args.workers, scheduler=args.scheduler)
    print(f"{args.output}: {run.frames} frames{_part(args, run)} in {run.seconds:.1f} s "
          f"({run.fps:.1f} fps); both lines found in {run.found_frames} of {run.frames} frames"
          + (f"; per-frame log in {args.log}" if args.log else ""))
    _print_joints(run.joints)
    return 0


def _add_evaluate(sub) -> None:
    p = sub.add_parser(
        "evaluate", help="score the pipeline against ground truth, or predictions by a benchmark's "
                         "official metric",
        description="images|video: run the lane pipeline on synthetic data with ground truth and "
                    "print one table: "
                    "frames, lane found (%), median and 95th-percentile |offset error| (cm), median "
                    "|curvature error| (1/m), median radius error (%, on curves of radius <= 3 km), "
                    "point accuracy (TuSimple: share of truth line points within 20 px across the "
                    "line, in the raw image, inside the bird's-eye view), and the false-positive and "
                    "false-negative line rates. See lanelib/evaluate.py for the exact rules. An "
                    "image that cannot be scored (unreadable, its truth missing or corrupt, another "
                    "size than the truth's camera) is left out of the scores, and the table says "
                    "how many failed. "
                    "tusimple: score a TuSimple prediction file (JSON lines: raw_file, lanes, "
                    "h_samples, run_time) against its labels and print the official Accuracy, FP "
                    "and FN. culane: score a folder of CULane .lines.txt predictions against the "
                    "labels of a list file and print the official TP, FP, FN, precision, recall "
                    "and F1 (lanes 30 px wide on 1640x590, IoU above 0.5). See "
                    "lanelib/benchmarks/metrics.py for the rules matched.",
        epilog=_exit_codes("1 images: some images could not be scored (one `error:` line each on "
                           "stderr; the table and the figures cover the rest; a video that stops "
                           "decoding before the frames to score counts as unreadable: 2);"))
    p.add_argument("kind", choices=("images", "video", "tusimple", "culane"),
                   help="images: PATH is a folder of images, each NAME.jpg with NAME.json beside it; "
                        "video: PATH is a video with NAME.csv and NAME.json beside it; tusimple: "
                        "--gt LABELS.json --pred PRED.json; culane: --gt ROOT --list LIST --pred DIR")
    p.add_argument("path", type=Path, nargs="?", metavar="PATH",
                   help="images|video: folder of images, or video file")
    b = p.add_argument_group("benchmarks (tusimple, culane)")
    b.add_argument("--gt", type=Path, metavar="PATH",
                   help="tusimple: the label file (test_label.json), or a folder of label_data*.json; "
                        "culane: the dataset root the list's paths are relative to")
    b.add_argument("--pred", type=Path, metavar="PATH",
                   help="tusimple: the prediction file; culane: the folder of .lines.txt predictions "
                        "mirroring the list's paths (a missing file counts as no lanes)")
    b.add_argument("--list", dest="list_file", type=Path, metavar="FILE",
                   help="culane: the list of images to score (e.g. ROOT/list/test.txt)")
    b.add_argument("--lane-width-px", type=int, default=metrics.CULANE_LANE_WIDTH_PX, metavar="PX",
                   help=f"culane: thickness the lanes are drawn with (default: "
                        f"{metrics.CULANE_LANE_WIDTH_PX}, the official)")
    b.add_argument("--iou", type=float, default=metrics.CULANE_IOU, metavar="T",
                   help=f"culane: IoU above which a pair is a true positive (default: "
                        f"{metrics.CULANE_IOU}, the official; 0.3 is the other published one)")
    g = p.add_argument_group("images and video")
    g.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig, as for `images` (default: built-in)")
    _set_arg(g)
    g.add_argument("--calibration", type=Path, metavar="FILE",
                   help="camera calibration JSON from `calibrate` (e.g. of camera_cal/); default: "
                        "the true camera recorded in the ground truth, so the score is the lane "
                        "finding's alone; pass your calibration to score calibration and lane "
                        "finding together")
    g.add_argument("--detector", choices=("frame", "tracker"),
                   help="frame: detect every frame on its own; tracker: LaneTracker through the "
                        "frames in order (video only). Default: frame for images, tracker for video")
    g.add_argument("--max-frames", type=int, metavar="N",
                   help="score only the first N images (by name) or video frames")
    p.add_argument("--json", type=Path, metavar="OUT",
                   help="also write the figures as JSON; tusimple: benchmark, images, Accuracy, "
                        "FP, FN; culane: benchmark, images, TP, FP, FN, precision, recall, F1, "
                        "missing_predictions; images|video: frames, found_rate, offset_err_cm_median, "
                        "offset_err_cm_p95, curvature_err_median, radius_err_pct_median, "
                        "point_accuracy, fp_rate, fn_rate, files_failed (rates as fractions, null "
                        "where nothing was scored)")
    _dask_args(p, "evaluate")
    p.set_defaults(func=_run_evaluate)


_PIPELINE_ONLY = (("config", "--config"), ("settings", "--set"), ("calibration", "--calibration"),
                  ("detector", "--detector"), ("max_frames", "--max-frames"))
_BENCHMARK_ONLY = (("gt", "--gt"), ("pred", "--pred"), ("list_file", "--list"))


def _run_evaluate(args) -> int:
    if args.kind in ("tusimple", "culane"):
        return _run_evaluate_benchmark(args)
    if args.path is None:
        raise InputError(f"evaluate {args.kind}: give the PATH to score (a folder of images, or a video)")
    given = [flag for dest, flag in _BENCHMARK_ONLY if getattr(args, dest) is not None]
    if given:
        raise InputError(f"{', '.join(given)}: for `evaluate tusimple|culane` only; evaluate "
                         f"{args.kind} scores the pipeline on PATH")
    if args.max_frames is not None and args.max_frames < 1:
        raise InputError(f"--max-frames {args.max_frames}: give a number of frames of 1 or more")
    detector = args.detector or ("tracker" if args.kind == "video" else "frame")
    if args.kind == "images" and detector == "tracker":
        raise InputError(f"{args.path}: the tracker follows consecutive video frames; evaluate "
                         "images with --detector frame, or a video with --detector tracker")
    config, calibration = _load_pipeline_inputs(args)
    true_camera = evaluate.calibration_from_truth(args.path)  # also gives the frame size
    pipe = LanePipeline(config, calibration or true_camera, size=true_camera.image_size)
    if args.kind == "images":
        files = list_images(args.path)
        inputs = files + [f.with_suffix(".json") for f in files]
    else:
        inputs = [args.path] + [args.path.with_suffix(s) for s in (".csv", ".json")]
    if args.json:
        check_not_input(args.json, inputs)  # before the run, not after it
    if args.kind == "images":
        report = evaluate.evaluate_images(args.path, pipe, max_frames=args.max_frames,
                                          workers=args.workers, scheduler=args.scheduler)
    else:
        report = evaluate.evaluate_video(args.path, pipe, use_tracker=detector == "tracker",
                                         max_frames=args.max_frames, workers=args.workers,
                                         scheduler=args.scheduler)
    print(report.table())
    _print_joints(report.joints)
    for _, error in report.failed:
        print(f"error: {error}", file=sys.stderr)
    if args.json:
        write_json(args.json, report.to_dict(), inputs=inputs)
        print(f"figures written to {args.json}")
    return 1 if report.failed else 0


def _run_evaluate_benchmark(args) -> int:
    """``evaluate tusimple|culane``: print the official figures of a prediction set (and --json)."""
    given = [flag for dest, flag in _PIPELINE_ONLY if getattr(args, dest) not in (None, [])]
    if args.path is not None:
        given.insert(0, str(args.path))
    if args.kind == "tusimple":
        given += [flag for flag, value, default in (
            ("--lane-width-px", args.lane_width_px, metrics.CULANE_LANE_WIDTH_PX),
            ("--iou", args.iou, metrics.CULANE_IOU)) if value != default]
    if given:
        takes = ("--gt, --pred, --json" if args.kind == "tusimple"
                 else "--gt, --list, --pred, --json, --lane-width-px, --iou")
        raise InputError(f"{', '.join(given)}: not for `evaluate {args.kind}`, which scores a "
                         f"prediction set; it takes {takes}")
    need = [("gt", "--gt"), ("pred", "--pred")] + ([("list_file", "--list")] if args.kind == "culane" else [])
    missing = [flag for dest, flag in need if getattr(args, dest) is None]
    if missing:
        what = ("--gt LABELS.json --pred PRED.json" if args.kind == "tusimple"
                else "--gt ROOT --list LIST --pred PRED_DIR")
        raise InputError(f"evaluate {args.kind}: {' and '.join(missing)} missing; give {what}")
    inputs = [f for f in (args.gt, args.pred, args.list_file) if f is not None and not f.is_dir()]
    if args.json:
        check_not_input(args.json, inputs)  # before the run, not after it
    dask = dict(workers=args.workers, scheduler=args.scheduler,
                progress=args.workers != 1 or args.scheduler is not None)
    if args.kind == "tusimple":
        result = tusimple.evaluate(args.gt, args.pred, **dask)
    else:
        result = culane.evaluate(args.gt, args.list_file, args.pred, width_px=args.lane_width_px,
                                 iou_threshold=args.iou, **dask)
    print(result.table())
    if args.json:
        write_json(args.json, result.to_dict(), inputs=inputs)
        print(f"figures written to {args.json}")
    return 0


def _add_predict(sub) -> None:
    p = sub.add_parser(
        "predict", help="predict the lanes of a TuSimple or CULane dataset in its format",
        description="Detect the lane in every labelled frame of DATASET_ROOT, each frame on its own "
                    "(no tracking: the labelled frames are seconds apart), and write the lines found, "
                    "left to right, in the benchmark's format under PRED_DIR: tusimple: "
                    f"PRED_DIR/{runs.TUSIMPLE_PREDICTIONS} (JSON lines: lanes at the label's h_samples, "
                    "run_time in ms), assembled from one part per frame in "
                    f"PRED_DIR/{runs.TUSIMPLE_PARTS}/; culane: one NAME.lines.txt per image mirroring "
                    "the list. A frame with no line found gets an empty prediction. A run resumes: "
                    "frames whose prediction exists are skipped; every file is written whole "
                    "(temporary file, then rename), so a stopped run leaves no half-written file. "
                    f"PRED_DIR/{runs.PREDICT_SETTINGS} records the settings; other settings are refused "
                    "there. Score with `evaluate tusimple|culane`.",
        epilog=_exit_codes("1 some frames failed (an unreadable image): one `error:` line each, no "
                           "prediction for them (a later run retries them);"))
    p.add_argument("benchmark", choices=runs.PREDICT_BENCHMARKS, help="the dataset's format")
    p.add_argument("root", type=Path, metavar="DATASET_ROOT",
                   help="the folder the labels' image paths are relative to")
    p.add_argument("--list", dest="list_file", type=Path, metavar="FILE",
                   help="tusimple: the label file whose frames to predict (default: every "
                        "label_data*.json of DATASET_ROOT); culane: the list of images (default: "
                        "DATASET_ROOT/list/test.txt)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="PRED_DIR",
                   help="folder for the predictions (not DATASET_ROOT)")
    _common_pipeline_args(p, default="the preset named like the benchmark (tusimple or culane: its "
                                      "camera's bird's-eye points)")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    _dask_args(p, "predict")
    _geometry_args(p, auto=True, refused=_REFUSED_FALLS_BACK)
    p.set_defaults(func=_run_predict)


# what --workers splits, and where the workers read and write (the shared filesystem --scheduler needs)
_DASK_WORK = {
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


def _dask_args(p, command: str) -> None:
    split, shared = _DASK_WORK[command]
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


def _config_name(args) -> str:
    """Return what the notes call the config of a ``predict`` run, e.g. "the culane preset"."""
    if args.config:
        name = f"--config {args.config}"
    elif args.benchmark in preset_names():
        name = f"the {args.benchmark} preset"
    else:
        name = "the built-in config"
    return name + (" with --set" if args.settings else "")


def _run_predict(args) -> int:
    config, calibration = _load_pipeline_inputs(args, benchmark_config(args.benchmark))
    options = _geometry_options(args) if args.auto_geometry else None

    def show(sequence, estimate) -> None:
        if isinstance(estimate, runs.GeometryFallback):
            print(estimate.note(_config_name(args)))
            return
        print(f"{sequence}: road geometry from its frames")
        _print_geometry(estimate)

    run = runs.predict_benchmark(args.benchmark, args.root, args.output, args.list_file, config,
                                 calibration, args.calibration, options, progress=not args.no_progress,
                                 on_geometry=show, workers=args.workers, scheduler=args.scheduler)
    for o in run.failed:
        print(f"error: {o.error}", file=sys.stderr)
    done = len(run.outcomes) - len(run.failed)
    print(f"{run.frames} frames: {done} predicted ({run.without_lines} with no line found), "
          f"{run.skipped} skipped (predicted before)"
          + (f", {len(run.failed)} failed" if run.failed else "") + f"; predictions in {run.output}")
    return 1 if run.failed else 0


def _add_synth(sub) -> None:
    p = sub.add_parser(
        "synth", help="render synthetic chessboards, road images and videos with ground truth",
        description="Render lanelib's synthetic data with exact ground truth from fixed seeds (the "
                    "same bytes on one machine). --all rewrites the bundled camera_cal/ (20 chessboards and "
                    "camera_truth.json), test_images/ (8 scenes and the 6 hard-road stills in hard/, NAME.json "
                    "beside each) and videos/ (project, challenge, harder, shadows, seams, glare, "
                    "country: 10 s each, NAME.csv per frame and NAME.json beside each). The "
                    "subcommands render one part.",
        epilog=_exit_codes())
    p.add_argument("--all", action="store_true", help="render all the bundled data")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="with --all: folder to write camera_cal/, test_images/ and videos/ into "
                        "(default: the repository root)")
    kinds = p.add_subparsers(dest="synth_kind", metavar="KIND")
    k = kinds.add_parser("images", help="the 8 test scenes and the 6 hard-road stills (in hard/), each with its JSON truth")
    k.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="folder to write")
    k = kinds.add_parser("boards", help="the 20 chessboard photographs and camera_truth.json")
    k.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="folder to write")
    k.add_argument("--seed", type=int, help="random seed (default: the bundled one)")
    k = kinds.add_parser("video", help="one video with its per-frame CSV and JSON truth")
    k.add_argument("--set", dest="video_set", choices=tuple(synth.video_sets()), default="project",
                   help="project: clean highway in sun; challenge: tar seams, an underpass, low "
                        "contrast; harder: tight curves, strong light changes; shadows: overpasses, "
                        "hard shadows, exposure jumps, missing paint; seams: seams and repaved "
                        "edges beside the lines, a barrier; glare: low sun, glare, a wet sheen; "
                        "country: hairpins on a two-lane road with slopes (default: project)")
    k.add_argument("-o", "--output", type=Path, required=True, metavar="FILE", help="video (mp4) to write")
    k.add_argument("--seconds", type=float, default=10.0,
                   help="length in seconds, up to 20 (default: 10); a shorter clip is the start of "
                        "a longer one")
    k.add_argument("--seed", type=int, help="random seed of the scene (default: the set's)")
    k = kinds.add_parser(
        "dataset", help="a sample in the TuSimple or CULane layout with exact labels",
        description="Render --frames labelled images in a benchmark's layout, in sequences of up to "
                    f"{synth_datasets.FRAMES_PER_SEQUENCE} frames {synth_datasets.FRAME_SPACING_S:g} s "
                    "apart, each sequence one camera on one multi-lane road. tusimple: "
                    "clips/<seq>/<clip>/20.jpg (1280x720) and label_data_<seq>.json (every line in "
                    "view, left to right, at h_samples 160..710, -2 where absent); culane: "
                    "driver_9<k>_30frame/synth_<k>.MP4/<frame>.jpg (1640x590) with <frame>.lines.txt "
                    "(up to 4 lines) and list/test.txt. The labels are the generator's truth.")
    k.add_argument("benchmark", choices=synth_datasets.BENCHMARKS, help="the layout to write")
    k.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="dataset root to write")
    k.add_argument("--frames", type=int, required=True, metavar="N", help="labelled images to render")
    k.add_argument("--seed", type=int, default=0, help="random seed of the sample (default: 0)")

    def run(args) -> int:
        if args.all == bool(args.synth_kind):
            p.error("give either --all or one of the kinds: images, boards, video, dataset")
        if args.all:
            root = args.out or data.PACKAGE_REPO
            files = synth.generate_all(root, progress=print)
            print(f"{len(files)} files (and their truth) written under {root}")
        elif args.synth_kind == "images":
            print(f"{len(synth.write_test_images(args.output))} images written to {args.output}")
        elif args.synth_kind == "dataset":
            out = synth_datasets.write_dataset(args.benchmark, args.output, args.frames, args.seed)
            print(f"{args.output}: {len(out.images)} {args.benchmark} images in {len(out.sequences)} "
                  f"sequences, {out.lines} labelled lines; labels in "
                  + ("label_data_*.json" if args.benchmark == "tusimple" else
                     "*.lines.txt beside the images, list in list/test.txt"))
        elif args.synth_kind == "boards":
            kw = {} if args.seed is None else {"seed": args.seed}
            print(f"{len(synth.write_boards(args.output, **kw))} chessboards written to {args.output}")
        else:
            synth.write_video(args.output, synth.video_sets()[args.video_set], args.seconds, args.seed)
            print(f"{args.output}: {args.seconds:g} s of {args.video_set}, truth in "
                  f"{args.output.with_suffix('.csv')} and {args.output.with_suffix('.json')}")
        return 0

    p.set_defaults(func=run)


def _add_scoreboard(sub) -> None:
    rows = ", ".join(f"{k} ({title})" for k, (title, _) in scoreboard.ROWS.items())
    p = sub.add_parser(
        "scoreboard", help="one table of lanelib on every data set at hand, real data first",
        description="Measure lanelib on the real data (LANELIB_DATA: CULane and TuSimple dev frames "
                    "predicted and scored by the official rules; the Udacity and P1 clips tracked "
                    "and scored by plausible frames: lane found, 3.0-4.5 m wide, |offset| < 0.6 m) "
                    "and on synthetic data with exact truth, in one run on one thread, and print one "
                    "table with the time per frame. A row whose data is absent says why and is "
                    "skipped. See lanelib/scoreboard.py for each row.",
        epilog=_exit_codes("1 some rows failed: one `error:` line each, the others are in the table;"))
    p.add_argument("--json", type=Path, metavar="FILE", help="also write the figures as JSON")
    p.add_argument("--out", type=Path, default=scoreboard.DEFAULT_OUT, metavar="DIR",
                   help="folder for the predictions (replaced every run), the synthetic samples and "
                        "the upscaled TuSimple frames (kept); default: out/scoreboard")
    p.add_argument("--only", metavar="ROW,...", help=f"run only these rows: {rows}")
    p.set_defaults(func=_run_scoreboard)


def _run_scoreboard(args) -> int:
    if args.json:
        check_output(args.json)  # before the run, not after it
    only = [k.strip() for k in args.only.split(",") if k.strip()] if args.only is not None else None
    rows = scoreboard.run(args.out, only, on_row=lambda r: print(
        f"scoreboard: {r.key} {'skipped' if r.skipped else 'failed' if r.error else 'done'} "
        f"({r.seconds:g} s)", file=sys.stderr))
    print(scoreboard.format_table(rows))
    if args.json:
        write_json(args.json, {"rows": [r.to_dict() for r in rows]})
        print(f"figures written to {args.json}")
    for r in rows:
        if r.error:
            print(f"error: {r.key}: {r.error}", file=sys.stderr)
    return 1 if any(r.error for r in rows) else 0


def _add_ablation(sub) -> None:
    p = sub.add_parser(
        "ablation", help="each part switched alone, its effect on every row of the scoreboard",
        description="Run the scoreboard once as it is and once per part with the part switched (off "
                    "for a part on by default, on for an opt-in part), and print per part the change of "
                    "each row's headline figure it makes (percentage points, + helps) and what the real "
                    "rows say of it. See lanelib/ablation.py for the parts.",
        epilog=_exit_codes("1 some runs' rows failed (see the JSON file);"))
    p.add_argument("--parts", metavar="NAME,...", help="only these parts: " +
                   ", ".join(q.name for q in ablation.PARTS))
    p.add_argument("--only", metavar="ROW,...", help="only these scoreboard rows: " + ", ".join(scoreboard.ROWS))
    p.add_argument("--out", type=Path, default=ablation.DEFAULT_OUT, metavar="DIR",
                   help="folder of each run's files (out/ablation/<part>/ by default)")
    p.add_argument("--workers", type=int, default=1, metavar="N", help="runs side by side (default 1)")
    p.add_argument("--json", type=Path, metavar="FILE", help="also write every run's rows as JSON")
    p.add_argument("--markdown", type=Path, metavar="FILE", help="also write the table as Markdown")
    p.set_defaults(func=_run_ablation)


def _run_ablation(args) -> int:
    for target in (args.json, args.markdown):
        if target:
            check_output(target)
    names = [n.strip() for n in args.parts.split(",") if n.strip()] if args.parts is not None else None
    only = [k.strip() for k in args.only.split(",") if k.strip()] if args.only is not None else None
    result = ablation.run(ablation.choose(names), only, args.out, args.workers,
                          on_done=lambda name: print(f"ablation: {name} done", file=sys.stderr))
    table = ablation.format_table(result)
    print(table)
    if args.json:
        write_json(args.json, result.to_dict())
    if args.markdown:
        write_text(args.markdown, table + "\n")
    failed = [r for rows in [result.baseline, *result.switched.values()] for r in rows if r.error]
    return 1 if failed else 0


def _add_why(sub) -> None:
    p = sub.add_parser(
        "why", help="why each labelled line of a benchmark frame is found, refused or missed",
        description="Run the benchmark path on labelled frames as `predict` does, match the lines to the "
                    "labels by the official rule, and give each label line its class: found, reported "
                    "but off (a reported line on it fails the match), refused (a line the vote weighed "
                    "and refused lies on it: the reason), missed (no line near it: no paint in the mask "
                    "along it, a mask as busy beside it, or paint and no candidate); and each line that "
                    "matches no label: false line. With FRAME: one PNG per frame in -o (labels green, "
                    "lines red when matched and orange when false, refused lines grey, the lines view's "
                    "mask as an inset) and each line's class printed. Without: the whole set (the dev "
                    "set of LANELIB_DATA, or --root), and a table of the classes and reasons.",
        epilog=_exit_codes())
    p.add_argument("benchmark", choices=why.BENCHMARKS, help="the frames' benchmark")
    p.add_argument("frames", nargs="*", metavar="FRAME",
                   help="frames to draw: paths, or names under the dataset root (e.g. "
                        "driver_161_90frame/06030819_0755.MP4/00000.jpg, clips/0313-1/6040/20.jpg)")
    p.add_argument("-o", "--output", type=Path, metavar="DIR",
                   help="with FRAME: the folder of the PNGs (default out/why; not a frame's folder); "
                        "without: also write the counts and the frames of each class to "
                        "DIR/why_BENCHMARK.json")
    p.add_argument("--root", type=Path, metavar="DATASET_ROOT",
                   help="the dataset (default: the dev set in LANELIB_DATA: culane-dev, tusimple-dev)")
    p.add_argument("--list", dest="list_file", type=Path, metavar="FILE",
                   help="without FRAME: culane: the list of images (default list.txt, else "
                        "list/test.txt); tusimple: the label file (default label_data_fullres.json, "
                        "else every label_data*.json)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON or a preset's name (default: the preset named like the "
                        "benchmark)")
    _set_arg(p)
    p.set_defaults(func=_run_why)


def _run_why(args) -> int:
    config = _load_config(args, benchmark_config(args.benchmark))
    if args.frames:
        out = args.output if args.output is not None else Path("out") / "why"
        for frame, png in why_images.write_why(args.benchmark, args.frames, out, args.root, config):
            print(f"{frame.name}: {png}")
            for line in frame.summary():
                print(f"  {line}")
        return 0
    target = args.output / f"why_{args.benchmark}.json" if args.output is not None else None
    if target is not None:
        check_output(target)
    result = why.explain_set(args.benchmark, args.root, config, args.list_file)
    print(result.table())
    if target is not None:
        write_json(target, result.to_dict())
        print(f"classes and their frames written to {target}")
    return 0


def _add_bench(sub) -> None:
    p = sub.add_parser("bench", help="speed of the detection path and of the video command",
                       description="Time the per-frame detection path against one full-frame remap "
                                   "(one thread) and the video command against decode + encode of "
                                   "the same clip; print the figures and the per-stage times. The "
                                   "clip is the Udacity project video when the Udacity data is "
                                   "present, else the bundled videos/project.mp4.",
                       epilog=_exit_codes())
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--video", type=Path, metavar="FILE",
                   help="1280x720 clip to time (default: see above); pass --calibration with it")
    _common_pipeline_args(p)
    p.add_argument("--frames", type=int, default=250, metavar="N",
                   help="frames of the clip for video_fps and codec_fps (default: 250)")
    p.set_defaults(func=_run_bench)


def _run_bench(args) -> int:
    if args.frames < 10:
        raise InputError(f"--frames {args.frames}: give 10 frames or more")
    config, calibration = _load_pipeline_inputs(args)
    figures = bench.run(args.video, calibration, config, clip_frames=args.frames)
    print(json.dumps(figures, indent=2) if args.json else bench.format_report(figures))
    return 0


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit code.

    Exit codes
    ----------
    0 : every input ran.
    1 : the run finished but some inputs failed: a file of a folder (``images``, ``hough``,
        ``evaluate images``) that could not be read or processed has its own row with an
        ``error`` and one ``error:`` line on stderr; a frame of ``predict`` that could not be
        read has one ``error:`` line and no prediction (a later run retries it); a row of
        ``scoreboard`` failed (one ``error:`` line each, the other rows in the table); or a video
        (``video``, ``hough``) broke off half-way, and its outputs keep the frames before the
        break (``PartialOutputError``).
    2 : nothing was run: a usage error (argparse), or a ``LaneLibError`` before any work (missing
        or empty input folder, unreadable or empty video, bad config or calibration, an output
        over an input); one line on stderr, nothing written.
    130 : interrupted (Ctrl-C); no half-written output is left.
    141 : the reader of the output went away (``... | head``); no traceback.
    """
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except PartialOutputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except LaneLibError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted; no partial output was left behind", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output went away (`... | head`): stop quietly, as Unix tools do;
        # stdout goes to /dev/null so Python's own flush at exit does not complain again
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141  # 128 + SIGPIPE
