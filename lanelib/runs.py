"""Batch runs of every pipeline: a folder of images, or a video, frame by frame.

The same two verbs on the two pipelines, each a thin ``process`` callable on shared machinery:

- the advanced pipeline (``LanePipeline``, ``LaneTracker`` through a video): ``process_images``,
  ``process_video``;
- the basic Hough pipeline (``hough.HoughLaneFinder``, ``hough.HoughTracker`` through a video):
  ``hough_images``, ``hough_video``.

``run_images`` and ``run_video`` take a ``process`` callable that turns one RGB frame into an
output frame and a row of numbers, and do the reading, writing, progress bar, per-frame CSV log
and results file, all written atomically and never over an input; so the two pipelines behave
the same on the command line. A video run returns one ``VideoRun`` record whichever the pipeline.

On Dask (``workers``/``scheduler``, ``cluster.dask_client``): a folder goes in chunks of files
(``image_chunk``), a video in segments of frames (``run_video_segments``, ``video_segment``)
that each start ``cluster.WARMUP_FRAMES`` early to warm the tracker up (a segment whose tracker
did not reach the previous segment's final state in that warm-up runs again from that state:
``cluster.settle_joints``, ``FrameState``; the evidence a ``GeometryWatch`` keeps for later is
carried through a segment's record of its checks instead, ``carry_lane_state``, and the
segments that started from the wrong geometry, as the records of the checks show, run again at
once from the one process's, ``plan_lane_restarts``), joined without re-encoding; the ``process``
callables are built on the workers by picklable factories (``lane_image_process``,
``lane_video_process``, ``hough_image_process``, ``hough_video_process``), so the rows, logs
and results are those of one process.

Bad inputs: in a folder run, a file that cannot be read or processed (a lanelib error) gets its
own row with an ``error`` and the run goes on; a video that breaks off half-way keeps the frames
processed before the break and raises ``PartialOutputError`` once its outputs are in place.
"""
from __future__ import annotations

import csv
import functools
import hashlib
import math
import os
import pickle
import shutil
import tempfile
import time
from collections import deque
from dataclasses import dataclass, replace
from pathlib import Path, PurePosixPath
from typing import Callable, Iterable, Sequence

import numpy as np
from tqdm import tqdm

from . import autogeometry, cluster, hough, io
from .benchmarks import culane, tusimple
from .camera import Calibration
from .config import PipelineConfig, benchmark_config, to_dict
from .errors import (ConfigError, DecodeStoppedError, GeometryError, InputError, LaneLibError,
                     PartialOutputError, naming_the_file)
from .autogeometry import RoadGeometry
from .perspective import DEFAULT_LANE_WIDTH_M
from .pipeline import LanePipeline, pipeline_for
from .result import FrameResult, LinesResult
from .tracking import LaneTracker

# process(rgb) -> (output rgb, row of JSON-able values)
ImageFn = Callable[[np.ndarray], tuple[np.ndarray, dict]]
# process(rgb, frame index, time in s) -> (output rgb, row of CSV values, whether the lane was found)
FrameFn = Callable[[np.ndarray, int, float], tuple[np.ndarray, dict, bool]]


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


def _image_row(f: Path, out: Path, process: ImageFn, files: Sequence[Path]) -> dict:
    """Return the results row of one image after processing it and writing its output image."""
    try:
        rgb, info = io.read_image_info(f)
        image, row = process(rgb)
        io.write_image(out / f.name, image, inputs=files)
    except ConfigError:
        raise
    except LaneLibError as e:
        return {"file": f.name, "error": naming_the_file(str(e), f)}
    notes = image_notes(info)
    return {"file": f.name, **{k: _clean(v) for k, v in row.items()},
            **({"note": "; ".join(notes)} if notes else {})}


def image_chunk(chunk: Sequence[Path], out_dir: Path, make: Callable[[], ImageFn],
                files: Sequence[Path]) -> list[dict]:
    """Return the results rows of a chunk of images (a Dask task of ``run_images``): ``make()``
    gives the chunk's ``process`` (its pipelines built once per chunk)."""
    process = make()
    return [_image_row(f, out_dir, process, files) for f in chunk]


def run_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike, process: ImageFn | None,
               results_name: str = "results.json", make: Callable[[], ImageFn] | None = None,
               client=None, progress: bool = True) -> list[dict]:
    """Process each image, write ``OUT_DIR/<name>`` and ``OUT_DIR/results.json``; return the rows.

    Each row is ``{"file": <input file name>, **row}``, with ``"note"`` when the image was grey,
    16-bit or slightly corrupt (``image_notes``). A file that fails with a lanelib error (unreadable,
    not an image, a size the calibration does not fit, ...) gets the row ``{"file": <name>,
    "error": <one line naming the file, the cause and the fix>}``, no output image, and the run
    goes on. Any other exception is a bug and stops the run, as does a ``ConfigError`` (a bad
    configuration fails every file alike).

    With a Dask ``client`` (``cluster.dask_client``) the files go in chunks to its workers
    (``cluster.map_items``, one progress bar unless ``progress`` is false), each chunk processed
    by the ``process`` that ``make()`` (a picklable factory, e.g. a ``functools.partial`` of a
    module-level function) builds there; the workers write the images, this process the results
    file, with the rows of one process.

    Raises
    ------
    InputError
        If the output folder is the input folder.
    """
    out = Path(out_dir)
    files = [Path(f) for f in files]
    if any(f.parent.resolve() == out.resolve() for f in files):
        raise io.InputError(f"{out}: the output folder is the input folder; choose another -o folder")
    if client is None:
        process = process if process is not None else make()
        rows = [_image_row(f, out, process, files) for f in files]
    else:
        with tqdm(total=len(files), desc=out.name, unit="image", disable=not progress,
                  dynamic_ncols=True) as bar:
            rows = cluster.map_items(client, image_chunk, files, bar, out_dir=out, make=make, files=files)
    io.write_json(out / results_name, rows, inputs=files)
    return rows


@dataclass(frozen=True)
class VideoRun:
    """What a video run did: frames, wall time (s), frames per second, frames with a lane found.

    ``found_frames`` counts the frames whose ``process`` said found: for ``process_video`` a lane
    that passed the checks (tracked, held or inferred included), for ``hough_video`` both lines
    (measured or held). ``first_frame`` is the clip's index of the first frame processed (0
    unless the run started later: ``start_s``); the frames run ``first_frame .. first_frame +
    frames - 1`` of the clip.
    """

    frames: int
    seconds: float
    fps: float
    found_frames: int
    first_frame: int = 0
    notes: tuple[str, ...] = ()  # what happened on the way (e.g. the road geometry re-estimated)
    joints: cluster.Joints | None = None  # on Dask: how the segments' joints were made exact


# a frame whose time is a hair (float rounding) before a bound counts as at the bound
_BOUND_EPS_FRAMES = 1e-6


def clip_frames(info: io.VideoInfo, start_s: float | None = None, end_s: float | None = None) -> range:
    """Return the clip's frame indices from ``start_s`` to ``end_s`` (seconds; None: the clip's start, end).

    Frame ``i`` shows from ``i / fps`` (``io.exact_fps``): the range holds the frames from the
    first one at or after ``start_s`` to the last one before ``end_s`` (``--start 2 --end 3`` at
    25 fps: frames 50..74). An ``end_s`` beyond the clip's end runs to its last frame.

    Raises
    ------
    InputError
        If a bound is negative or not a number, if ``start_s`` is not before ``end_s``, if
        ``start_s`` is at or beyond the clip's end, or if no frame starts between the two; the
        message names the clip, its duration and the fix.
    """
    n, fps = info.n_frames, io.exact_fps(info.fps)
    duration = n / fps
    clip = f"{info.path}: the clip is {duration:.3f} s long ({n} frames at {info.fps:g} fps)"
    for name, value in (("start", start_s), ("end", end_s)):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise InputError(f"{clip}; --{name} {value:g} s is not a time in it; pass a time in "
                             f"seconds from 0 to {duration:.3f}")
    if start_s is not None and end_s is not None and start_s >= end_s:
        raise InputError(f"{clip}; --start {start_s:g} s is not before --end {end_s:g} s; pass a "
                         "start time before the end time")
    last_s = (n - 1) / fps
    if start_s is not None and start_s * fps > n - 1 + _BOUND_EPS_FRAMES:
        where = ("is at or beyond its end" if start_s * fps >= n - _BOUND_EPS_FRAMES else
                 f"is after its last frame, which starts at {last_s:.3f} s")
        raise InputError(f"{clip}; --start {start_s:g} s {where}; pass a start time from 0 to "
                         f"{last_s:.3f} s")
    first = 0 if start_s is None else max(0, math.ceil(start_s * fps - _BOUND_EPS_FRAMES))
    stop = n if end_s is None else min(n, math.ceil(end_s * fps - _BOUND_EPS_FRAMES))
    if stop <= first:
        raise InputError(f"{clip}; no frame starts from {start_s or 0:g} s to before --end "
                         f"{end_s:g} s (frames are {1 / fps:.3f} s apart); pass a longer span")
    return range(first, stop)


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
              desc: str = "frames", threads: int | None = None, start_s: float | None = None,
              end_s: float | None = None) -> VideoRun:
    """Return what a run did after processing every frame and writing the output video (and log).

    ``process(frame, index, time_s)`` returns the output frame, the row of the per-frame CSV log
    and whether the lane was found in the frame (counted in ``VideoRun.found_frames``). The
    output keeps the input's size and frame rate (H.264). A tqdm bar shows fps and ETA when
    ``progress`` is true. An empty, corrupt or missing input, or one in a codec ffmpeg cannot
    decode, raises ``InputError`` with nothing written; an exception or Ctrl-C mid-run removes the
    partial output and log.

    ``start_s``, ``end_s`` (seconds, either may be None) run on part of the clip: the frames
    ``clip_frames`` gives, from the first at or after ``start_s`` to the last before ``end_s``.
    Decoding seeks to the first one (``io.VideoReader(start=...)``) and stops after the last.
    ``index`` and ``time_s`` stay those of the source clip (``index / fps``: frame 50 of a 25 fps
    clip is 2.0 s whatever the start), so a log row names the source frame it came from; the
    output video holds only the part, from its own time 0. Bad bounds raise ``InputError``
    (``clip_frames``) before anything is written.

    Raises
    ------
    PartialOutputError
        If the input stops decoding after some frames (``DecodeStoppedError``: truncated or
        corrupt): the output video and the log are finished and moved into place with the frames
        processed before the break, then this error says where decoding stopped and why, and
        what was written.
    """
    in_path = Path(in_path)
    if start_s is None and end_s is None:
        reader = io.VideoReader(in_path)
        frames = range(reader.info.n_frames)
    else:
        info = io.video_info(in_path)
        frames = clip_frames(info, start_s, end_s)
        reader = io.VideoReader(in_path, frames.start, frames.stop if end_s is not None else None, info)
    inputs = [in_path]
    log = _CsvLog(Path(log_path) if log_path else None, inputs)
    writer = io.VideoWriter(out_path, reader.info.fps, inputs=inputs, threads=threads)
    ok = False
    stopped: DecodeStoppedError | None = None
    n = found = 0
    first = frames.start
    t0 = time.perf_counter()
    try:
        bar = tqdm(total=len(frames) or None, desc=desc, unit="frame", disable=not progress,
                   dynamic_ncols=True)
        with bar:
            try:
                for frame in reader:
                    index = first + n
                    image, row, lane = process(frame, index, index / reader.info.fps)
                    found += bool(lane)
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
    return VideoRun(n, seconds, n / seconds if seconds > 0 else float("nan"), found, first)


