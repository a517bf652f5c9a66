"""The subcommands that find the lane in a folder of images or a video: ``images``, ``video`` (the
advanced pipeline) and ``hough`` (the basic one); each calls ``lanelib.batch``."""
from __future__ import annotations

from pathlib import Path

from .. import batch
from ..draw import STRAIGHT_M
from ..errors import InputError
from ..io import VIDEO_SUFFIXES, list_images
from .common import (clip_part, common_pipeline_args, dask_args, exit_codes, geometry_args, geometry_options,
                     load_config, load_pipeline_inputs, print_failed, print_geometry, print_joints, range_args,
                     set_arg)


_EXIT_IMAGES = ("1 the run finished but some files failed (unreadable, not an image, too small, a "
                "size the calibration does not fit): one `error:` line each on stderr, a row with "
                "its \"error\" in results.json, no output image;")
_EXIT_HOUGH = ("1 images: the run finished but some files failed (unreadable, not an image): one "
               "`error:` line each on stderr, a row with its \"error\" in results.json, no output "
               "image; video: the video broke off half-way (decoding stopped): the output video and "
               "log keep the frames before the break, and one `error:` line says where and why;")
_EXIT_VIDEO = ("1 the video broke off half-way (decoding stopped): the output video and log keep the "
               "frames before the break, and one `error:` line says where and why;")


def add_images(sub) -> None:
    p = sub.add_parser("images", help="find the lane in a folder of images",
                       description="Run the lane pipeline on every image of IN_DIR; write one "
                                   "annotated image per input and OUT_DIR/results.json (file, found, "
                                   "left_found, right_found, radius_m, offset_m, lane_width_m, "
                                   "and note when the image was grey, 16-bit or slightly corrupt). "
                                   "Grey, RGBA and 16-bit images are read as RGB (16-bit: value "
                                   ">> 8); a file that fails gets a row {file, error} and the run "
                                   "goes on.",
                       epilog=exit_codes(_EXIT_IMAGES))
    p.add_argument("in_dir", type=Path, metavar="IN_DIR", help="folder of road images")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT_DIR",
                   help="folder for the annotated images and results.json")
    common_pipeline_args(p)
    p.add_argument("--debug", action="store_true",
                   help="write the 2x2 debug composite instead of the annotated frame")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar (Dask runs)")
    dask_args(p, "images")
    geometry_args(p, auto=True)
    p.set_defaults(func=_run_images)


def _run_images(args) -> int:
    files = list_images(args.in_dir)
    config, calibration = load_pipeline_inputs(args)
    if args.auto_geometry:
        config, calibration = batch.road_geometry_run(args.in_dir, config, calibration, geometry_options(args),
                                                      on_geometry=print_geometry)
    rows = batch.process_images(files, args.output, config, calibration, debug=args.debug,
                                workers=args.workers, scheduler=args.scheduler,
                                progress=not args.no_progress)
    for r in rows:
        if "error" in r:
            continue
        radius = "straight" if r["found"] and r["radius_m"] >= STRAIGHT_M else f"{r['radius_m']} m"
        status = (f"radius {radius}, offset {r['offset_m']} m, width {r['lane_width_m']} m"
                  if r["found"] else f"no lane found: {r['reason']}")
        print(f"{r['file']}: {status}" + (f" (note: {r['note']})" if r.get("note") else ""))
    failed = print_failed(rows)
    print(f"{sum(bool(r.get('found')) for r in rows)} of {len(rows)} images: lane found"
          + (f"; {failed} failed" if failed else "") + f"; results in {args.output / 'results.json'}")
    return 1 if failed else 0


def add_video(sub) -> None:
    p = sub.add_parser("video", help="track the lane through a video",
                       description="Track the lane through IN (frame by frame, with sanity checks, "
                                   "smoothing and fall back) and write the annotated video OUT "
                                   "(H.264, same size and frame rate). A progress bar shows fps "
                                   "and ETA; Ctrl-C leaves no half-written file.",
                       epilog=exit_codes(_EXIT_VIDEO))
    p.add_argument("input", type=Path, metavar="IN", help="input video (mp4)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output video (mp4) to write")
    common_pipeline_args(p)
    p.add_argument("--debug", action="store_true",
                   help="write the 2x2 debug composite (undistorted, binary, search, result)")
    p.add_argument("--log", type=Path, metavar="CSV",
                   help="per-frame CSV: frame, time_s, found, method (windows, prior, or hold: "
                        "held from earlier frames, drawn in amber), left_conf, right_conf, radius_m, "
                        "offset_m, lane_width_m, left_a..c, right_a..c (bird's-eye pixel fits)")
    range_args(p)
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    dask_args(p, "video")
    geometry_args(p, auto=True, video=True)
    p.set_defaults(func=_run_video)


