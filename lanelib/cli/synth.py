"""The subcommands that make data and time the code: ``synth`` (synthetic chessboards, road images,
videos and benchmark samples with exact truth) and ``bench``."""
from __future__ import annotations

import json
from pathlib import Path

from .. import bench, data, synth
from ..errors import InputError
from ..synth import datasets as synth_datasets
from .common import common_pipeline_args, exit_codes, load_pipeline_inputs


def add_synth(sub) -> None:
    p = sub.add_parser(
        "synth", help="render synthetic chessboards, road images and videos with ground truth",
        description="Render lanelib's synthetic data with exact ground truth from fixed seeds (the "
                    "same bytes on one machine). --all rewrites the bundled camera_cal/ (20 chessboards and "
                    "camera_truth.json), test_images/ (8 scenes and the 6 hard-road stills in hard/, NAME.json "
                    "beside each) and videos/ (project, challenge, harder, shadows, seams, glare, "
                    "country: 10 s each, NAME.csv per frame and NAME.json beside each). The "
                    "subcommands render one part.",
        epilog=exit_codes())
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


def add_bench(sub) -> None:
    p = sub.add_parser("bench", help="speed of the detection path and of the video command",
                       description="Time the per-frame detection path against one full-frame remap "
                                   "(one thread) and the video command against decode + encode of "
                                   "the same clip; print the figures and the per-stage times. The "
                                   "clip is the Udacity project video when the Udacity data is "
                                   "present, else the bundled videos/project.mp4.",
                       epilog=exit_codes())
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--video", type=Path, metavar="FILE",
                   help="1280x720 clip to time (default: see above); pass --calibration with it")
    common_pipeline_args(p)
    p.add_argument("--frames", type=int, default=250, metavar="N",
                   help="frames of the clip for video_fps and codec_fps (default: 250)")
    p.set_defaults(func=_run_bench)


def _run_bench(args) -> int:
    if args.frames < 10:
        raise InputError(f"--frames {args.frames}: give 10 frames or more")
    config, calibration = load_pipeline_inputs(args)
    figures = bench.run(args.video, calibration, config, clip_frames=args.frames)
    print(json.dumps(figures, indent=2) if args.json else bench.format_report(figures))
    return 0