@dataclass(frozen=True)
class FrameState:
    """How a video's ``process`` carries its state (the tracker) from frame to frame, for the
    joints of Dask segments (``cluster.settle_joints``): ``key()`` the fingerprint of the state
    now (equal keys: the same results on the same next frames), ``get()`` the state (picklable),
    ``put(state)`` go on from a state that ``get`` gave in another process (before any frame)."""

    key: Callable[[], bytes | None]
    get: Callable[[], object]
    put: Callable[[object], None]
    core: Callable[[], bytes | None] = lambda: None  # the part the results depend on now (``cluster.Carry``)


# a FrameFn, the list its notes go to (what happened on the way: GeometryWatch.notes) and its state
FrameFnMaker = Callable[[], tuple[FrameFn, list[str], FrameState]]


@dataclass(frozen=True)
class SegmentOutcome:
    """What ``video_segment`` did with one segment: the log rows of its kept frames, the frames
    with a lane found, where decoding stopped (empty when it did not) and the notes of its kept
    frames (a warm-up's are the previous segment's)."""

    rows: tuple[dict, ...]
    found: int
    stopped: str = ""
    notes: tuple[str, ...] = ()
    carry: cluster.Carry = cluster.Carry()  # the state at its ends, to check its joints


def video_segment(chunk: Sequence[tuple[int, int, int, bool]], in_path: Path, parts: Path,
                  make: FrameFnMaker, threads: int | None = None, state: object = None
                  ) -> list[SegmentOutcome]:
    """Return the outcome of each segment of a chunk after writing its part video (a Dask task).

    A segment ``(first, start, stop, to_end)`` (``cluster.segments``) is run from frame
    ``first`` with a fresh ``make()``; the frames before ``start`` only warm the tracker up and
    are dropped; the frames ``start .. stop - 1`` (to the clip's end when ``to_end``) go to
    ``parts/<start>.mp4`` (written atomically, only when it holds a frame). A clip that stops
    decoding in the segment (or before it) ends the segment there, with ``stopped`` saying why.
    ``state`` (``FrameState.get`` of another process, or planned: ``plan_lane_restarts``): the
    segments go on from it, not from a fresh state (a re-run of a joint that did not settle in
    the warm-up, from ``start``; a restart from the warm-up with the geometry planned). Each outcome's
    ``carry`` holds the state's fingerprint before frame ``start`` and the state after the last.
    """
    out = []
    for first, start, stop, to_end in chunk:
        process, notes, carried = make()
        if state is not None:
            carried.put(state)
        rows, found, stopped, entry, entry_core, noted = [], 0, "", None, None, len(notes)
        writer = None
        try:
            try:
                reader = io.VideoReader(in_path, first, None if to_end else stop)
                writer = io.VideoWriter(parts / f"{start:09d}.mp4", reader.info.fps, inputs=[in_path],
                                        threads=threads)
                with reader:
                    for n, frame in enumerate(reader):
                        index = first + n
                        if index == start:
                            entry, entry_core, noted = carried.key(), carried.core(), len(notes)
                        image, row, lane = process(frame, index, index / reader.info.fps)
                        if index >= start:
                            writer.write(image)
                            rows.append(row)
                            found += bool(lane)
            except DecodeStoppedError as e:
                stopped = str(e)
            except InputError as e:  # no frame from `first` on: the clip broke off before
                if writer is None and first == 0:
                    raise
                stopped = str(e)
            if writer is not None and writer.frames_written:
                writer.close()
            elif writer is not None:
                writer.abort()
        except BaseException:
            if writer is not None:
                writer.abort()
            raise
        carry = cluster.Carry(entry, carried.key(), carried.get(), entry_core, carried.core())
        out.append(SegmentOutcome(tuple(rows), found, stopped, tuple(notes[noted:] if rows else ()), carry))
    return out


def run_video_segments(in_path: str | os.PathLike, out_path: str | os.PathLike, make: FrameFnMaker,
                       client, log_path: str | os.PathLike | None = None, progress: bool = True,
                       desc: str = "frames", threads: int | None = None, start_s: float | None = None,
                       end_s: float | None = None, warmup: int = cluster.WARMUP_FRAMES,
                       carry: Callable[[object, object, int], tuple[object, bytes] | None] | None = None,
                       plan: Callable[[object, Sequence[object], Sequence[tuple[int, int, int, bool]]],
                                      dict[int, object]] | None = None) -> VideoRun:
    """Return what a run did, as ``run_video``, with the clip split into segments run by the
    workers of a Dask ``client``.

    The frames (all, or ``start_s`` .. ``end_s``: ``clip_frames``) are split into consecutive
    segments (``cluster.segments``, ``cluster.segment_count``); each worker runs a fresh
    ``make()`` over its segment from ``warmup`` frames earlier (the warm-up frames are dropped)
    and writes the segment's video to a folder of parts beside ``out_path``. Each joint is then
    checked (``cluster.settle_joints``): where the warm-up did not bring the tracker to the state
    the previous segment ended in, the segment is run again from that state, so the frames and
    the log are those of one process; ``VideoRun.joints`` counts the re-runs. ``carry(state
    before, end state, start)`` (``carry_lane_state``): where the states differ only in evidence
    kept for later (``FrameState.core``), carry the previous state through the segment instead
    of running it again (``cluster.settle_joints``). ``plan(fresh state, end states, segments)``
    (``plan_lane_restarts``): before the joints are checked, the segments whose start was wrong
    as the end states' records tell (``fresh state``: ``make()``'s before any frame), each with
    the state to run it again from its warm-up; they run again at once (one round). This process joins
    the parts (``io.join_videos``, no re-encoding) and writes the per-frame log, both
    atomically, and removes the parts. One progress bar counts the frames of the segments done
    (re-runs included). A clip that stops decoding keeps the frames before the break, as
    ``run_video`` (``PartialOutputError``).
    """
    in_path, out = Path(in_path), Path(out_path)
    t0 = time.perf_counter()
    info = io.video_info(in_path)
    whole = start_s is None and end_s is None
    frames = range(info.n_frames) if whole else clip_frames(info, start_s, end_s)
    inputs = [in_path]
    io.check_not_input(out, inputs)
    if log_path is not None:
        io.check_not_input(log_path, inputs + [out])
    count = cluster.segment_count(len(frames), cluster.total_threads(client), warmup)
    spans = cluster.segments(frames, count, warmup)
    segs = [(first, start, stop, end_s is None and stop == frames.stop) for first, start, stop in spans]
    out.parent.mkdir(parents=True, exist_ok=True)

    def carry_on(k: int, before: object, o: SegmentOutcome) -> SegmentOutcome | None:
        got = None if carry is None else carry(before, o.carry.end_state, segs[k][1])
        return None if got is None else replace(o, carry=replace(o.carry, end_state=got[0], end_key=got[1]))

    def plan_restarts(outcomes: Sequence[SegmentOutcome]) -> dict[int, object]:
        ends = []
        for o in outcomes:
            ends.append(o.carry.end_state)
            if o.stopped:
                break
        return plan(make()[2].get(), ends, segs)

    parts = Path(tempfile.mkdtemp(prefix=f".{out.stem}.", suffix=".parts", dir=out.parent))
    try:
        with tqdm(total=len(frames) or None, desc=desc, unit="frame", disable=not progress,
                  dynamic_ncols=True) as bar:
            settled, joints = cluster.map_segments(client, video_segment, segs, bar, lambda o: o.carry,
                                                   lambda o: bool(o.stopped), rebase=carry_on,
                                                   plan=plan_restarts if plan is not None else None,
                                                   in_path=in_path.resolve(), parts=parts.resolve(),
                                                   make=make, threads=threads)
        outcomes, files = [], []
        for (_, start, _), o in zip(spans, settled):
            outcomes.append(o)
            if o.rows:
                files.append(parts / f"{start:09d}.mp4")
            if o.stopped:
                break
        if not files:
            raise InputError(f"{in_path}: no frame could be decoded ({outcomes[0].stopped}); "
                             "pass a readable video")
        log = _CsvLog(Path(log_path) if log_path else None, inputs)
        ok = False
        try:
            for o in outcomes:
                for row in o.rows:
                    log.write(row)
            io.join_videos(files, out, inputs=inputs)
            ok = True
        finally:
            log.finish(ok)
    finally:
        shutil.rmtree(parts, ignore_errors=True)
    n = sum(len(o.rows) for o in outcomes)
    found = sum(o.found for o in outcomes)
    seconds = time.perf_counter() - t0
    notes = tuple(note for o in outcomes for note in o.notes)
    stopped = next((o.stopped for o in outcomes if o.stopped), "")
    if stopped:
        wrote = f"wrote {n} frames to {out}" + (f" and {n} rows to {log_path}" if log_path else "")
        raise PartialOutputError(f"{stopped}; {wrote}", n)
    return VideoRun(n, seconds, n / seconds if seconds > 0 else float("nan"), found, frames.start, notes,
                    joints)