def _run_video(args) -> int:
    config, calibration = load_pipeline_inputs(args)
    options = geometry_options(args) if args.auto_geometry else None
    if options is not None:
        print(f"estimating the road geometry from the first {options.seconds:g} s of {args.input}")
    run = batch.process_video(args.input, args.output, config, calibration, debug=args.debug,
                              log_path=args.log, progress=not args.no_progress,
                              start_s=args.start, end_s=args.end, auto_geometry=options,
                              on_geometry=print_geometry, workers=args.workers, scheduler=args.scheduler)
    for note in run.notes:
        print(f"geometry: {note}")
    print(f"{args.output}: {run.frames} frames{clip_part(args, run)} in {run.seconds:.1f} s "
          f"({run.fps:.1f} fps); lane found in {run.found_frames} of {run.frames} frames"
          + (f"; per-frame log in {args.log}" if args.log else ""))
    print_joints(run.joints)
    return 0


def add_hough(sub) -> None:
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
                       epilog=exit_codes(_EXIT_HOUGH))
    p.add_argument("input", type=Path, metavar="IN", help="folder of road images, or a video (mp4)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output folder (images) or output video (mp4)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON (its `hough` part is used) or the name of a bundled "
                        "preset; default: built-in")
    set_arg(p)
    p.add_argument("--log", type=Path, metavar="CSV",
                   help="videos only: per-frame CSV: frame, time_s, left_found, right_found, "
                        "left_x_bottom, left_x_top, right_x_bottom, right_x_top, left_held, "
                        "right_held, reason")
    range_args(p, "videos only: ")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    dask_args(p, "hough")
    p.set_defaults(func=_run_hough)


def _run_hough(args) -> int:
    config = load_config(args).hough
    if args.input.is_dir():
        if args.log:
            raise InputError("--log is for videos; for images the rows are in OUT/results.json")
        if args.start is not None or args.end is not None:
            raise InputError(f"{args.input}: --start and --end are for videos; drop them for a "
                             "folder of images")
        rows = batch.hough_images(list_images(args.input), args.output, config, workers=args.workers,
                                  scheduler=args.scheduler, progress=not args.no_progress)
        for r in rows:
            if "error" in r:
                continue
            print(f"{r['file']}: left x {r['left_x_bottom']} px, right x {r['right_x_bottom']} px "
                  f"at the bottom row" + (f"; {r['reason']}" if r["reason"] else "")
                  + (f" (note: {r['note']})" if r.get("note") else ""))
        failed = print_failed(rows)
        both = sum(bool(r.get("left_found") and r.get("right_found")) for r in rows)
        print(f"{both} of {len(rows)} images: both lines found" + (f"; {failed} failed" if failed else "")
              + f"; results in {args.output / 'results.json'}")
        return 1 if failed else 0
    if not args.input.exists():
        raise InputError(f"{args.input}: no such file or folder; check the path")
    if args.input.suffix.lower() not in VIDEO_SUFFIXES:
        raise InputError(f"{args.input}: neither a folder of images nor a video "
                         f"({', '.join(VIDEO_SUFFIXES)}); pass one of those")
    run = batch.hough_video(args.input, args.output, config, log_path=args.log,
                            progress=not args.no_progress, start_s=args.start, end_s=args.end,
                            workers=args.workers, scheduler=args.scheduler)
    print(f"{args.output}: {run.frames} frames{clip_part(args, run)} in {run.seconds:.1f} s "
          f"({run.fps:.1f} fps); both lines found in {run.found_frames} of {run.frames} frames"
          + (f"; per-frame log in {args.log}" if args.log else ""))
    print_joints(run.joints)
    return 0
