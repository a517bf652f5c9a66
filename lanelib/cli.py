"""Command-line interface: ``python -m lanelib SUBCOMMAND ...``.

Each subcommand has one ``_add_<name>`` function below that registers its parser and a thin
``_run_<name>`` that calls into the module owning the work. A ``LaneLibError`` (missing or
unreadable input, bad config, ...) prints one line to stderr and exits with code 2; Ctrl-C exits
with 130 and leaves no half-written output.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import LaneLibError


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="python -m lanelib",
        description="lanelib: camera calibration, lane finding on images and videos, synthetic "
                    "data with ground truth, evaluation and benchmarks.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    # one line per subcommand, in the order of the pipeline
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit code (0 ok, 2 bad input, 130 interrupted)."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except LaneLibError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted; no partial output was left behind", file=sys.stderr)
        return 130