# --------------------------------------------------------------------------- road geometry from frames

@dataclass(frozen=True)
class GeometryOptions:
    """How ``--auto-geometry`` estimates the road geometry and, through a video, checks it.

    Parameters
    ----------
    lane_width_m, look_ahead_m, dash_m, gap_m, focal_px : as for ``autogeometry.estimate_geometry``.
    seconds : of a video read for the estimate, from its start (or from ``start_s``).
    max_frames : frames of those (or of a folder's images) used, evenly spread.
    check_every_s : through a video, the vanishing point is measured this often
        (``autogeometry.RoadLineFinder``, about 15 ms a frame); the straight checks refine it
        along the horizon (``GeometryWatch``).
    drift_checks : this many checks in a row with the vanishing point off the horizon (by more
        than ``autogeometry.DRIFT_PX`` or 1 % of the height: a crest, a dip, a knocked camera) call
        for a new estimate from those frames (fewer than ``autogeometry.MIN_GOOD_FRAMES``, 5, give
        too little confidence for a new estimate to be used).
    accept_low_confidence : use an estimate below ``autogeometry.LOW_CONFIDENCE`` (refused otherwise).
    """

    lane_width_m: float = DEFAULT_LANE_WIDTH_M
    look_ahead_m: float = autogeometry.DEFAULT_LOOK_AHEAD_M
    dash_m: float = autogeometry.DEFAULT_DASH_M
    gap_m: float = autogeometry.DEFAULT_GAP_M
    focal_px: float | None = None
    seconds: float = 20.0
    max_frames: int = 50
    check_every_s: float = 0.5
    drift_checks: int = 5
    accept_low_confidence: bool = False

    def __post_init__(self):
        if not (self.seconds > 0 and self.max_frames >= 1 and self.check_every_s > 0
                and self.drift_checks >= 1):
            raise ConfigError("geometry options: seconds and check_every_s must be positive, "
                              "max_frames and drift_checks 1 or more")

    def estimate(self, frames: Sequence[np.ndarray], calibration: Calibration | None,
                 hood_row_px: float | None = None, lens_from_road: bool = True) -> RoadGeometry:
        """Return ``autogeometry.estimate_geometry`` of ``frames`` with these options.

        ``lens_from_road``: with no calibration, let the estimate measure the lens from the lane
        lines' bend (``autogeometry.estimate_lens``); a run then undistorts with it
        (``geometry_calibration``). Off for callers that cannot undistort with it.
        """
        return autogeometry.estimate_geometry(frames, calibration, focal_px=self.focal_px,
                                          lane_width_m=self.lane_width_m, look_ahead_m=self.look_ahead_m,
                                          dash_m=self.dash_m, gap_m=self.gap_m, hood_row_px=hood_row_px,
                                          lens_from_road=lens_from_road)


def sample_frames(source: str | os.PathLike, seconds: float | None = None, max_frames: int = 50,
                  start_s: float | None = None) -> list[np.ndarray]:
    """Return up to ``max_frames`` frames of a video (from ``start_s``, over ``seconds``) or of a
    folder of images (by name), evenly spread.

    Raises
    ------
    InputError
        If the source is missing, unreadable, or holds no frame; an image that cannot be read
        names itself.
    """
    path = Path(source)
    if path.is_dir():
        files = io.list_images(path)
        step = max(1, math.ceil(len(files) / max_frames))
        return [io.read_image(f) for f in files[::step]]
    if not path.exists():
        raise InputError(f"{path}: no such file or folder; check the path")
    info = io.video_info(path)
    end = None if seconds is None else (start_s or 0.0) + seconds
    span = clip_frames(info, start_s, end if end is None or end * info.fps < info.n_frames else None)
    step = max(1, math.ceil(len(span) / max_frames))
    out = []
    with io.VideoReader(path, span.start, span.stop, info) as reader:
        for i, frame in enumerate(reader):
            if i % step == 0:
                out.append(frame)
    return out


def estimate_road_geometry(source: str | os.PathLike, calibration: Calibration | None = None,
                           options: GeometryOptions = GeometryOptions(),
                           start_s: float | None = None, lens_from_road: bool = True) -> RoadGeometry:
    """Return the road geometry estimated from a video's first ``options.seconds`` or a folder
    (``lens_from_road``: as for ``GeometryOptions.estimate``).

    Raises
    ------
    GeometryError
        If the frames give no consistent vanishing point (the reason: no road, too few
        segments, inconsistent, road not straight), or if the estimate's confidence is below
        ``autogeometry.LOW_CONFIDENCE`` and ``options.accept_low_confidence`` is off: a low
        confidence result is never used silently.
    """
    frames = sample_frames(source, options.seconds, options.max_frames, start_s)
    return checked_geometry(frames, source, calibration, options, lens_from_road)


def checked_geometry(frames: Sequence[np.ndarray], source: str | os.PathLike,
                     calibration: Calibration | None, options: GeometryOptions,
                     lens_from_road: bool = True) -> RoadGeometry:
    """Return the road geometry of ``frames`` (taken from ``source``, a video or a folder;
    ``lens_from_road``: as for ``GeometryOptions.estimate``).

    Raises
    ------
    GeometryError
        As ``estimate_road_geometry``: no consistent vanishing point, or a confidence below
        ``autogeometry.LOW_CONFIDENCE`` without ``options.accept_low_confidence``; the message names
        ``source`` and the fix.
    """
    try:
        geo = options.estimate(frames, calibration, lens_from_road=lens_from_road)
    except GeometryError as e:
        raise GeometryError(naming_the_file(str(e), Path(source))) from None
    if geo.low_confidence and not options.accept_low_confidence:
        fixes = ([] if calibration is not None or options.focal_px else ["a calibration (--calibration)"])
        fixes.append("frames of a longer straight stretch" + ("" if Path(source).is_dir() else
                                                              " (--geometry-seconds)"))
        raise GeometryError(f"{source}: {_low_confidence(geo, len(frames))} ({'; '.join(geo.assumptions)}); "
                            f"give {' or '.join(fixes)}, or pass --accept-low-confidence to use it anyway")
    return geo


def _low_confidence(geo: RoadGeometry, n_frames: int) -> str:
    """Return why ``geo``, estimated from ``n_frames`` frames, is refused for its confidence."""
    return (f"the road geometry estimated from {n_frames} frames ({len(geo.frames_used)} on straight "
            f"road) has confidence {geo.confidence:.2f}, below {autogeometry.LOW_CONFIDENCE}")


def geometry_calibration(calibration: Calibration | None, geo: RoadGeometry) -> Calibration | None:
    """Return the calibration to run with ``geo``: the one given, else the lens the estimate
    measured from the road's lines (``RoadGeometry.lens``; its points are for frames undistorted
    with it), else None."""
    return calibration if calibration is not None else geo.lens


def with_geometry(config: PipelineConfig, geo: RoadGeometry) -> PipelineConfig:
    """Return ``config`` with the bird's-eye points and scale of ``geo``."""
    return replace(config, perspective=geo.perspective_config())


# The watch refines the vanishing point's place along the horizon (the car's straight-ahead
# direction: the road's, on average over straight road) from the straight checks' points:
# at least this many of them, and at least as many as the estimate in use rests on (its
# ``frames_used``), so that a refinement rests on more straight road than the estimate it corrects
REFINE_MIN_CHECKS = 2 * autogeometry.MIN_GOOD_FRAMES
# ... and only when their median lies farther from the point in use than its standard error plus
# this share of the width: the straight checks' column spreads 0.2-0.55 % of the width from one
# check to the next (1.9 and 4.0 px on the 960 px P1 clips, 7.0 px on the 1280 px project video:
# median |difference| / 0.95); a shift smaller than one check's noise is not worth restarting the
# tracker for, and it is the hysteresis that keeps the point from going back and forth
REFINE_TOLERANCE = 0.005
# the last this many straight checks count (5 minutes of straight road at 2 checks a second), and
# the record of them a Dask joint reads holds as many: a watch pickles in at most ~35 kB (points
# 12 kB, record 20 kB) however long the video
REFINE_MAX_CHECKS = 600


class _NeedsFrames(Exception):
    """A watch carried through a record of checks (no frames) reached a new estimate."""


