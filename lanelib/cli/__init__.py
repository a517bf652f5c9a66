"""Command-line interface: ``python -m lanelib SUBCOMMAND ...``.

Argument parsing only. Each subcommand has one ``add_<name>`` function that registers its parser
and a thin ``_run_<name>`` that calls into the library module owning the work, in a module per
command group:

- ``images``: ``images``, ``video``, ``hough`` (``lanelib.batch``);
- ``camera``: ``calibrate``, ``geometry``;
- ``benchmarks``: ``evaluate``, ``predict``, ``scoreboard``, ``ablation``, ``why``;
- ``synth``: ``synth``, ``bench``;
- ``common``: the options and printed lines they share.

 The exit codes (``main``): 0 when
every input ran; 1 when the run finished but some inputs failed (a bad file in a folder: its own
row and one ``error:`` line each; a video that broke off half-way: the outputs keep the frames
before the break); 2 when nothing was run (usage error, missing or empty input, unreadable video,
bad config or calibration: one line on stderr, nothing written); 130 on Ctrl-C, which leaves no
half-written output.
"""
from __future__ import annotations

import argparse
import os
import sys

from ..errors import LaneLibError, PartialOutputError
from .benchmarks import add_ablation, add_evaluate, add_predict, add_scoreboard, add_why
from .camera import add_calibrate, add_geometry
from .images import add_hough, add_images, add_video
from .synth import add_bench, add_synth

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="python -m lanelib",
        description="lanelib: camera calibration, lane finding on images and videos, synthetic "
                    "data with ground truth, evaluation and benchmarks.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    # one line per subcommand, in the order of the pipeline
    add_calibrate(sub)
    add_images(sub)
    add_video(sub)
    add_geometry(sub)
    add_bench(sub)
    add_hough(sub)
    add_evaluate(sub)
    add_predict(sub)
    add_synth(sub)
    add_scoreboard(sub)
    add_ablation(sub)
    add_why(sub)
    return parser


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
