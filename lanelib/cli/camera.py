"""The subcommands that measure the camera: ``calibrate`` (from chessboard photos) and ``geometry``
(the bird's-eye view estimated from the road, ``lanelib.autogeometry``)."""
from __future__ import annotations

import sys
from pathlib import Path

from .. import batch
from ..camera import Calibration, calibrate
from ..config import PipelineConfig, load_config_or_preset, save_parts
from ..errors import InputError
from ..io import check_output, write_json
from .common import exit_codes, geometry_args, geometry_options, print_geometry


def add_calibrate(sub) -> None:
    p = sub.add_parser("calibrate", help="calibrate a camera from chessboard photos",
                       description="Find the chessboard in every image of CAL_DIR, calibrate the "
                                   "camera and write the calibration as JSON (camera_matrix, "
                                   "dist_coeffs, image_size [w, h], rms_px, used, skipped).",
                       epilog=exit_codes())
    p.add_argument("cal_dir", type=Path, metavar="CAL_DIR", help="folder of chessboard photos")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE",
                   help="calibration JSON to write")
    p.add_argument("--pattern", default="9x6",
                   help="inner corners per row x per column (default: 9x6)")
    p.set_defaults(func=_run_calibrate)


def parse_pattern(text: str) -> tuple[int, int]:
    """Return (cols, rows) from a pattern like "9x6"; anything else raises InputError."""
    try:
        cols, rows = (int(v) for v in text.lower().split("x"))
        if cols < 2 or rows < 2:
            raise ValueError
    except ValueError:
        raise InputError(f"pattern {text!r}: give inner corners as COLSxROWS, e.g. 9x6") from None
    return cols, rows


def _run_calibrate(args) -> int:
    cal = calibrate(args.cal_dir, parse_pattern(args.pattern))
    for name, why in sorted(cal.skip_reasons.items()):
        print(f"skipped {args.cal_dir / name}: {why}", file=sys.stderr)
    cal.save(args.output)
    print(f"{args.output}: {len(cal.used)} boards used, {len(cal.skipped)} skipped, "
          f"RMS reprojection error {cal.rms_px:.3f} px, image size "
          f"{cal.image_size[0]}x{cal.image_size[1]}")
    return 0


def add_geometry(sub) -> None:
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
        epilog=exit_codes())
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
    geometry_args(p, auto=False)
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
    geo = batch.estimate_road_geometry(args.input, calibration, geometry_options(args))
    print_geometry(geo)
    save_parts(batch.with_geometry(base, geo), args.output, ("perspective",))
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