class GeometryWatch:
    """Through a video, check the road geometry: refine the vanishing point along the horizon as
    straight road accumulates, and estimate the geometry again when the horizon moves.

    ``check(frame, index, time_s)`` measures the frame's vanishing point every
    ``options.check_every_s``; frames where the road bends say nothing (``VanishingPoint.ok``).
    It returns the geometry to use from this frame on when it changed (None otherwise); ``notes``
    says what happened and why.

    - **Drift.** After ``options.drift_checks`` checks in a row whose point lies off the horizon
      (``RoadGeometry.horizon_shift_px`` beyond ``autogeometry.DRIFT_PX`` or 1 % of the height: a
      crest, a dip, a knocked camera) it estimates the geometry from those frames. A failed or
      low-confidence new estimate keeps the old autogeometry. A new estimate starts the refinement
      afresh.
    - **Refinement.** The first estimate's point is where the road headed, on average, in the
      first seconds' straight frames: a gentle curve or the car's wander across its lane puts
      it a few px aside, which moves the car's column in the bird's-eye view and so the
      offset read. The points of the straight checks on the horizon (the last
      ``REFINE_MAX_CHECKS``) are kept; once there are ``REFINE_MIN_CHECKS`` of them and at least
      as many as the estimate in use rests on, and their median along the horizon lies
      farther from the point in use than its standard error (1.25 x 1.48 x MAD / sqrt(n))
      plus ``REFINE_TOLERANCE`` of the width, the point moves to the median
      (``autogeometry.refined_geometry``: the horizon, hood, scale and look-ahead are kept). The
      next move takes twice as many points (and the median off the new point by as much): the
      checks, half a second apart, follow the car's weave across its lane for seconds, so the
      standard error of n of them is too small until they span several weaves; doubling the
      evidence each time keeps the point from going back and forth and leaves at most a few
      moves in a video (10, 20, 40, ... points).

    A watch pickles without its ``finder`` (its undistortion maps and hood mask, megabytes),
    which the copy builds again on first use: a Dask segment ships it back to the driver.
    """

    def __init__(self, geo: RoadGeometry, calibration: Calibration | None, options: GeometryOptions,
                 fps: float):
        self.geometry = geo
        self.calibration = calibration
        self.options = options
        self.every = max(1, round(options.check_every_s * fps))
        self._finder: autogeometry.RoadLineFinder | None = None  # built on first use (``finder``)
        self.tolerance_px = max(autogeometry.DRIFT_PX, 0.01 * geo.size_px[1])
        self.refine_tolerance_px = REFINE_TOLERANCE * geo.size_px[0]
        self.refine_min = max(REFINE_MIN_CHECKS, len(geo.frames_used))  # points the next refinement takes
        self.off: deque[np.ndarray] = deque(maxlen=options.drift_checks)
        self.shifts: list[float] = []
        self.points: deque[tuple[float, float]] = deque(maxlen=REFINE_MAX_CHECKS)
        # a record of the straight checks (index, time, point) and the last frame the geometry
        # changed at: a Dask joint carries the evidence through a segment by them (``carried_through``)
        self.record: deque[tuple[int, float, float, float]] = deque(maxlen=REFINE_MAX_CHECKS)
        self.recorded = 0
        self.changed_at = -1
        self.notes: list[str] = []

    @property
    def finder(self) -> autogeometry.RoadLineFinder:
        """The frames' vanishing-point finder, built on first use: for the geometry's frame size
        and hood row (a new estimate keeps both: the hood is the car's) and the calibration."""
        if self._finder is None:
            self._finder = autogeometry.RoadLineFinder(self.geometry.size_px, lens=self.calibration,
                                                   hood_top_px=self.geometry.hood_row_px)
        return self._finder

    def __getstate__(self) -> dict:
        return self.__dict__ | {"_finder": None}

    def state_key(self) -> bytes:
        """Return a fingerprint of what the next checks depend on: the geometry in use, the
        horizon shifts of the checks off it in a row (their frames are those checks') and the
        straight checks' points kept for the refinement."""
        return hashlib.sha256(pickle.dumps((self.geometry, self.shifts, tuple(self.points),
                                            self.refine_min))).digest()

    def core_key(self) -> bytes:
        """Return a fingerprint of what the frames' results depend on until the geometry changes:
        the geometry in use and the horizon shifts of the checks off it in a row."""
        return hashlib.sha256(pickle.dumps((self.geometry, self.shifts))).digest()

    def carried_through(self, other: GeometryWatch, start: int) -> GeometryWatch | None:
        """Return this watch (the state before frame ``start``) carried through the straight
        checks ``other`` made from ``start`` on, or None when they would have changed the
        geometry, or called for a new estimate, or ``other`` no longer holds them all.

        A Dask segment starts with a fresh watch; when its geometry and run of checks off the
        horizon at ``start`` are this watch's (``core_key``) and it changed nothing from there,
        its frames are those this watch would have given too unless this watch's evidence
        (the points a refinement rests on) would have changed the geometry on the way.
        """
        if other.changed_at >= start:
            return None
        checks = [c for c in other.record if c[0] >= start]
        if other.recorded > len(other.record) and (not other.record or other.record[0][0] >= start):
            return None  # the record lost some of them
        got = self.replayed(checks)
        if got is None or got[1]:
            return None
        copy = got[0]
        copy.off = deque(other.off, maxlen=other.off.maxlen)  # the frames of the same checks
        copy.notes = []
        return copy

    def replayed(self, checks: Sequence[tuple[int, float, float, float]]) -> tuple[GeometryWatch, list[int]] | None:
        """Return a copy of this watch carried through straight checks ``(index, time_s, x, y)``
        (a ``record``) as ``check`` would have gone through them, and the frames at which it
        changed the geometry on the way; None where a new estimate was due (it takes frames).

        A check's point does not depend on the geometry in use (``finder``: the frame size, the
        lens and the hood row, which a refined or new estimate keeps), nor which frames are
        checked (every ``every``-th): any run's record of a frame's check is every run's. The
        copy's ``off`` holds None for the frames of checks off the horizon in a row.
        """
        copy = pickle.loads(pickle.dumps(self))
        changed = []
        for index, time_s, x, y in checks:
            copy.record.append((index, time_s, x, y))
            copy.recorded += 1
            try:
                if copy._step((x, y), None, index, time_s) is not None:
                    copy.changed_at = index
                    changed.append(index)
            except _NeedsFrames:
                return None
        return copy, changed

    def check(self, frame: np.ndarray, index: int, time_s: float) -> RoadGeometry | None:
        if index % self.every:
            return None
        vp = self.finder.vanishing_point(frame)
        if not vp.ok:
            return None  # a bend, a frame without lines: says nothing about the horizon
        point = (float(vp.point_px[0]), float(vp.point_px[1]))
        self.record.append((index, time_s) + point)
        self.recorded += 1
        new = self._step(point, frame, index, time_s)
        if new is not None:
            self.changed_at = index
        return new

    def _step(self, point: tuple[float, float], frame: np.ndarray | None, index: int,
              time_s: float) -> RoadGeometry | None:
        """Return the new geometry after a straight check's point, or None (``check``); without
        its ``frame`` (``carried_through``), raise ``_NeedsFrames`` where a new estimate is due."""
        shift = self.geometry.horizon_shift_px(point)
        if abs(shift) <= self.tolerance_px:
            self.off.clear()
            self.shifts.clear()
            self.points.append(point)
            return self._refine(index, time_s)
        self.off.append(frame)
        self.shifts.append(shift)
        if len(self.off) < self.options.drift_checks:
            return None
        if frame is None:
            raise _NeedsFrames
        where = (f"frame {index} ({time_s:.2f} s): the vanishing point lay "
                 f"{abs(float(np.median(self.shifts))):.1f} px {'below' if np.median(self.shifts) > 0 else 'above'} "
                 f"the horizon in {len(self.off)} checks in a row")
        frames = list(self.off)
        self.off.clear()
        self.shifts.clear()
        try:  # the hood is the car's: it stays where it was
            new = self.options.estimate(frames, self.calibration, self.geometry.hood_row_px)
        except GeometryError as e:
            self.notes.append(f"{where}; a new estimate failed ({e}); the geometry is kept")
            return None
        if new.low_confidence and not self.options.accept_low_confidence:
            self.notes.append(f"{where}; the new estimate has confidence {new.confidence:.2f}, "
                              "below the limit; the geometry is kept")
            return None
        self.notes.append(f"{where}; geometry estimated again: horizon row "
                          f"{self.geometry.horizon_row_px:.1f} -> {new.horizon_row_px:.1f} px, "
                          f"{new.ym_per_px:.4f} m/px along (was {self.geometry.ym_per_px:.4f})")
        self.geometry = new
        self.points.clear()  # points about the old horizon (a knocked camera turned too)
        self.refine_min = max(REFINE_MIN_CHECKS, len(new.frames_used))
        return new

    def _refine(self, index: int, time_s: float) -> RoadGeometry | None:
        """Return the geometry with its vanishing point moved to the straight checks' median
        along the horizon when they place it off the point in use (class docstring), else None."""
        n = len(self.points)
        if n < self.refine_min:
            return None
        geo = self.geometry
        r = math.radians(geo.roll_deg)
        d = np.asarray(self.points) - np.asarray(geo.vanishing_point_px)
        along = d[:, 0] * math.cos(r) - d[:, 1] * math.sin(r)
        median = float(np.median(along))
        error = 1.2533 * 1.4826 * float(np.median(np.abs(along - median))) / math.sqrt(n)
        if abs(median) <= error + self.refine_tolerance_px:
            return None
        where = (f"frame {index} ({time_s:.2f} s): the {n} straight checks so far place the vanishing point "
                 f"{abs(median):.1f} px {'right' if median > 0 else 'left'} of the one in use along the horizon "
                 f"(median; standard error {error:.1f} px, tolerance {self.refine_tolerance_px:.1f} px)")
        try:
            new = autogeometry.refined_geometry(geo, median, f"vanishing point refined by {median:+.1f} px along the "
                                                         f"horizon from {n} straight checks through the video")
        except GeometryError as e:
            self.notes.append(f"{where}; not refined: {e}")
            self.refine_min = 2 * n  # tried again on twice the evidence, not at every check
            return None
        yaw = ("" if geo.yaw_deg is None else f", yaw {geo.yaw_deg:+.2f} -> {new.yaw_deg:+.2f} deg")
        (x0, y0), (x1, y1) = geo.vanishing_point_px, new.vanishing_point_px
        self.notes.append(f"{where}; refined: vanishing point ({x0:.1f}, {y0:.1f}) -> ({x1:.1f}, {y1:.1f}) px{yaw}")
        self.geometry = new
        self.refine_min = 2 * n
        return new


