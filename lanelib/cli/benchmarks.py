"""The subcommands that measure lanelib: ``evaluate`` (against synthetic truth, or a benchmark's
official metric), ``predict`` (a TuSimple or CULane dataset in its format), ``scoreboard``,
``ablation`` and ``why``."""
from __future__ import annotations

import sys
from pathlib import Path

from .. import ablation, batch, evaluate, scoreboard
from ..benchmarks import culane, metrics, tusimple, why, why_images
from ..config import preset_names
from ..errors import InputError
from ..io import check_not_input, check_output, list_images, write_json, write_text
from ..pipeline import LanePipeline
from .common import (REFUSED_FALLS_BACK, common_pipeline_args, dask_args, exit_codes, geometry_args,
                     geometry_options, load_config, load_pipeline_inputs, print_geometry, print_joints,
                     set_arg)


def add_evaluate(sub) -> None:
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
        epilog=exit_codes("1 images: some images could not be scored (one `error:` line each on "
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
                   help="tusimple: the label file (test_label.json), or a folder of label_data*.json "
                        "(else its test_label*.json); "
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
    set_arg(g)
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
    dask_args(p, "evaluate")
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
    config, calibration = load_pipeline_inputs(args)
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
    print_joints(report.joints)
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


def add_predict(sub) -> None:
    p = sub.add_parser(
        "predict", help="predict the lanes of a TuSimple or CULane dataset in its format",
        description="Detect the lane in every labelled frame of DATASET_ROOT, each frame on its own "
                    "(no tracking: the labelled frames are seconds apart), and write the lines found, "
                    "left to right, in the benchmark's format under PRED_DIR: tusimple: "
                    f"PRED_DIR/{batch.TUSIMPLE_PREDICTIONS} (JSON lines: lanes at the label's h_samples, "
                    "run_time in ms), assembled from one part per frame in "
                    f"PRED_DIR/{batch.TUSIMPLE_PARTS}/; culane: one NAME.lines.txt per image mirroring "
                    "the list. A frame with no line found gets an empty prediction. A run resumes: "
                    "frames whose prediction exists are skipped; every file is written whole "
                    "(temporary file, then rename), so a stopped run leaves no half-written file. "
                    f"PRED_DIR/{batch.PREDICT_SETTINGS} records the settings; other settings are refused "
                    "there. Score with `evaluate tusimple|culane`.",
        epilog=exit_codes("1 some frames failed (an unreadable image): one `error:` line each, no "
                           "prediction for them (a later run retries them);"))
    p.add_argument("benchmark", choices=batch.PREDICT_BENCHMARKS, help="the dataset's format")
    p.add_argument("root", type=Path, metavar="DATASET_ROOT",
                   help="the folder the labels' image paths are relative to")
    p.add_argument("--list", dest="list_file", type=Path, metavar="FILE",
                   help="tusimple: the label file whose frames to predict (default: every "
                        "label_data*.json of DATASET_ROOT, else its test_label*.json, else its "
                        "test_tasks*.json, the test set's task file); culane: the list of images (default: "
                        "DATASET_ROOT/list/test.txt, else DATASET_ROOT/list.txt)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="PRED_DIR",
                   help="folder for the predictions (not DATASET_ROOT)")
    common_pipeline_args(p, default="the preset named like the benchmark (tusimple or culane: its "
                                      "camera's bird's-eye points)")
    p.add_argument("--no-progress", action="store_true", help="do not show the progress bar")
    dask_args(p, "predict")
    geometry_args(p, auto=True, refused=REFUSED_FALLS_BACK)
    p.set_defaults(func=_run_predict)


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
    config, calibration = load_pipeline_inputs(args, batch.benchmark_config(args.benchmark))
    options = geometry_options(args) if args.auto_geometry else None

    def show(sequence, estimate) -> None:
        if isinstance(estimate, batch.GeometryFallback):
            print(estimate.note(_config_name(args)))
            return
        print(f"{sequence}: road geometry from its frames")
        print_geometry(estimate)

    run = batch.predict_benchmark(args.benchmark, args.root, args.output, args.list_file, config,
                                  calibration, args.calibration, options, progress=not args.no_progress,
                                  on_geometry=show, on_points=lambda r: print(r.note()),
                                  workers=args.workers, scheduler=args.scheduler)
    for o in run.failed:
        print(f"error: {o.error}", file=sys.stderr)
    done = len(run.outcomes) - len(run.failed)
    print(f"{run.frames} frames: {done} predicted ({run.without_lines} with no line found), "
          f"{run.skipped} skipped (predicted before)"
          + (f", {len(run.failed)} failed" if run.failed else "") + f"; predictions in {run.output}")
    return 1 if run.failed else 0


def add_scoreboard(sub) -> None:
    rows = ", ".join(f"{k} ({title})" for k, (title, _) in scoreboard.ROWS.items())
    p = sub.add_parser(
        "scoreboard", help="one table of lanelib on every data set at hand, real data first",
        description="Measure lanelib on the real data (LANELIB_DATA: CULane and TuSimple dev frames "
                    "predicted and scored by the official rules; the Udacity and P1 clips tracked "
                    "and scored by plausible frames: lane found, 3.0-4.5 m wide, |offset| < 0.6 m) "
                    "and on synthetic data with exact truth, in one run on one thread, and print one "
                    "table with the time per frame. A row whose data is absent says why and is "
                    "skipped. See lanelib/scoreboard.py for each row.",
        epilog=exit_codes("1 some rows failed: one `error:` line each, the others are in the table;"))
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


def add_ablation(sub) -> None:
    p = sub.add_parser(
        "ablation", help="each part switched alone, its effect on every row of the scoreboard",
        description="Run the scoreboard once as it is and once per part with the part switched (off "
                    "for a part on by default, on for an opt-in part), and print per part the change of "
                    "each row's headline figure it makes (percentage points, + helps) and what the real "
                    "rows say of it. See lanelib/ablation.py for the parts.",
        epilog=exit_codes("1 some runs' rows failed (see the JSON file);"))
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


def add_why(sub) -> None:
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
        epilog=exit_codes())
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
                   help="without FRAME: culane: the list of images (default list/test.txt, else "
                        "list.txt); tusimple: the label file (default label_data_fullres.json, else "
                        "every label_data*.json, else test_label*.json)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="PipelineConfig JSON or a preset's name (default: the preset named like the "
                        "benchmark)")
    set_arg(p)
    p.set_defaults(func=_run_why)


def _run_why(args) -> int:
    config = load_config(args, batch.benchmark_config(args.benchmark))
    if args.frames:
        out = args.output if args.output is not None else Path("out") / "why"
        for frame, png in why_images.write_why(args.benchmark, args.frames, out, args.root, config,
                                               on_points=lambda r: print(r.note())):
            print(f"{frame.name}: {png}")
            for line in frame.summary():
                print(f"  {line}")
        return 0
    target = args.output / f"why_{args.benchmark}.json" if args.output is not None else None
    if target is not None:
        check_output(target)
    result = why.explain_set(args.benchmark, args.root, config, args.list_file,
                             on_points=lambda r: print(r.note()))
    print(result.table())
    if target is not None:
        write_json(target, result.to_dict())
        print(f"classes and their frames written to {target}")
    return 0
