"""Batch runs shared by every pipeline: a folder of images, or a video, frame by frame.

A run takes a ``process`` callable that turns one RGB frame into an output frame and a row of
numbers; this module does the reading, writing, progress bar, per-frame CSV log and results file,
all written atomically and never over an input. The advanced pipeline (``pipeline``) and the basic
Hough pipeline (``hough``) both run through here, so their CLI behaviour is the same.

Bad inputs: in a folder run, a file that cannot be read or processed (a lanelib error) gets its
own row with an ``error`` and the run goes on; a video that breaks off half-way keeps the frames
processed before the break and raises ``PartialOutputError`` once its outputs are in place.
"""
from __future__ import annotations

import csv
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np
from tqdm import tqdm

from . import io
from .errors import ConfigError, DecodeStoppedError, LaneLibError, PartialOutputError, naming_the_file

# process(rgb) -> (output rgb, row of JSON-able values)
ImageFn = Callable[[np.ndarray], tuple[np.ndarray, dict]]
# process(rgb, frame index, time in s) -> (output rgb, row of CSV values)
FrameFn = Callable[[np.ndarray, int, float], tuple[np.ndarray, dict]]


def _clean(value):
    """Return ``value`` as a JSON-safe scalar: numpy types unwrapped, NaN and inf as None."""
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


GRAYSCALE_NOTE = ("grayscale image: the colour masks (yellow) find nothing; gradient and "
                  "lightness masks still work")


def image_notes(info: io.ImageFileInfo) -> list[str]:
    """Return what a results row should say about how an image file was read (may be empty).

    A grey image (``GRAYSCALE_NOTE``), 16-bit samples scaled to 8 bits, and what the decoder
    printed about an image it could still decode (e.g. corrupt JPEG data).
    """
    notes = [GRAYSCALE_NOTE] if not info.colour else []
    if info.bit_depth == 16:
        notes.append("16-bit image: scaled to 8 bits (value >> 8)")
    notes += [f"the decoder warned: {m}" for m in info.decoder_messages]
    return notes


def run_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike, process: ImageFn,
               results_name: str = "results.json") -> list[dict]:
    """Process each image, write ``OUT_DIR/<name>`` and ``OUT_DIR/results.json``; return the rows.

    Each row is ``{"file": <input file name>, **row}``, with ``"note"`` when the image was grey,
    16-bit or slightly corrupt (``image_notes``). A file that fails with a lanelib error (unreadable,
    not an image, a size the calibration does not fit, ...) gets the row ``{"file": <name>,
    "error": <one line naming the file, the cause and the fix>}``, no output image, and the run
    goes on. Any other exception is a bug and stops the run, as does a ``ConfigError`` (a bad
    configuration fails every file alike).

    Raises
    ------
    InputError
        If the output folder is the input folder.
    """
    out = Path(out_dir)
    files = [Path(f) for f in files]
    if any(f.parent.resolve() == out.resolve() for f in files):
        raise io.InputError(f"{out}: the output folder is the input folder; choose another -o folder")
    rows = []
    for f in files:
        try:
            rgb, info = io.read_image_info(f)
            image, row = process(rgb)
            io.write_image(out / f.name, image, inputs=files)
        except ConfigError:
            raise
        except LaneLibError as e:
            rows.append({"file": f.name, "error": naming_the_file(str(e), f)})
            continue
        notes = image_notes(info)
        rows.append({"file": f.name, **{k: _clean(v) for k, v in row.items()},
                     **({"note": "; ".join(notes)} if notes else {})})
    io.write_json(out / results_name, rows, inputs=files)
    return rows


@dataclass(frozen=True)
class VideoRunSummary:
    """What a video run did: frames processed, wall time (s) and frames per second."""

    frames: int
    seconds: float
    fps: float


class _CsvLog:
    """A per-frame CSV log written to a temporary file and renamed into place at the end."""

    def __init__(self, path: Path | None, inputs: Iterable[Path]):
        self.path = path
        self._ctx = io.atomic_path(path, inputs=inputs) if path else None
        self._tmp = self._ctx.__enter__() if self._ctx else None
        self._fh = open(self._tmp, "w", newline="") if self._tmp else None
        self._writer = None

    def write(self, row: dict) -> None:
        if self._fh is None:
            return
        if self._writer is None:
            self._writer = csv.DictWriter(self._fh, fieldnames=list(row))
            self._writer.writeheader()
        self._writer.writerow({k: _format_csv(v) for k, v in row.items()})

    def finish(self, ok: bool) -> None:
        if self._fh is None:
            return
        self._fh.close()
        if ok:
            self._ctx.__exit__(None, None, None)
        else:
            try:
                self._ctx.__exit__(RuntimeError, RuntimeError("aborted"), None)
            except RuntimeError:
                pass


def _format_csv(v) -> str:
    v = _clean(v)
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def run_video(in_path: str | os.PathLike, out_path: str | os.PathLike, process: FrameFn,
              log_path: str | os.PathLike | None = None, progress: bool = True,
              desc: str = "frames", threads: int | None = None) -> VideoRunSummary:
    """Read a video, process every frame, write the output video (and per-frame CSV log).

    The output keeps the input's size and frame rate (H.264). A tqdm bar shows fps and ETA when
    ``progress`` is true. An empty, corrupt or missing input, or one in a codec ffmpeg cannot
    decode, raises ``InputError`` with nothing written; an exception or Ctrl-C mid-run removes the
    partial output and log.

    Raises
    ------
    PartialOutputError
        If the input stops decoding after some frames (``DecodeStoppedError``: truncated or
        corrupt): the output video and the log are finished and moved into place with the frames
        processed before the break, then this error says where decoding stopped and why, and
        what was written.
    """
    in_path = Path(in_path)
    reader = io.VideoReader(in_path)
    inputs = [in_path]
    log = _CsvLog(Path(log_path) if log_path else None, inputs)
    writer = io.VideoWriter(out_path, reader.info.fps, inputs=inputs, threads=threads)
    ok = False
    stopped: DecodeStoppedError | None = None
    n = 0
    t0 = time.perf_counter()
    try:
        bar = tqdm(total=reader.info.n_frames or None, desc=desc, unit="frame", disable=not progress,
                   dynamic_ncols=True)
        with bar:
            try:
                for frame in reader:
                    image, row = process(frame, n, n / reader.info.fps)
                    writer.write(image)
                    log.write(row)
                    bar.update(1)
                    n += 1
            except DecodeStoppedError as e:  # raised only after at least one frame
                stopped = e
        writer.close()
        ok = True
    finally:
        reader.close()
        if not ok:
            writer.abort()
        log.finish(ok)
    seconds = time.perf_counter() - t0
    if stopped is not None:
        wrote = f"wrote {n} frames to {writer.path}" + (f" and {n} rows to {log.path}" if log.path else "")
        raise PartialOutputError(f"{stopped}; {wrote}", n)
    return VideoRunSummary(n, seconds, n / seconds if seconds > 0 else float("nan"))