# --------------------------------------------------------------------------- the advanced pipeline

def lane_image_process(config: PipelineConfig, calibration: Calibration | None, debug: bool) -> ImageFn:
    """Return ``process_images``'s ``process``: one image -> (annotated image or debug composite,
    ``FrameResult.summary``), with one pipeline per frame size, built on first use."""
    cache: dict[tuple[int, int], LanePipeline] = {}

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        size = (rgb.shape[1], rgb.shape[0])
        if size not in cache:
            try:
                cache[size] = LanePipeline(config, calibration, size=size)
            except ConfigError:
                LanePipeline(config)  # a bad config raises here again: it fails every image alike
                w, h = config.perspective.size_px
                raise InputError(f"the image is {size[0]}x{size[1]} px, too small for the bird's-eye "
                                 "view (the perspective points collapse when scaled to it); pass "
                                 f"larger images (the config's points are for {w}x{h})") from None
        pipe = cache[size]
        result = pipe.process(rgb, keep_images=debug)
        image = pipe.debug_composite(result) if debug else result.images["result"]
        return image, result.summary()

    return process


def process_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                   config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                   debug: bool = False, workers: int = 1, scheduler: str | None = None,
                   progress: bool = True) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lane in each image and writing it annotated.

    Each row is the image's ``FrameResult.summary``. Frames of several sizes are allowed: one
    pipeline is built per size (the calibration is rescaled or refused per
    ``Calibration.for_size``). A file that cannot be read, an image too small for the bird's-eye
    view, or one whose size the calibration does not fit gets a row with an ``error``
    (``run_images``), and the run goes on. ``debug`` writes the 2x2 debug composite
    (``LanePipeline.debug_composite``) instead of the annotated frame. ``workers``,
    ``scheduler``: the images go in chunks to Dask workers (``cluster.dask_client``,
    ``run_images``; a progress bar unless ``progress`` is false), with the rows of one process.
    """
    make = functools.partial(lane_image_process, config, calibration, debug)
    with cluster.dask_client(workers, scheduler) as client:
        return run_images([Path(f) for f in files], out_dir, None, make=make, client=client,
                          progress=progress)


VIDEO_LOG_COLUMNS = ("frame", "time_s", "found", "method", "left_conf", "right_conf", "radius_m", "offset_m",
                     "lane_width_m", "left_a", "left_b", "left_c", "right_a", "right_b", "right_c",
                     "left_source", "right_source")


def video_log_row(frame: int, time_s: float, result: FrameResult) -> dict:
    """Return one row of the per-frame video log (``VIDEO_LOG_COLUMNS``; NaN where not found).

    The fit coefficients are the tracked bird's-eye pixel fits x = a*y**2 + b*y + c. ``method``
    is how the lane was found: ``windows`` or ``prior`` (seen in this frame), ``hold`` (held
    from earlier frames, not seen in this one), or the search tried when none was found.
    ``left_source``/``right_source`` say where each line comes from (``FrameResult.sources``:
    seen, edge, shoulder, inferred, held, or empty without a line).
    """
    nan = float("nan")
    row = {"frame": frame, "time_s": round(time_s, 4), "found": int(result.found),
           "method": result.method,
           "left_conf": result.left_conf, "right_conf": result.right_conf,
           "radius_m": result.radius_m, "offset_m": result.offset_m,
           "lane_width_m": result.lane_width_m}
    for side, fit in (("left", result.left), ("right", result.right)):
        coeffs = fit.coeffs_px if fit.found else (nan, nan, nan)
        row.update({f"{side}_{k}": v for k, v in zip("abc", coeffs)})
    row["left_source"], row["right_source"] = result.sources
    return row


def process_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                  config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                  debug: bool = False, log_path: str | os.PathLike | None = None,
                  progress: bool = True, threads: int | None = None, start_s: float | None = None,
                  end_s: float | None = None, auto_geometry: GeometryOptions | None = None,
                  on_geometry: Callable[[RoadGeometry], None] | None = None, workers: int = 1,
                  scheduler: str | None = None) -> VideoRun:
    """Return what the run did after tracking the lane through a video and writing it annotated.

    The lane is drawn on the RAW frames, mapped through the lens model (``config.draw.
    video_undistorted`` draws on undistorted frames instead, at one more remap per frame).

    Parameters
    ----------
    in_path, out_path : input video and output mp4 (H.264, the input's size and frame rate).
    config, calibration : as for ``LanePipeline``; the pipeline is made for the video's frame size.
    debug : write the 2x2 debug composite (undistorted, binary, search, result) instead.
    log_path : per-frame CSV with ``VIDEO_LOG_COLUMNS`` (optional).
    progress : show a tqdm bar with fps and ETA.
    threads : encoder threads (None: ffmpeg's choice).
    start_s, end_s : run on part of the clip (seconds; None: from its start, to its end): the
        frames from the first at or after ``start_s`` to the last before ``end_s``
        (``clip_frames``). The tracker starts fresh on the first of them; the log's ``frame``
        and ``time_s`` are the source clip's (``run_video``).
    auto_geometry : estimate the bird's-eye points and scale from the clip's first
        ``seconds`` (from ``start_s``) instead of ``config.perspective`` (``estimate_road_geometry``:
        a ``GeometryError`` before anything is written when that fails or is not confident), then
        keep checking them (``GeometryWatch``): the vanishing point is refined along the horizon
        as straight road accumulates, and the geometry estimated again when the horizon moves; a
        refined or new geometry restarts the tracker. The run's ``notes`` say when and why.
    on_geometry : called with the first estimate, before the run starts (the CLI prints it).
    workers, scheduler : run the clip in segments on Dask workers (``cluster.dask_client``,
        ``run_video_segments``: each segment starts ``cluster.WARMUP_FRAMES`` early to warm the
        tracker up, and runs again from the previous segment's tracker where that was not
        enough, so the frames and the log are those of one process). With ``auto_geometry`` the
        geometry is estimated once here; the geometry watch is part of the state checked at the
        joints (a drift found in one segment carries over into the next by a re-run); the
        straight checks a refinement rests on are carried through the next segment's record of
        its checks (``carry_lane_state``), which is run again only where they would have
        refined the geometry in it. The checks' points do not depend on the geometry in use, so
        the segments' records tell where one process changes the geometry: the segments that
        started from another geometry than its (every one after a refinement) run again at once
        from its watch (``plan_lane_restarts``; one round, ``VideoRun.joints.rounds``).

    Every output is written atomically by ``run_video``: an error or Ctrl-C leaves nothing under
    ``out_path`` or ``log_path``, except a video that stops decoding half-way: its outputs keep
    the frames before the break, and ``PartialOutputError`` says so.
    """
    geo = None
    if auto_geometry is not None:
        # before the cluster: a failed estimate stops the run before any worker starts
        geo = estimate_road_geometry(in_path, calibration, auto_geometry, start_s)
        calibration = geometry_calibration(calibration, geo)
        if on_geometry is not None:
            on_geometry(geo)
    fps = io.video_info(in_path).fps if geo is not None else None
    make = functools.partial(lane_video_process, config, calibration, debug, geo, auto_geometry, fps)
    with cluster.dask_client(workers, scheduler) as client:
        if client is not None:
            return run_video_segments(in_path, out_path, make, client, log_path=log_path,
                                      progress=progress, desc=Path(in_path).name, threads=threads,
                                      start_s=start_s, end_s=end_s,
                                      carry=carry_lane_state if geo is not None else None,
                                      plan=plan_lane_restarts if geo is not None else None)
    process, notes, _ = make()
    run = run_video(in_path, out_path, process, log_path=log_path, progress=progress,
                    desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)
    return replace(run, notes=tuple(notes))


def lane_video_process(config: PipelineConfig, calibration: Calibration | None, debug: bool,
                       geo: RoadGeometry | None = None, auto_geometry: GeometryOptions | None = None,
                       fps: float | None = None) -> tuple[FrameFn, list[str], FrameState]:
    """Return ``process_video``'s ``process`` (a fresh ``LaneTracker`` on the first frame), the
    list its notes go to and its state (the tracker; with ``geo`` also the geometry watch); with
    ``geo``, the road geometry in use, checked (``GeometryWatch`` at ``fps``), refined and
    estimated again when it drifts; a refined or new geometry restarts the tracker."""
    trackers: list[LaneTracker] = []  # made on the first frame, for the video's frame size
    watch: list[GeometryWatch] = []
    if geo is not None:
        config = with_geometry(config, geo)
        watch.append(GeometryWatch(geo, calibration, auto_geometry, fps))

    current = [config]  # the config of the geometry in use

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        new = watch[0].check(frame, index, time_s) if watch else None
        if new is not None:
            current[0] = with_geometry(config, new)
        if not trackers or new is not None:
            trackers[:] = [LaneTracker(pipeline_for(frame, current[0], calibration))]
        tracker = trackers[0]
        pipe = tracker.pipeline
        result = tracker.update(frame, keep_images=debug, index=index)
        if debug:
            image = pipe.debug_composite(result, raw=frame)
        elif config.draw.video_undistorted:
            image = pipe.annotate(pipe.undistort(frame), result)
        else:
            image = pipe.annotate(frame, result, raw=True)
        return image, video_log_row(index, time_s, result), result.found

    def key() -> bytes | None:
        return _lane_state_key(trackers[0] if trackers else None, watch[0] if watch else None)

    def core() -> bytes | None:
        if not trackers or not watch:
            return None
        return trackers[0].state_key() + watch[0].core_key()

    def get() -> object:
        return trackers[0] if trackers else None, current[0], watch[0] if watch else None

    def put(state: object) -> None:
        tracker, current[0], new = state
        trackers[:] = [tracker] if tracker is not None else []
        if new is not None:  # its notes were the other process's: this one's go to the list returned
            new.notes = watch[0].notes
            watch[0] = new

    return process, (watch[0].notes if watch else []), FrameState(key, get, put, core)


def _lane_state_key(tracker: LaneTracker | None, watch: GeometryWatch | None) -> bytes | None:
    """Return the fingerprint of ``lane_video_process``'s state: its tracker's and watch's."""
    if tracker is None:
        return None
    return tracker.state_key() + (watch.state_key() if watch is not None else b"")


def carry_lane_state(before: object, state: object, start: int) -> tuple[object, bytes] | None:
    """Return ``lane_video_process``'s state ``state`` (a segment's end, from a fresh start)
    with the geometry watch of ``before`` (the previous segment's end) carried through the
    segment's straight checks from frame ``start`` (``GeometryWatch.carried_through``), and its
    key; None when that would have changed the geometry (the segment must run again)."""
    tracker, config, watch = state
    watch = before[2].carried_through(watch, start) if watch is not None and before[2] is not None else None
    if watch is None:
        return None
    return (tracker, config, watch), _lane_state_key(tracker, watch)


def plan_lane_restarts(fresh: object, ends: Sequence[object], spans: Sequence[tuple[int, int, int, bool]]
                       ) -> dict[int, object]:
    """Return, for each Dask segment that started from the wrong geometry, the state of
    ``lane_video_process`` to run it again from, from its first (warm-up) frame: a fresh tracker
    and the geometry watch of one process at that frame (``cluster.settle_joints``' plan).

    ``fresh``: the state every segment started from (the first estimate, a fresh watch);
    ``ends``: the segments' end states after that start, in order; ``spans``: their
    ``(first, start, stop, to_end)``. The watch's checks measure the same points whatever the
    geometry in use (``GeometryWatch.replayed``), so a fresh watch carried through the segments'
    records frame by frame is the one process's watch: where its geometry at a segment's first
    frame, or its changes in the segment, differ from the fresh start's (a refinement in an
    earlier segment, or in this one on evidence from before it), the segment is planned to run
    again with it. The tracker is restarted by the geometry's change in one process, and warms
    up with the right geometry here; the joints' keys check the rest (a restarted segment that
    still did not settle runs again from the state before it). The plan ends (the later
    segments are left to the joints' checks) where the records cannot tell: a new estimate due
    (it takes the frames), checks off the horizon pending at a segment's first frame, a record
    that lost checks, a segment without a watch.
    """
    _, config, watch = fresh
    plan: dict[int, object] = {}
    if watch is None:
        return plan
    first_geometry = watch.geometry
    for k, end in enumerate(ends):
        own = end[2]
        first, _, stop, _ = spans[k]
        if own is None or own.recorded > len(own.record) or watch.off:
            break
        checks = list(own.record)  # the segment's checks from its first frame on
        if k > 0:
            got = watch.replayed([c for c in checks if c[0] < stop])
            if got is None:
                break
            if watch.geometry != first_geometry or got[1] or own.changed_at >= 0:
                start_watch = pickle.loads(pickle.dumps(watch))
                start_watch.notes = []
                plan[k] = (None, with_geometry(config, watch.geometry), start_watch)
        if k + 1 < len(ends):
            got = watch.replayed([c for c in checks if c[0] < spans[k + 1][0]])
            if got is None:
                break
            watch = got[0]
    return plan


# --------------------------------------------------------------------------- the basic Hough pipeline

def hough_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                 config: hough.HoughConfig = hough.HoughConfig(), workers: int = 1,
                 scheduler: str | None = None, progress: bool = True) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lines in each image and writing it annotated.

    Each row holds ``file``, ``left_found``, ``right_found``, each line's x (px) at the bottom
    row and at the top of the region (None when not found), and ``reason``
    (``HoughResult.row``); a file that cannot be read holds ``file`` and ``error`` instead, and
    the run goes on (``run_images``). ``workers``, ``scheduler``: on Dask, as ``process_images``.
    """
    make = functools.partial(hough_image_process, config)
    with cluster.dask_client(workers, scheduler) as client:
        return run_images(files, out_dir, None, make=make, client=client, progress=progress)


def hough_image_process(config: hough.HoughConfig) -> ImageFn:
    """Return ``hough_images``'s ``process``: one image -> (annotated, ``HoughResult.row``)."""
    finder = hough.HoughLaneFinder(config)

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        result = finder.process(rgb)
        return hough.annotate(rgb, result), result.row()

    return process


def hough_log_row(frame: int, time_s: float, result: hough.HoughResult) -> dict:
    """Return one row of the per-frame Hough video log: ``frame``, ``time_s`` and ``HoughResult.row``."""
    return {"frame": frame, "time_s": time_s, **result.row()}


def hough_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                config: hough.HoughConfig = hough.HoughConfig(),
                log_path: str | os.PathLike | None = None, progress: bool = True,
                threads: int | None = None, start_s: float | None = None,
                end_s: float | None = None, workers: int = 1, scheduler: str | None = None) -> VideoRun:
    """Return what the run did after tracking both lines through a video and writing it annotated.

    ``out_path`` is an H.264 video with the input's size and frame rate; the optional per-frame
    CSV at ``log_path`` holds ``hough_log_row``. ``found_frames`` counts frames with both lines
    (measured or held). ``start_s``, ``end_s`` run on part of the clip, as for
    ``process_video``. Outputs are written atomically by ``run_video``: an error or Ctrl-C
    leaves nothing behind, except a video that stops decoding half-way: its outputs keep the
    frames before the break, and ``PartialOutputError`` says so. ``workers``, ``scheduler``: in
    segments on Dask, as ``process_video``.
    """
    if Path(out_path).suffix.lower() not in io.VIDEO_SUFFIXES:
        raise InputError(f"{out_path}: the output video needs a video suffix "
                         f"({', '.join(io.VIDEO_SUFFIXES)}); e.g. out.mp4")
    make = functools.partial(hough_video_process, config)
    with cluster.dask_client(workers, scheduler) as client:
        if client is not None:
            # a warm-up its smoothing forgets a start in, to the last bit (most joints settle)
            return run_video_segments(in_path, out_path, make, client, log_path=log_path,
                                      progress=progress, desc=Path(in_path).name, threads=threads,
                                      start_s=start_s, end_s=end_s, warmup=hough.settle_frames(config))
    return run_video(in_path, out_path, make()[0], log_path=log_path, progress=progress,
                     desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)


def hough_video_process(config: hough.HoughConfig) -> tuple[FrameFn, list[str], FrameState]:
    """Return ``hough_video``'s ``process`` (a fresh ``HoughTracker``), its (empty) notes and its
    state (the tracker)."""
    tracker = [hough.HoughTracker(config)]

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        result = tracker[0].process(frame)
        return (hough.annotate(frame, result), hough_log_row(index, time_s, result),
                result.left_found and result.right_found)

    def put(state: object) -> None:
        tracker[0] = state

    return process, [], FrameState(lambda: tracker[0].state_key(), lambda: tracker[0], put)


# --------------------------------------------------------------------------- benchmark predictions

PREDICT_BENCHMARKS = ("tusimple", "culane")
TUSIMPLE_PREDICTIONS = "predictions.json"  # PRED_DIR/predictions.json: the TuSimple prediction file
TUSIMPLE_PARTS = "parts"                   # PRED_DIR/parts/<raw_file>.json: one JSON line per frame
PREDICT_SETTINGS = "predict.json"          # PRED_DIR/predict.json: what the predictions were made with
PREDICT_FORMAT = "lanelib-predict/1"


# pipelines predict_frame keeps in its cache: the last few sequences'
PIPELINES_KEPT = 4


@dataclass(frozen=True)
class FrameWork:
    """One labelled frame to predict: all a worker needs besides the sequence's config.

    Parameters
    ----------
    benchmark : "tusimple" or "culane".
    name : the frame as the labels name it (TuSimple ``raw_file``, CULane list entry).
    image : the image file.
    sequence : the camera's folder (``frame_sequence``); its frames share one autogeometry.
    rows_px : the rows the lanes are given at (TuSimple: the label's ``h_samples``; CULane:
        ``culane.SAMPLE_ROWS_PX``, bottom up).
    target : the frame's own prediction file (TuSimple: a part; CULane: its ``.lines.txt``).
    """

    benchmark: str
    name: str
    image: Path
    sequence: str
    rows_px: tuple[float, ...]
    target: Path


@dataclass(frozen=True)
class FrameOutcome:
    """What ``predict_frame`` did with one frame: lines written, time (ms), or the error."""

    name: str
    lines: int = 0
    run_time_ms: float = 0.0
    error: str = ""


@dataclass(frozen=True)
class GeometryFallback:
    """A sequence of a ``predict_benchmark`` run whose geometry estimate was not used: its frames
    keep the bird's-eye points of the run's config. ``reason`` says why (the frames give no
    consistent vanishing point, none could be read, or the confidence is too low)."""

    sequence: str
    reason: str

    def note(self, points_of: str) -> str:
        """Return the one-line note of this fallback; ``points_of`` names the config, e.g.
        ``"the tusimple preset"``.

        Examples
        --------
        >>> GeometryFallback("clips/0313-1", "no road").note("the tusimple preset")
        "clips/0313-1: road geometry not used (no road); its frames use the tusimple preset's bird's-eye points"
        """
        return (f"{self.sequence}: road geometry not used ({self.reason}); its frames use {points_of}'s "
                "bird's-eye points")


@dataclass(frozen=True)
class PredictRun:
    """What ``predict_benchmark`` did: frames listed, skipped (predicted before), predicted, failed.

    ``outcomes`` holds the frames run now, in list order; ``output`` is the prediction file
    (TuSimple) or folder (CULane) to pass to ``evaluate``; ``geometries`` the road geometry of each
    sequence whose estimate is used (``--auto-geometry``), ``fallbacks`` the sequences whose
    estimate was refused or failed (they keep the config's points), both in list order.
    """

    frames: int
    skipped: int
    outcomes: tuple[FrameOutcome, ...]
    output: Path
    seconds: float
    geometries: tuple[tuple[str, RoadGeometry], ...] = ()
    fallbacks: tuple[GeometryFallback, ...] = ()

    @property
    def failed(self) -> tuple[FrameOutcome, ...]:
        return tuple(o for o in self.outcomes if o.error)

    @property
    def without_lines(self) -> int:
        """Return how many frames run now found no line (an empty prediction was written)."""
        return sum(1 for o in self.outcomes if not o.error and o.lines == 0)


def frame_sequence(benchmark: str, name: str) -> str:
    """Return the sequence (one camera's folder) of a frame: TuSimple ``clips/0313-1`` of
    ``clips/0313-1/6040/20.jpg`` (the clip's parent), CULane ``driver_23_30frame/05151640_0419.MP4``
    of ``/driver_23_30frame/05151640_0419.MP4/00000.jpg`` (the image's folder)."""
    parts = PurePosixPath(name.lstrip("/")).parts[:-1]
    if benchmark == "tusimple" and len(parts) > 1:
        parts = parts[:-1]
    return "/".join(parts) or "."


def benchmark_work(benchmark: str, root: str | os.PathLike, out_dir: str | os.PathLike,
                   list_file: str | os.PathLike | None = None) -> list[FrameWork]:
    """Return the frames of a benchmark's dataset to predict, in list order.

    Parameters
    ----------
    benchmark : "tusimple" (labels: ``list_file``, a label file, or every ``label_data*.json`` of
        ``root``) or "culane" (``list_file``, default ``root/list/test.txt``).
    root : the dataset root the labels' image paths are relative to.
    out_dir : the prediction folder (``PRED_DIR``); each frame's target lies under it.

    Raises
    ------
    InputError
        If the root is missing, the labels or the list are bad, an image is missing (naming the
        entry and the file looked for), or ``out_dir`` is the dataset root.
    """
    if benchmark not in PREDICT_BENCHMARKS:
        raise InputError(f"{benchmark!r}: not a benchmark; choose one of {', '.join(PREDICT_BENCHMARKS)}")
    r, out = Path(root), Path(out_dir)
    if not r.is_dir():
        raise InputError(f"{r}: no such folder; pass the {benchmark} dataset root (the folder the "
                         "labels' image paths are relative to)")
    if out.resolve() == r.resolve():
        raise InputError(f"{out}: the prediction folder is the dataset root (predictions would lie "
                         "among the labels); choose another -o folder")
    if benchmark == "tusimple":
        labels = Path(list_file) if list_file is not None else r
        source = str(labels)
        named = [(rec.raw_file, tuple(rec.h_samples)) for rec in tusimple.read_labels(labels)]
    else:
        source = str(Path(list_file) if list_file is not None else r / "list" / "test.txt")
        named = [(entry, culane.SAMPLE_ROWS_PX) for entry in culane.read_list(source)]
    work = []
    for n, (name, rows) in enumerate(named, 1):
        image = r.joinpath(*PurePosixPath(name.lstrip("/")).parts)
        if not image.is_file():
            raise InputError(f"{source}: entry {n} ({name}) has no image: {image} is missing; pass the "
                             "dataset root the labels are relative to, or a list of the images you have")
        if benchmark == "tusimple":
            target = out.joinpath(TUSIMPLE_PARTS, *PurePosixPath(name.lstrip("/")).with_suffix(".json").parts)
        else:
            target = culane.lines_path(out, name)
        work.append(FrameWork(benchmark, name, image, frame_sequence(benchmark, name),
                              tuple(float(y) for y in rows), target))
    return work


def seen_lines(found: LinesResult, rows_px: Sequence[float], w: int,
               per_side: int | None = None) -> list[np.ndarray]:
    """Return the x (px) at ``rows_px`` of every line ``detect_lines`` saw, left to right.

    x is NaN on rows where the line is not seen or outside the image (``w`` px wide); a line
    with fewer than 2 points is left out. ``per_side``: at most that many lines on each side
    of the car (the nearest ones; CULane labels two a side), else all.
    """
    kept = list(found.lines)
    if per_side is not None:
        left = [line for line in kept if line.offset_m < 0][-per_side:] if per_side else []
        right = [line for line in kept if line.offset_m >= 0][:per_side]
        kept = left + right
    out = []
    for line in kept:
        xs = line.x_at_rows(rows_px)
        xs[~((xs >= 0) & (xs <= w - 1))] = np.nan
        if np.count_nonzero(np.isfinite(xs)) >= 2:
            out.append(xs)
    return out


def _prediction_text(work: FrameWork, lines: list[np.ndarray], run_time_ms: float) -> str:
    """Return the text of a frame's prediction file in its benchmark's format."""
    rows = np.asarray(work.rows_px, np.float64)
    if work.benchmark == "tusimple":
        lanes = tuple(tuple(tusimple.NO_POINT if not math.isfinite(x) else round(float(x), 2) for x in xs)
                      for xs in lines)
        record = tusimple.TuSimpleRecord(work.name, lanes, work.rows_px, round(run_time_ms, 1))
        return tusimple.record_line(record, work.target, prediction=True)
    pts = [np.column_stack([np.round(xs[np.isfinite(xs)], 2), rows[np.isfinite(xs)]]) for xs in lines]
    return culane.format_lines(pts)


def predict_frame(work: FrameWork, config: PipelineConfig, calibration: Calibration | None,
                  cache: dict) -> FrameOutcome:
    """Return the outcome of detecting the lane in one frame on its own and writing its prediction.

    The frame is read, ``LanePipeline.detect_lines`` runs on it (no prior: each labelled frame
    stands alone), every line seen is sampled at ``work.rows_px`` where it is seen (``seen_lines``;
    CULane: ``culane.LINES_PER_SIDE`` a side) and written to
    ``work.target`` atomically (a frame with no line found gets an empty prediction); stale
    temporaries of that target from a killed run are removed first. ``run_time_ms`` is the
    detection and sampling time. ``cache`` keeps one pipeline per (sequence, frame size) across
    calls (a worker's own dict), the last ``PIPELINES_KEPT`` of them (each holds its maps: a
    2,000-frame run of 200 sequences once kept them all and peaked at 1.3 GB). A lanelib error
    (unreadable image, a size the calibration does not fit) is the outcome's ``error``; a
    ``ConfigError`` is raised (it fails every frame).
    """
    try:
        rgb = io.read_image(work.image)
        key = (work.sequence, rgb.shape[1], rgb.shape[0])
        if key not in cache:
            while len(cache) >= PIPELINES_KEPT:  # the oldest goes: lists run sequence by sequence
                del cache[next(iter(cache))]
            cache[key] = LanePipeline(config, calibration, size=key[1:])
            cache[key].lines_view()  # per camera, like the pipeline's own maps: not in run_time
        pipe = cache[key]
        t0 = time.perf_counter()
        lines = seen_lines(pipe.detect_lines(rgb, ego=False), work.rows_px, w=rgb.shape[1],
                           per_side=culane.LINES_PER_SIDE if work.benchmark == "culane" else None)
        ms = (time.perf_counter() - t0) * 1000.0
        io.remove_stale_temp_files(work.target)
        io.write_text(work.target, _prediction_text(work, lines, ms), inputs=[work.image])
    except ConfigError:
        raise
    except LaneLibError as e:
        return FrameOutcome(work.name, error=naming_the_file(str(e), work.image))
    return FrameOutcome(work.name, len(lines), ms)


def predict_chunk(chunk: Sequence[FrameWork], configs: dict[str, PipelineConfig],
                  calibration: Calibration | None) -> list[FrameOutcome]:
    """Return the outcome of ``predict_frame`` for each frame of a chunk, in order (a Dask task).

    ``configs`` holds the config of each sequence of the chunk (its geometry estimated by the
    client); the pipelines are built once per chunk and sequence.
    """
    cache: dict = {}
    return [predict_frame(w, configs[w.sequence], calibration, cache) for w in chunk]


def _check_visible(outcomes: list[FrameOutcome], work: Sequence[FrameWork]) -> list[FrameOutcome]:
    """Return the outcomes, a frame a worker wrote where this process does not see it failed."""
    checked = []
    for o, w in zip(outcomes, work):
        if not o.error and not w.target.is_file():
            o = FrameOutcome(o.name, error=f"{w.target}: a Dask worker wrote this prediction but it is "
                                           "not here; --scheduler needs the dataset and PRED_DIR on a "
                                           "filesystem every worker sees at the same path")
        checked.append(o)
    return checked


def _settings(benchmark: str, root: Path, config: PipelineConfig, calibration_file: str | None,
              auto_geometry: GeometryOptions | None) -> dict:
    return {"format": PREDICT_FORMAT, "benchmark": benchmark, "dataset_root": str(root.resolve()),
            "calibration": calibration_file, "config": to_dict(config),
            "auto_geometry": to_dict(auto_geometry) if auto_geometry is not None else None}


def _check_settings(out: Path, settings: dict) -> bool:
    """Return whether ``out`` records these settings already; raise if it records others."""
    path = out / PREDICT_SETTINGS
    if not path.is_file():
        return False
    old = io.read_json(path, "prediction settings file")
    if old != settings:
        keys = sorted(k for k in set(old) | set(settings) if old.get(k) != settings.get(k))
        raise InputError(f"{out}: holds predictions made with other settings ({', '.join(keys)} "
                         f"differ; see {path}); pass another -o folder, or remove it to start again")
    return True


def _sequence_geometry(work: Sequence[FrameWork], calibration: Calibration | None,
                       options: GeometryOptions) -> RoadGeometry | GeometryFallback:
    """Return the geometry of one sequence, estimated from up to ``options.max_frames`` of its
    frames, evenly spread, or a ``GeometryFallback`` saying why it is not used: the estimate
    failed (``GeometryError``, or frames it cannot take) or its confidence is below
    ``autogeometry.LOW_CONFIDENCE`` without ``options.accept_low_confidence``. A value, not an
    exception, so that a Dask task returns it like a autogeometry. An image that cannot be read is
    left out here (``predict_frame`` reports it)."""
    step = max(1, math.ceil(len(work) / options.max_frames))
    frames = []
    for w in work[::step]:
        try:
            frames.append(io.read_image(w.image))
        except InputError:
            continue
    sequence = work[0].sequence
    if not frames:
        return GeometryFallback(sequence, "none of its images could be read")
    try:
        # one calibration serves every sequence's frames: no lens is estimated per sequence
        geo = options.estimate(frames, calibration, lens_from_road=False)
    except (GeometryError, InputError) as e:
        return GeometryFallback(sequence, str(e))
    if geo.low_confidence and not options.accept_low_confidence:
        return GeometryFallback(sequence, f"{_low_confidence(geo, len(frames))}; --accept-low-confidence "
                                          "uses it")
    return geo


def _assemble_tusimple(work: Sequence[FrameWork], out: Path, inputs: Sequence[Path]) -> Path:
    """Write ``PRED_DIR/predictions.json`` from the parts of the listed frames that have one."""
    records = []
    for w in work:
        if w.target.is_file():
            text = w.target.read_text(encoding="utf-8")
            records.append(tusimple.parse_record(text, str(w.target), prediction=True))
    path = out / TUSIMPLE_PREDICTIONS
    io.remove_stale_temp_files(path)
    return tusimple.write_predictions(path, records, inputs=inputs)


def _sequence_configs(work: Sequence[FrameWork], sequences: Sequence[str], config: PipelineConfig,
                      calibration: Calibration | None, options: GeometryOptions, client,
                      on_geometry: Callable[[str, RoadGeometry | GeometryFallback], None] | None
                      ) -> tuple[dict[str, PipelineConfig], list[tuple[str, RoadGeometry]], list[GeometryFallback]]:
    """Return the config of each of ``sequences`` (``config`` with its estimated geometry, or
    ``config`` itself where the estimate is not used), the geometries used and the fallbacks.

    The estimates run here, or on the Dask ``client``'s workers, one task per sequence.
    """
    groups = [[w for w in work if w.sequence == sequence] for sequence in sequences]
    if client is None:
        estimates = (_sequence_geometry(g, calibration, options) for g in groups)
    else:  # one task per sequence, all sent at once; results in order
        estimates = cluster.map_ordered(client, _sequence_geometry, groups, calibration=calibration,
                                        options=options)
    configs, geometries, fallbacks = {}, [], []
    for sequence, estimate in zip(sequences, estimates):
        if on_geometry is not None:
            on_geometry(sequence, estimate)
        if isinstance(estimate, GeometryFallback):
            fallbacks.append(estimate)
            configs[sequence] = config
        else:
            geometries.append((sequence, estimate))
            configs[sequence] = with_geometry(config, estimate)
    return configs, geometries, fallbacks


def predict_benchmark(benchmark: str, root: str | os.PathLike, out_dir: str | os.PathLike,
                      list_file: str | os.PathLike | None = None,
                      config: PipelineConfig | None = None, calibration: Calibration | None = None,
                      calibration_file: str | os.PathLike | None = None,
                      auto_geometry: GeometryOptions | None = None, progress: bool = True,
                      on_geometry: Callable[[str, RoadGeometry | GeometryFallback], None] | None = None,
                      workers: int = 1, scheduler: str | None = None) -> PredictRun:
    """Return what the run did after predicting every labelled frame of a benchmark dataset.

    Each frame is detected on its own (``predict_frame``: the labelled frames are seconds apart,
    so no tracking) and written in the benchmark's format under ``out_dir``: TuSimple as one part
    per frame in ``out_dir/parts/`` assembled at the end into ``out_dir/predictions.json`` (the
    listed frames with a part, in list order); CULane as one ``.lines.txt`` per image mirroring
    the list (``evaluate culane --pred out_dir``).

    Resuming: a frame whose prediction file exists is skipped, so a run that was stopped goes on
    where it was. Every file is written atomically (temporary file, then rename): a stop leaves
    whole per-frame files and never a half-written one, and the TuSimple file is only written
    once the frames are done (a killed process's temporaries are removed when their file is next
    written). ``out_dir/predict.json`` records the settings; a run with other settings (config,
    calibration, geometry options, dataset) refuses to add to that folder.

    Parameters
    ----------
    benchmark, root, list_file : the dataset (``benchmark_work``).
    config : as for ``LanePipeline``; None (the default): ``lanelib.config.benchmark_config``, the
        bundled preset of the benchmark's camera. Frames of another size than its
        ``perspective.size_px`` get its points scaled to their size (``LanePipeline``), which is
        right for resized copies of the same camera's frames; the thresholds' widths in px are
        not scaled (in a smaller frame they span more road).
    calibration : as for ``LanePipeline``; ``calibration_file`` names it in the settings record.
    auto_geometry : estimate the bird's-eye points and scale once per sequence (one camera's
        folder, ``frame_sequence``) from up to ``max_frames`` of its frames, and use them for that
        sequence's frames instead of ``config.perspective`` (only sequences with frames still to
        predict are estimated). Where the estimate fails or its confidence is too low
        (``_sequence_geometry``), the sequence keeps ``config.perspective`` and the run goes on:
        ``PredictRun.fallbacks`` says which and why.
    progress : show a tqdm bar.
    on_geometry : called with (sequence, geometry or ``GeometryFallback``) for each estimate, in
        list order, before any frame is predicted (the CLI prints them).
    workers, scheduler : where the frames are predicted (``cluster.dask_client``): 1 worker (the
        default) in this process; more on a Dask ``LocalCluster`` of that many processes; or the
        workers of the Dask scheduler at ``scheduler``. With Dask the frames go in chunks
        (``cluster.chunk_size``) to the workers, which read the images and write the predictions
        themselves (``predict_chunk``: with ``scheduler`` the dataset and ``out_dir`` must be on a
        filesystem the workers share, at the same path); the geometries too are estimated on the
        workers, one task per sequence, all before any frame; the outputs are the same as in one
        process (``run_time`` aside).

    Raises
    ------
    InputError
        For a bad dataset or list (``benchmark_work``) or a folder of other settings; nothing is
        written then.
    """
    out = Path(out_dir)
    config = benchmark_config(benchmark) if config is None else config
    work = benchmark_work(benchmark, root, out, list_file)
    settings = _settings(benchmark, Path(root), config,
                         None if calibration_file is None else str(calibration_file), auto_geometry)
    recorded = _check_settings(out, settings)
    t0 = time.perf_counter()
    todo = [w for w in work if not w.target.is_file()]
    # the cluster is reached before anything is written: a bad --scheduler leaves no trace
    with (cluster.dask_client(workers, scheduler) if todo else cluster.dask_client()) as client:
        sequences = list(dict.fromkeys(w.sequence for w in todo))
        configs, geometries, fallbacks = {sequence: config for sequence in sequences}, [], []
        if auto_geometry is not None:
            configs, geometries, fallbacks = _sequence_configs(work, sequences, config, calibration,
                                                               auto_geometry, client, on_geometry)
        if not recorded:
            path = out / PREDICT_SETTINGS
            io.remove_stale_temp_files(path)
            io.write_json(path, settings)
        outcomes, cache = [], {}
        with tqdm(total=len(todo), desc=f"predict {benchmark}", unit="frame", disable=not progress,
                  dynamic_ncols=True) as bar:
            if client is None:
                for w in todo:
                    outcomes.append(predict_frame(w, configs[w.sequence], calibration, cache))
                    bar.update(1)
            else:
                chunks = cluster.split(todo, cluster.chunk_size(len(todo), cluster.total_threads(client)))
                done = cluster.map_chunks(client, predict_chunk, chunks, bar, calibration=calibration,
                                          configs=configs)
                outcomes = _check_visible([o for chunk in done for o in chunk], todo)
    output = out
    if benchmark == "tusimple":
        output = _assemble_tusimple(work, out, tusimple.label_files(list_file if list_file is not None else root))
    return PredictRun(len(work), len(work) - len(todo), tuple(outcomes), output,
                      time.perf_counter() - t0, tuple(geometries), tuple(fallbacks))
